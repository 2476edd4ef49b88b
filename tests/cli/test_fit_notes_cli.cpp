// The commands that fit along replayed logs (fit, residual, fit-ocv, calibrate) and discharge
// say what replay says of a misread log: a fit of a log read with the wrong sign, units or a
// jumping clock runs without an error, and its numbers alone had not shown it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "cli_util.h"

using clitest::q;
using clitest::run;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kCell = kSource + "/configs/fitted/samsung-30q-discharge.json";  // a 3 Ah 18650

struct Discharge {
    double sign = -1.0;          // the logged current's sign while discharging
    double current_scale = 1.0;  // 1000: a current in mA under an ampere header
    double jump_s = 0.0;         // the clock jumps this far halfway through
    double end_v = 3.25;         // the voltage at the end of the load
    std::string time_header = "time_s";
    double temperature_c = NAN;  // NaN: no temperature column
};

// A 1S constant-current discharge at 3 A, one row a second: 10 s at rest, then 600 s under
// load while the voltage falls from 4.05 V to `end_v`.
std::string discharge_csv(const Discharge& d) {
    std::ostringstream s;
    const bool temperature = !std::isnan(d.temperature_c);
    s << d.time_header << ",voltage_v,current_a" << (temperature ? ",temperature_c" : "") << "\n";
    for (int k = 0; k < 610; ++k) {
        const double t_s = k + (k >= 305 ? d.jump_s : 0.0);
        const bool loaded = k >= 10;
        const double v = loaded ? 4.05 - (4.05 - d.end_v) * (k - 10) / 600.0 : 4.15;
        const double a = loaded ? d.sign * 3.0 * d.current_scale : 0.0;
        char row[80];
        std::snprintf(row, sizeof row, "%.1f,%.4f,%.4f", t_s, v, a);
        s << row;
        if (temperature) s << "," << d.temperature_c;
        s << "\n";
    }
    return s.str();
}
}  // namespace

TEST_CASE("fit, residual and fit-ocv say a current of the other sign, as replay does", "[cli][fit]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/negative.csv";
    clitest::write_file(log, discharge_csv(Discharge{}));
    const std::string note = ": note: " + log + ": the current never reaches the take-off threshold";
    auto r = run("fit " + q(log) + " -c " + q(kCell) + " --initial zero --params none");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim fit" + note) && Catch::Contains("replay it with --negative-discharge"));
    r = run("residual " + q(log) + " -c " + q(kCell) + " --initial zero --max-effects 0");
    CHECK_THAT(r.err, Catch::Contains("battsim residual" + note));
    r = run("fit-ocv " + q(log) + " -c " + q(kCell) + " --json");
    CHECK_THAT(r.err, Catch::Contains("battsim fit-ocv" + note));
    // Read the right way round, nothing to say.
    r = run("fit " + q(log) + " -c " + q(kCell) + " --initial zero --params none --negative-discharge");
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, !Catch::Contains("note:"));
}

TEST_CASE("fit says why the samples were kept out: a current in mA read as amperes", "[cli][fit]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/ma.csv";
    Discharge d;
    d.current_scale = 1000.0;
    clitest::write_file(log, discharge_csv(d));
    // The 10 resting rows pass the sensor limits; the 600 loaded ones read 3000 A.
    const auto r = run("fit " + q(log) + " -c " + q(kCell) + " --initial zero --params none --negative-discharge");
    INFO(r.err);
    CHECK_THAT(r.err, Catch::Contains("battsim fit: note: " + log + ": the config's sensor limits kept out 600 of the 610 "
                                      "samples: 600 current_high (sensor.max_current_a); a current in mA read as amperes "
                                      "(give --current-unit mA)?"));
}

