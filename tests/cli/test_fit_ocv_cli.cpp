// battsim fit-ocv run as a program: a fleet of real CMU Matrice 100 flights, each starting at
// its own state of charge, gives a table that explains flights it never saw better than the
// config's estimated curve; the written config reads back and replays; bad input fails clearly.
#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_util.h"

using clitest::q;
using clitest::run;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kData = BATTSIM_DATA_DIR;
const std::string kCmu =
    " --time-col time --time-unit s --voltage-col battery_voltage --current-col battery_current --current-unit A";

std::string flights(std::initializer_list<int> ids) {
    std::string s;
    for (int id : ids) s += " " + q(kData + "/cmu-m100/flights/" + std::to_string(id) + ".csv");
    return s;
}
}  // namespace

TEST_CASE("fit-ocv stitches a table from real fleet flights and it holds on held-out ones", "[cli][data]") {
    const std::string dir = clitest::temp_dir();
    const std::string out = dir + "/m100.json";
    const std::string cfg = kSource + "/configs/dji-tb47d-6s.json";
    // Twelve flights to fit (starts from 3.5 to 4.3 V per cell), four held out; the slow
    // polarisation's time constant is chosen by the fit.
    const auto j = clitest::run_json("fit-ocv" + flights({1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23}) + " --test" +
                                     flights({2, 4, 6, 8}) + " -c " + q(cfg) + kCmu + " -o " + q(out) + " --json --plot " +
                                     q(dir + "/m100.svg"));
    CHECK(clitest::read_file(dir + "/m100.svg").find("<svg") != std::string::npos);
    CHECK(j["schema"] == "battsim.ocv_stitch");
    CHECK(j["cells"] == 6);
    REQUIRE(j["flights"].size() == 16u);
    const auto& table = j["ocv_cell_voltage_v"]["fitted"];
    REQUIRE(table.size() == 21u);
    for (size_t k = 1; k < table.size(); ++k) CHECK(table[k].get<double>() > table[k - 1].get<double>());
    // The pack tops out near 4.3 V per cell (a high-voltage LiPo), which the config's estimated
    // curve (a 4.2 V pack's, scaled) puts at 4.24.
    CHECK(table[20].get<double>() > 4.27);
    const auto& rms = j["rms_v_per_cell"];
    INFO(rms.dump());
    CHECK(rms["fitted"].get<double>() < 0.6 * rms["config_curve"].get<double>());
    CHECK(rms["test_fitted"].get<double>() < 0.6 * rms["test_config_curve"].get<double>());
    CHECK(j["soc_span"][1].get<double>() == Approx(1.0).margin(1e-6));

    // The config carries the table and replays a flight.
    const auto written = nlohmann::json::parse(clitest::read_file(out));
    REQUIRE(written["joint"]["ocv_cell_voltage_v"].size() == 21u);
    CHECK(written["joint"]["ocv_cell_voltage_v"][20].get<double>() == Approx(table[20].get<double>()).margin(1e-4));
    const auto summary = clitest::run_json("replay" + flights({2}) + " -c " + q(out) + kCmu + " --estimator joint --json");
    CHECK(summary["flight"]["capacity_ah"]["final"].get<double>() > 0.0);
}