TEST_CASE("fit, residual, calibrate and discharge say a clock that jumps", "[cli][fit]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/jump.csv";
    Discharge d;
    d.jump_s = 3600.0;
    clitest::write_file(log, discharge_csv(d));
    // An hour at 1 C with the voltage where it was: read as a step of the clock, not a gap.
    const std::string jump = ": note: " + log + ": the log's clock steps 3601 s ahead at 304 s into the log";
    auto r = run("fit " + q(log) + " -c " + q(kCell) + " --initial zero --params none --negative-discharge");
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim fit" + jump));
    r = run("residual " + q(log) + " -c " + q(kCell) + " --initial zero --max-effects 0 --negative-discharge");
    CHECK_THAT(r.err, Catch::Contains("battsim residual" + jump));
    // discharge reads one log, and says its notes without the path, as replay does.
    r = run("discharge " + q(log) + " -c " + q(kCell) + " --negative-discharge --min-voltage 3.2 --ocv-points 0");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim discharge: note: the log's clock steps 3601 s ahead at 304 s into the log"));
    // calibrate: the bundled 4S flight with its clock jumping an hour after the landing.
    std::istringstream in(clitest::read_file(kSource + "/logs/example-4s.csv"));
    std::string line, jumped;
    for (int k = 0; std::getline(in, line); ++k) {
        const size_t comma = line.find(',');
        const long t_ms = std::stol(line.substr(0, comma)) + (k >= 3800 ? 3600000L : 0L);
        jumped += std::to_string(t_ms) + line.substr(comma) + "\n";
    }
    const std::string flight = dir + "/example-jump.csv";
    clitest::write_file(flight, jumped);
    r = run("calibrate " + q(flight) + " -c " + q(kSource + "/configs/sim-4s.json"));
    CHECK_THAT(r.err, Catch::Contains("battsim calibrate: note: " + flight + ": the log's clock jumps 36"));
}

TEST_CASE("replay and fit say a pack emptied on a thousandth of its charge: seconds under a time_ms header", "[cli][fit]") {
    // 1 ms apart, as a blackbox log is: the spacing cannot tell, the charge can (a 3 Ah cell
    // emptied in 0.61 s on 0.5 mAh).
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/seconds.csv";
    Discharge d;
    d.end_v = 2.5;
    d.time_header = "time_ms";
    clitest::write_file(log, discharge_csv(d));
    const std::string note = "the pack voltage fell from 4.15 to 2.503 V (the config's range: 4.2 to 2.5 V) on 0.5 mAh";
    auto r = run("replay " + q(log) + " -c " + q(kCell) + " --negative-discharge --json");
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim replay: note: " + note) && Catch::Contains("give --time-unit s"));
    r = run("fit " + q(log) + " -c " + q(kCell) + " --negative-discharge --initial zero --params none");
    CHECK_THAT(r.err, Catch::Contains("battsim fit: note: " + log + ": " + note));
    // Read in seconds, the same log says nothing of it.
    r = run("replay " + q(log) + " -c " + q(kCell) + " --negative-discharge --time-unit s --json");
    CHECK_THAT(r.err, !Catch::Contains("fell from"));
    // Only the units the columns were not read in are advised: with the current read in mA
    // too, both; in seconds, the current's alone; in seconds and amperes, neither.
    r = run("replay " + q(log) + " -c " + q(kCell) + " --negative-discharge --current-unit mA --json");
    CHECK_THAT(r.err, Catch::Contains("if the time column counts seconds, give --time-unit s; if the current column "
                                      "counts amperes, --current-unit A"));
    r = run("replay " + q(log) + " -c " + q(kCell) + " --negative-discharge --time-unit s --current-unit mA --json");
    CHECK_THAT(r.err, Catch::Contains("fell from") &&
                          Catch::Contains(": if the current column counts amperes, give --current-unit A\n") &&
                          !Catch::Contains("--time-unit s"));
    d.time_header = "time_s";
    d.current_scale = 1e-3;  // 3 mA under an ampere header: no unit explains it
    clitest::write_file(log, discharge_csv(d));
    r = run("replay " + q(log) + " -c " + q(kCell) + " --negative-discharge --json");
    CHECK_THAT(r.err, Catch::Contains("fell from") &&
                          Catch::Contains(": no coarser unit to read them in, as the time column \"time_s\" is read in "
                                          "seconds and the current in amperes: check that they are the log's time and "
                                          "current columns, and that the config is this pack's") &&
                          !Catch::Contains("--time-unit") && !Catch::Contains("--current-unit"));
}

TEST_CASE("a config with a temperature dependence is noted on a log without a temperature", "[cli][fit]") {
    // The Panasonic cell's config, fitted with its temperature: read without one it runs at
    // 25 degC (its -20 degC drive cycle: MAE 0.370 V against 0.038 V with the column).
    const std::string config = kSource + "/configs/fitted/panasonic-18650pf.json";
    const std::string dir = clitest::temp_dir();
    const std::string bare = dir + "/bare.csv", warm = dir + "/warm.csv", kelvin = dir + "/kelvin.csv";
    Discharge d;
    clitest::write_file(bare, discharge_csv(d));
    d.temperature_c = 25.0;
    clitest::write_file(warm, discharge_csv(d));
    d.temperature_c = 250.0;
    clitest::write_file(kelvin, discharge_csv(d));
    const std::string note = "the config's model depends on the temperature (battery.extensions.temperature) but the "
                             "log has no temperature: it runs at 25 degC throughout";
    auto r = run("replay " + q(bare) + " -c " + q(config) + " --negative-discharge --json");
    REQUIRE(r.exit_code == 0);
    const auto notes = nlohmann::json::parse(r.out).value("config_notes", nlohmann::json::array());
    CHECK(std::any_of(notes.begin(), notes.end(), [&](const nlohmann::json& n) { return n.get<std::string>().rfind(note, 0) == 0; }));
    r = run("fit " + q(bare) + " -c " + q(config) + " --negative-discharge --initial zero --params none");
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim fit: note: " + bare + ": " + note));
    r = run("fit " + q(warm) + " -c " + q(config) + " --negative-discharge --initial zero --params none");
    CHECK_THAT(r.err, !Catch::Contains("depends on the temperature") && !Catch::Contains("kelvin"));
    // Kelvin read as degC: every reading above 200.
    r = run("replay " + q(kelvin) + " -c " + q(config) + " --negative-discharge --json");
    CHECK_THAT(r.err, Catch::Contains("battsim replay: note: the temperature reads 250 to 250 degC, every reading above "
                                      "200: in kelvin?"));
    // Temperature terms fitted without a temperature move nothing (they had stayed at 0 with
    // no standard error, and the config been written): refused, exit 3.
    const std::string start = kSource + "/configs/fitted/panasonic-18650pf-25c.json";
    r = run("fit " + q(bare) + " -c " + q(start) + " --negative-discharge --initial zero --add temperature -o " +
            q(dir + "/out.json"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("battsim fit: " + bare + ": the log has no temperature, so the temperature terms"));
    CHECK_FALSE(std::filesystem::exists(dir + "/out.json"));
    // With a temperature they are fitted.
    r = run("fit " + q(warm) + " -c " + q(start) + " --negative-discharge --initial zero --add temperature --params temp_e0");
    CHECK(r.exit_code == 0);
}

TEST_CASE("too little data to fit is an input error (exit 3) with the command's own remedy", "[cli][fit]") {
    const std::string dir = clitest::temp_dir();
    // Two rows of the 1S discharge: fewer samples than the six base parameters.
    const std::string csv = discharge_csv(Discharge{});
    const std::string two = dir + "/two.csv";
    clitest::write_file(two, csv.substr(0, csv.find('\n', csv.find('\n', csv.find('\n') + 1) + 1) + 1));
    auto r = run("fit " + q(two) + " -c " + q(kCell) + " --negative-discharge --initial zero");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("battsim fit: " + two + ": 2 samples to fit 6 parameters: too few (a longer log, or "
                                      "fewer parameters with --params)"));
    // residual has no --params: its parameters are kept at the config's values with --fixed.
    r = run("residual " + q(two) + " -c " + q(kCell) + " --negative-discharge --initial zero");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("2 samples to fit 6 parameters: too few (a longer log, or more parameters kept at "
                                      "the config's values with --fixed)"));
    CHECK_THAT(r.err, !Catch::Contains("--params"));
    // --window flight on a bench discharge at 0.3 A (under the cell config's 1 A take-off):
    // what is missing is a flight, not --initial zero, which was given.
    const std::string slow = dir + "/slow.csv";
    std::string low = csv;
    for (size_t at = low.find(",-3.0000"); at != std::string::npos; at = low.find(",-3.0000", at)) low.replace(at, 8, ",-0.3000");
    clitest::write_file(slow, low);
    r = run("fit " + q(slow) + " -c " + q(kCell) + " --negative-discharge --initial zero --window flight");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("battsim fit: " + slow + ": no sample to fit: it has no flight for --window flight: "
                                      "no sample reached the flying current (monitor.min_flying_current_a, 1 A; the "
                                      "highest valid one is 0.3 A); give --window all"));
    CHECK_THAT(r.err, !Catch::Contains("--initial zero"));
    // fit-ocv: no log with 10 valid samples.
    r = run("fit-ocv " + q(two) + " -c " + q(kCell) + " --negative-discharge");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("no log to fit holds 10 valid samples"));
}