TEST_CASE("fit-ocv reads a fleet manifest and holds out every other log", "[cli][data]") {
    const std::string dir = clitest::temp_dir();
    // The fleet's own reading settings come from the manifest, not the command line.
    nlohmann::json m = {{"schema", "battsim.manifest"},
                        {"version", 1},
                        {"base_dir", kData + "/cmu-m100/flights"},
                        {"defaults",
                         {{"config", kSource + "/configs/dji-tb47d-6s.json"},
                          {"format", "csv"},
                          {"columns",
                           {{"time", "time"},
                            {"time_unit", "s"},
                            {"voltage", "battery_voltage"},
                            {"current", "battery_current"},
                            {"current_unit", "A"}}}}},
                        {"logs", nlohmann::json::array()}};
    for (int id = 1; id <= 8; ++id) m["logs"].push_back({{"path", std::to_string(id) + ".csv"}});
    clitest::write_file(dir + "/fleet.json", m.dump(2));
    // One slow time constant: the choice is exercised above; here the reading is the point.
    const auto j = clitest::run_json("fit-ocv -m " + q(dir + "/fleet.json") + " --test-every 2 --slow-time 60 --json");
    REQUIRE(j["flights"].size() == 8u);
    for (size_t k = 0; k < 8; ++k) CHECK(j["flights"][k]["test"].get<bool>() == (k % 2 == 1));
    // The same split given as files and --test with the columns on the command line: the same fit.
    const auto same = clitest::run_json("fit-ocv" + flights({1, 3, 5, 7}) + " --test" + flights({2, 4, 6, 8}) + " -c " +
                                        q(kSource + "/configs/dji-tb47d-6s.json") + kCmu + " --slow-time 60 --json");
    std::vector<double> a, b;
    for (const auto& f : j["flights"])
        if (!f["test"].get<bool>()) a.push_back(f["start_soc"]["fitted"].get<double>());
    for (const auto& f : j["flights"])
        if (f["test"].get<bool>()) a.push_back(f["start_soc"]["fitted"].get<double>());
    for (const auto& f : same["flights"]) b.push_back(f["start_soc"]["fitted"].get<double>());
    CHECK(a == b);
    CHECK(j["ocv_cell_voltage_v"]["fitted"] == same["ocv_cell_voltage_v"]["fitted"]);
    // A manifest naming a missing log fails as bad input.
    m["logs"].push_back({{"path", "no-such-flight.csv"}});
    clitest::write_file(dir + "/broken.json", m.dump(2));
    const auto broken = run("fit-ocv -m " + q(dir + "/broken.json"));
    CHECK(broken.exit_code == 3);
    CHECK(broken.err.find("no-such-flight.csv") != std::string::npos);
}

TEST_CASE("fit-ocv says where its table is extrapolation; logs on the ground are refused", "[cli][data]") {
    // The first rows of three dissertation flights. 1,500 rows (the ground before take-off)
    // never leave the top of the curve, yet the fit had moved the table 85 mV lower down and
    // come out with a negative resistance, exit 0: now refused. 2,000 rows fly a little: the
    // table is fitted and says where it is extrapolation.
    const std::string dir = clitest::temp_dir();
    const auto first_rows = [&](int rows) {
        std::string logs;
        for (const char* n : {"29", "30", "32"}) {
            const std::string path = dir + "/first" + std::to_string(rows) + "-" + n + ".csv";
            clitest::write_first_rows(kData + "/predictive-bms/flights/" + n + ".csv", rows, path);
            logs += " " + q(path);
        }
        return logs;
    };
    const clitest::Result ground = run("fit-ocv" + first_rows(1500) + " -c " + q(kSource + "/configs/sim-4s.json") + " --json");
    CHECK(ground.exit_code == 3);
    CHECK_THAT(ground.err, Catch::Contains("in flight, under 2 % of the config's 1.55 Ah"));
    const auto j = clitest::run_json("fit-ocv" + first_rows(2000) + " -c " + q(kSource + "/configs/sim-4s.json") + " --json");
    bool extrapolated = false;
    for (const auto& n : j["notes"])
        extrapolated = extrapolated || n.get<std::string>().find("at state-of-charge points no sample reached (") != std::string::npos;
    CHECK(extrapolated);
}

TEST_CASE("fit-ocv says when its config is for another pack than the flights'", "[cli]") {
    // 4S flights with a 6S config had stitched a table of 2.77 V per cell at full without a word;
    // then it said so in a note and wrote it (exit 0). The table is one no pack has (its empty
    // point 791 mV below the config's minimum voltage): refused, with the note that says why.
    const std::string dir = clitest::temp_dir();
    const clitest::Result six = run("fit-ocv " + q(kSource + "/logs/example-4s.csv") + " -c " +
                                    q(kSource + "/configs/generic-6s.json") + " -o " + q(dir + "/six.json"));
    CHECK(six.exit_code == 3);
    CHECK_THAT(six.err, Catch::Contains("example-4s.csv: the log has 4 cell voltages but the config 6 cells"));
    CHECK_THAT(six.err, Catch::Contains("example-4s.csv: the stitched OCV table is one no pack has, so it is not written"));
    CHECK_THAT(six.err, Catch::Contains("is the config this pack's"));
    CHECK(clitest::read_file(dir + "/six.json").empty());
    // One log both fitted and held out tests nothing: refused.
    const auto twice = run("fit-ocv " + q(kSource + "/logs/example-4s.csv") + " --test " + q(kSource + "/logs/example-4s.csv") +
                           " -c " + q(kSource + "/configs/sim-4s.json"));
    CHECK(twice.exit_code == 2);
    CHECK_THAT(twice.err, Catch::Contains("is both fitted and held out (--test)"));
    // Its own config: no such note.
    const auto own = clitest::run_json("fit-ocv " + q(kSource + "/logs/example-4s.csv") + " -c " +
                                       q(kSource + "/configs/sim-4s.json") + " --json");
    for (const auto& n : own["notes"]) CHECK(n.get<std::string>().find("does the config match") == std::string::npos);
    // One flight is said as one (it had read "the flights start within 0 % of charge of each other").
    bool one = false;
    for (const auto& n : own["notes"]) {
        CHECK(n.get<std::string>().find("of each other") == std::string::npos);
        one = one || n.get<std::string>().rfind("one flight: nothing stitches its slice", 0) == 0;
    }
    CHECK(one);
}

namespace {
// The significant figures of every floating-point number in `j`, at most.
int most_figures(const nlohmann::json& j) {
    int most = 0;
    if (j.is_structured()) {
        for (const auto& v : j) most = std::max(most, most_figures(v));
    } else if (j.is_number_float()) {
        std::string t = j.dump();
        t = t.substr(0, t.find_first_of("eE"));
        std::string digits;
        for (char c : t)
            if (c >= '0' && c <= '9') digits += c;
        digits.erase(0, digits.find_first_not_of('0'));
        digits.erase(digits.find_last_not_of('0') + 1);
        most = static_cast<int>(digits.size());
    }
    return most;
}
}  // namespace

TEST_CASE("fit-ocv's report is rounded as the other reports are", "[cli]") {
    // 0.009217188882135187 and the like: 17 figures where the other JSON outputs give six.
    const auto j = clitest::run_json("fit-ocv " + q(kSource + "/logs/example-4s.csv") + " -c " +
                                     q(kSource + "/configs/sim-4s.json") + " --json");
    CHECK(most_figures(j) <= 6);
    CHECK(j["schema"] == "battsim.ocv_stitch");
    CHECK(j["schema_version"] == 1);
    // Which release wrote it, as the summaries say (`battsim --version` prints "battsim X").
    CHECK("battsim " + j["battsim_version"].get<std::string>() + "\n" == run("--version").out);
    CHECK(j["ocv_cell_voltage_v"]["fitted"].size() == 21u);
}

TEST_CASE("fit-ocv reports bad input and bad options with their exit codes", "[cli]") {
    const std::string dir = clitest::temp_dir();
    const std::string cfg = q(kSource + "/configs/sim-4s.json");
    const auto missing = run("fit-ocv " + q(dir + "/nope.csv") + " -c " + cfg);
    CHECK(missing.exit_code == 3);
    CHECK(missing.err.find("nope.csv") != std::string::npos);
    clitest::write_file(dir + "/bad.csv", "time_s,voltage_v,current_a\n0,16.0,0.1\n0.1,sixteen,0.1\n");
    const auto bad = run("fit-ocv " + q(dir + "/bad.csv") + " -c " + cfg);
    CHECK(bad.exit_code == 3);
    CHECK(bad.err.find("bad.csv:3") != std::string::npos);
    clitest::write_file(dir + "/tiny.csv", "time_s,voltage_v,current_a\n0,16.0,0.1\n0.1,16.0,0.1\n");
    const auto tiny = run("fit-ocv " + q(dir + "/tiny.csv") + " -c " + cfg);
    CHECK(tiny.exit_code == 3);  // too little data: the input's fault
    CHECK(tiny.err.find("10 valid samples") != std::string::npos);
    const auto points = run("fit-ocv " + q(dir + "/tiny.csv") + " -c " + cfg + " --points 40");
    CHECK(points.exit_code == 2);
    const auto plot = run("fit-ocv " + q(dir + "/tiny.csv") + " -c " + cfg + " --plot " + q(dir + "/p.jpg"));
    CHECK(plot.exit_code == 2);  // refused before any work
    const auto nothing = run("fit-ocv -c " + cfg);
    CHECK(nothing.exit_code == 2);
    // Nothing is written when the fit fails.
    const auto none = run("fit-ocv " + q(dir + "/tiny.csv") + " -c " + cfg + " -o " + q(dir + "/out.json"));
    CHECK(none.exit_code == 3);
    CHECK(clitest::read_file(dir + "/out.json").empty());
}