TEST_CASE("errors are prefixed once with the command", "[cli][fit]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/linear.csv";
    clitest::write_file(log, discharge_csv(Discharge{}));
    // Minimum above maximum: the library's message had carried its own "discharge: ".
    auto r = run("discharge " + q(log) + " --negative-discharge --min-voltage 3.5 --max-voltage 3.0");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("battsim discharge: need 0 < minimum voltage < maximum voltage"));
    // A straight line has no zones to read a start config off.
    r = run("discharge " + q(log) + " -c " + q(kCell) + " --negative-discharge --min-voltage 3.2 --config-out " +
            q(dir + "/start.json"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("battsim discharge: the zones were not found"));
    CHECK_THAT(r.err, !Catch::Contains("discharge: discharge:"));
    // Too few samples: "battsim fit: fit: 2 samples ..." had been said.
    const std::string csv = clitest::read_file(log);
    const std::string two = dir + "/two.csv";
    clitest::write_file(two, csv.substr(0, csv.find('\n', csv.find('\n', csv.find('\n') + 1) + 1) + 1));
    r = run("fit " + q(two) + " -c " + q(kCell) + " --negative-discharge --initial zero");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("battsim fit: " + two + ": 2 samples to fit") && !Catch::Contains("fit: fit:"));
}

TEST_CASE("discharge: a part of a discharge says so in its JSON; a config for another pack writes no config", "[cli][data]") {
    const std::string source = BATTSIM_SOURCE_DIR;
    // The bundled flight stops at 15.07 V, above the 13.3 V minimum: its capacity_mah is only
    // what flowed, which only standard error had said.
    const clitest::Result part = clitest::run("discharge " + clitest::q(source + "/logs/example-4s.csv") + " -c " +
                                              clitest::q(source + "/configs/sim-4s.json") + " --json");
    REQUIRE(part.exit_code == 0);
    const nlohmann::json p = nlohmann::json::parse(part.out);
    CHECK(p["complete"] == false);
    CHECK(p["zones"]["found"] == false);
    CHECK(p["ocv_table"].is_null());
    bool said = false;
    for (const auto& n : p["input"]["notes"]) said = said || n.get<std::string>().find("only what flowed until then") != std::string::npos;
    CHECK(said);
    // One Samsung cell with the built-in 4S config: noted, and no config written (it had
    // written one of 0.63-1.04 V per cell without a word).
    const std::string dir = clitest::temp_dir();
    const std::string cell = clitest::q(std::string(BATTSIM_DATA_DIR) + "/samsung-30q/Q30_S001_C10.csv");
    const clitest::Result four = clitest::run("discharge " + cell + " --min-voltage 2.5 --max-voltage 4.2 --negative-discharge --json"
                                              " --config-out " + clitest::q(dir + "/c.json"));
    CHECK(four.exit_code == 4);
    CHECK_THAT(four.err, Catch::Contains("1.035 V per cell for the config's 4 cells in series"));
    CHECK_FALSE(std::ifstream(dir + "/c.json").good());
    const nlohmann::json whole = clitest::run_json("discharge " + cell + " --min-voltage 2.5 --max-voltage 4.2 --negative-discharge --json");
    CHECK(whole["complete"] == true);
    CHECK(whole["zones"]["found"] == true);
    REQUIRE(whole["config_notes"].size() == 1);
}

TEST_CASE("fit says in its JSON how far the logs determine each parameter", "[cli][fit]") {
    // The bundled flight's first minute, on the ground: q had read 0.041 +/- 0.018 Ah with the
    // doubt said in the brief alone. Each label follows its rule from the value and standard
    // error printed beside it (which side of a third of the value q falls on moves with the
    // simulator's noise: 0.041 +/- 0.008 since the fifty-second session).
    const std::string source = BATTSIM_SOURCE_DIR;
    const std::string dir = clitest::temp_dir();
    clitest::write_first_rows(source + "/logs/example-4s.csv", 900, dir + "/ground.csv");
    const nlohmann::json j = clitest::run_json("fit " + q(dir + "/ground.csv") + " -c " + q(source + "/configs/sim-4s.json") + " --json");
    std::map<std::string, std::string> d;
    for (const auto& p : j["parameters"]) {
        const std::string name = p["name"].get<std::string>(), label = p["determined"].get<std::string>();
        d[name] = label;
        INFO(p.dump());
        if (label == "at_bound" || label == "signed") continue;
        if (p["sigma"].is_null()) {
            CHECK(label == "not_moved");
            continue;
        }
        const bool loose = p["sigma"].get<double>() > std::fabs(p["value"].get<double>()) / 3.0;
        CHECK(label == (loose ? "barely" : "determined"));
    }
    REQUIRE(d.count("q") == 1);
    CHECK(d.at("initial") == "signed");
    CHECK(d.at("kappa") == "at_bound");
    for (const auto& kv : d) {
        INFO(kv.first);
        CHECK((kv.second == "determined" || kv.second == "barely" || kv.second == "not_moved" || kv.second == "at_bound" ||
               kv.second == "signed"));
    }
}