TEST_CASE("fit-ocv: no held-out error without --test logs, and logs that never fly are refused", "[cli][data]") {
    const std::string dir = clitest::temp_dir();
    // Without --test there is no held-out error: it had read 0.0, a perfect fit.
    const auto j = clitest::run_json("fit-ocv" + flights({1, 3, 5}) + " -c " + q(kSource + "/configs/dji-tb47d-6s.json") + kCmu +
                                     " --json");
    CHECK(j["rms_v_per_cell"]["test_fitted"].is_null());
    CHECK(j["rms_v_per_cell"]["test_config_curve"].is_null());
    CHECK(j["rms_v_per_cell"]["fitted"].get<double>() > 0.0);
    // The bundled flight's first minute, on the ground: nothing to read a curve over. It had
    // exited 0 with a slow polarisation resistance of -1.4 ohm.
    clitest::write_first_rows(kSource + "/logs/example-4s.csv", 900, dir + "/ground.csv");
    const clitest::Result r = run("fit-ocv " + q(dir + "/ground.csv") + " -c " + q(kSource + "/configs/sim-4s.json") + " --json");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("in flight, under 2 % of the config's 1.55 Ah"));
    CHECK(clitest::is_error_object(r.out));  // no table: the reason, as JSON
}

TEST_CASE("fit-ocv refuses a table no pack has: a log whose clock jumps over discharges", "[cli][data]") {
    // The Panasonic 18650PF's HPPC log leaves out the discharges between its pulse sets (its
    // clock jumps over them): the charge counted spans 0.55-1.00 while the voltage falls to
    // empty. The table had read 0.93 V at SOC 0 and 1.21 V from 5 to 45 %, 2.4 V from the
    // config's curve where no sample reached, written with exit 0.
    const std::string dir = clitest::temp_dir();
    const clitest::Result r = run("fit-ocv " + q(kData + "/panasonic-18650pf/hppc_25c.csv") + " -c " +
                                  q(kSource + "/configs/fitted/panasonic-18650pf-25c.json") +
                                  " --negative-discharge -o " + q(dir + "/hppc.json") + " --report " + q(dir + "/r.json"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("hppc_25c.csv: the stitched OCV table is one no pack has, so it is not written"));
    CHECK_THAT(r.err, Catch::Contains("below the config's minimum voltage 2.500 V"));
    CHECK_THAT(r.err, Catch::Contains("which no sample reached, it lies up to"));
    CHECK_THAT(r.err, Catch::Contains("The log's clock jumps (13 gap(s) over 60 s)"));
    CHECK(clitest::read_file(dir + "/hppc.json").empty());
    CHECK(clitest::read_file(dir + "/r.json").empty());
}

TEST_CASE("fit-ocv keeps the fullest start full and the empty point at its prior on full discharges", "[cli][data]") {
    // Five constant-current discharges of one Samsung 30Q cell, each from full to 2.5 V. The
    // joint step had let four starts pass the fullest one (1.015-1.036), so the discharges
    // ended above SOC 0 and the table's empty point was bent to 2.225 V, below the config's
    // 2.5 V minimum and below every voltage measured.
    std::string logs;
    for (const char* rate : {"C10", "1C", "2C", "3C", "4C"}) logs += " " + q(kData + "/samsung-30q/Q30_S001_" + std::string(rate) + ".csv");
    const auto j = clitest::run_json("fit-ocv" + logs + " -c " + q(kSource + "/configs/fitted/samsung-30q-discharge.json") +
                                     " --negative-discharge --json");
    for (const auto& f : j["flights"]) {
        INFO(f["log"].get<std::string>());
        CHECK(f["start_soc"]["fitted"].get<double>() <= 1.0);
    }
    CHECK(j["soc_span"][1].get<double>() == Approx(1.0).margin(1e-9));
    const double empty_v = j["ocv_cell_voltage_v"]["fitted"][0].get<double>();
    CHECK(empty_v > 2.5);
    CHECK(empty_v < 2.7);
    // A make-config curve misses these discharges by half a volt, and the resistances fitted
    // on it soak that up (-0.671 ohm ohmic, -0.899 ohm slow): said, as the fitted ones are.
    const std::string dir = clitest::temp_dir();
    REQUIRE(run("make-config --cells 1 --capacity-mah 3000 --cutoff-v 2.5 -o " + q(dir + "/1s.json")).exit_code == 0);
    const auto m = clitest::run_json("fit-ocv" + logs + " -c " + q(dir + "/1s.json") + " --negative-discharge --json");
    CHECK(m["pack_resistance_ohm"]["config_curve"]["ohmic_median"].get<double>() < 0.0);
    bool said = false;
    for (const auto& n : m["notes"])
        said = said || n.get<std::string>().rfind("on the config's curve a fitted pack resistance is negative (ohmic -", 0) == 0;
    CHECK(said);
    // The data reach empty: there they, not the make-config curve's 3.33 V, place the table.
    CHECK(m["ocv_cell_voltage_v"]["fitted"][0].get<double>() == Approx(2.5).margin(0.05));
}
