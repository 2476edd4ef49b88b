// battsim make-config from the outside: a config for one's own pack, from its rating or an
// autopilot log; and replay saying when the config is for another pack than the log's.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_util.h"

using nlohmann::json;
using clitest::q;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kData = BATTSIM_DATA_DIR;

bool any_contains(const json& list, const std::string& text) {
    if (!list.is_array()) return false;
    for (const json& s : list)
        if (s.get<std::string>().find(text) != std::string::npos) return true;
    return false;
}
}  // namespace

TEST_CASE("battsim make-config: from a rating, and what it refuses", "[cli][make_config]") {
    const std::string dir = clitest::temp_dir();
    const std::string out = dir + "/pack.json";
    const clitest::Result r = clitest::run("make-config --cells 4 --capacity-mah 1550 -o " + q(out));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const json made = json::parse(clitest::read_file(out));
    const json ref = json::parse(clitest::read_file(kSource + "/configs/sim-4s.json"));
    CHECK(made["joint"]["ocv_cell_voltage_v"] == ref["joint"]["ocv_cell_voltage_v"]);
    CHECK(made["battery"]["internal_resistance_ohm"] == ref["battery"]["internal_resistance_ohm"]);

    // The example replays alike through it and through configs/sim-4s.json (same numbers;
    // only the name and the estimator's source differ).
    const json a = clitest::run_json("replay " + q(kSource + "/logs/example-4s.csv") + " -c " + q(out) + " --json");
    const json b = clitest::run_json("replay " + q(kSource + "/logs/example-4s.csv") + " -c " +
                                     q(kSource + "/configs/sim-4s.json") + " --estimator joint --json");
    CHECK(a["flight"] == b["flight"]);
    CHECK(a["warnings"] == b["warnings"]);
    CHECK(a["estimator"] == "joint");

    const clitest::Result no_cells = clitest::run("make-config --capacity-mah 1550");
    CHECK(no_cells.exit_code == 2);
    CHECK(no_cells.err.find("give --cells") != std::string::npos);
    const clitest::Result no_capacity = clitest::run("make-config --cells 4");
    CHECK(no_capacity.exit_code == 2);
    CHECK(no_capacity.err.find("give --capacity-mah") != std::string::npos);
    const clitest::Result bad_cutoff = clitest::run("make-config --cells 4 --capacity-mah 1500 --cutoff-v 8");
    CHECK(bad_cutoff.exit_code == 2);
    CHECK(bad_cutoff.err.find("V per cell, found 2 V") != std::string::npos);
    // A Li-ion cell's cutoff (2.5 V) is noted: the table is a LiPo's; a LiPo pilot's 3.0 V is not.
    const clitest::Result li_ion = clitest::run("make-config --cells 1 --capacity-mah 2900 --cutoff-v 2.5 -o " + q(dir + "/li.json"));
    CHECK(li_ion.exit_code == 0);
    CHECK_THAT(li_ion.err, Catch::Contains("note: the cutoff, 2.500 V per cell, lies below the empty point of the "
                                           "config's OCV table (3.327 V per cell), a lithium-polymer pack's"));
    const clitest::Result low_lipo = clitest::run("make-config --cells 4 --capacity-mah 1500 --cutoff-v 12 -o " + q(dir + "/lp.json"));
    CHECK(low_lipo.exit_code == 0);
    CHECK(low_lipo.err.find("lies below the empty point") == std::string::npos);
    const clitest::Result missing = clitest::run("make-config --from-log " + q(dir + "/nothing.bin"));
    CHECK(missing.exit_code == 3);
    // A CSV log without cell columns whose voltage fits two cell counts says what it lacks.
    const std::string csv = dir + "/ambiguous.csv";
    clitest::write_file(csv, "time_s,voltage_v,current_a\n0,21.9,0.2\n1,21.9,0.2\n2,21.8,12\n");
    const clitest::Result ambiguous = clitest::run("make-config --from-log " + q(csv) + " --capacity-mah 2200");
    CHECK(ambiguous.exit_code == 2);
    CHECK(ambiguous.err.find("give --cells (the log does not say)") != std::string::npos);
}

TEST_CASE("battsim make-config reads an ArduPilot log's pack, and replay notes the mismatch", "[cli][make_config][data]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = kData + "/ardupilot/robert_lefebvre_octo_PM.log";

    // With the default config (the dissertation's 1.55 Ah pack) replay says so, and names the cure.
    const json before = clitest::run_json("replay " + q(log) + " --json");
    CHECK(before["input"]["autopilot_battery"]["capacity_ah"].get<double>() == Approx(1.76));
    CHECK(before["input"]["autopilot_battery"]["cutoff_voltage_v"].get<double>() == Approx(10.5));
    CHECK(any_contains(before["config_notes"], "set for a 1.76 Ah pack (the log's BATT_CAPACITY 1760 mAh)"));
    CHECK(any_contains(before["config_notes"], "make-config --from-log"));

    const std::string cfg = dir + "/octo.json";
    const clitest::Result made = clitest::run("make-config --from-log " + q(log) + " -o " + q(cfg));
    INFO(made.err);
    REQUIRE(made.exit_code == 0);
    CHECK(made.err.find("4 cells from the pack resting at 14.99 V") != std::string::npos);
    const json c = json::parse(clitest::read_file(cfg));
    CHECK(c["battery"]["cells_in_series"] == 4);
    CHECK(c["battery"]["capacity_ah"].get<double>() == Approx(1.76));
    CHECK(c["monitor"]["min_flight_voltage_v"].get<double>() == Approx(10.5));
    CHECK(c["description"].get<std::string>().find("BATT_CAPACITY 1760") != std::string::npos);
    // Its LOW_VOLT, 10.5 V, is ArduCopter 3's default, a 3S pack's: 2.62 V per cell on this 4S
    // pack, which the remaining time runs to. Said, with the count it fits; not said once the
    // pilot gives a cutoff (nor the failsafe's note, which had said "it is the cutoff all the
    // same" beside the --cutoff-v that replaced it).
    CHECK_THAT(made.err, Catch::Contains("note: the log's LOW_VOLT 10.5 V is 2.62 V per cell on 4 cells, below where "
                                         "a LiPo is flown"));
    CHECK_THAT(made.err, Catch::Contains("it is 3.50 V per cell on 3 cells: set for another pack?"));
    const clitest::Result given = clitest::run("make-config --from-log " + q(log) + " --cutoff-v 13.3 -o " + q(dir + "/given.json"));
    INFO(given.err);
    REQUIRE(given.exit_code == 0);
    CHECK(given.err.find("LOW_VOLT") == std::string::npos);
    CHECK(json::parse(clitest::read_file(dir + "/given.json"))["monitor"]["min_flight_voltage_v"].get<double>() == Approx(13.3));

    // The capacity now matches. The reference model still reads the pack at 3.75 V per cell as
    // nearly empty (the Tremblay curve is no rest curve), so its count passes the capacity in
    // flight, and that is said: the model's voltage past it is not a battery's.
    const json after = clitest::run_json("replay " + q(log) + " -c " + q(cfg) + " --json");
    REQUIRE(after["config_notes"].size() == 1);
    CHECK_THAT(after["config_notes"][0].get<std::string>(),
               Catch::StartsWith("the charge counted since full passed the config's capacity (1.76 Ah)"));
    CHECK(after["config_notes"][0].get<std::string>().find("make-config") == std::string::npos);

    // A 3S pack: nothing in the log says so but how high it rests (4.03 V as 3S, 3.03 V as 4S at its first rest).
    const std::string under = kData + "/ardupilot/underpowered.log";
    const json under_before = clitest::run_json("replay " + q(under) + " --json");
    CHECK(any_contains(under_before["config_notes"], "4.03 V per cell as 3 cells, 3.03 V as the config's 4"));
    const std::string cfg3 = dir + "/under.json";
    REQUIRE(clitest::run("make-config --from-log " + q(under) + " -o " + q(cfg3)).exit_code == 0);
    const json c3 = json::parse(clitest::read_file(cfg3));
    CHECK(c3["battery"]["cells_in_series"] == 3);
    CHECK(c3["battery"]["capacity_ah"].get<double>() == Approx(4.0));
    CHECK(c3["monitor"]["min_flight_voltage_v"].get<double>() == Approx(9.4));
    const json under_made = clitest::run_json("replay " + q(under) + " -c " + q(cfg3) + " --estimator joint --json");
    CHECK_FALSE(under_made.contains("config_notes"));
    // Its CURR rows come once a second: the joint estimator never measures the pack's R0, and
    // says so (the sag at the take-off, 1.33 V for 19.3 A, is ten times the config's R0).
    CHECK(any_contains(under_made["input"]["notes"], "the samples are 1 s apart (median): the joint estimator's "
                                                      "resistance pairs samples at most 0.59 s apart"));
    // Nothing measured, nothing averaged: the config's R0 had been reported as the mean.
    CHECK(under_made["flight"]["resistance_ohm"]["mean"].is_null());
    CHECK(under_made["flight"]["resistance_ohm"]["final"].is_null());
}

TEST_CASE("battsim make-config counts a Matrice 100's cells from where it takes off", "[cli][make_config][data]") {
    // 24.22 V at rest rests as 6S (4.04 V per cell) and 7S (3.46 V); only 6S is a charge to
    // take off with. It had been a tie: "give --cells".
    const std::string dir = clitest::temp_dir();
    const std::string cfg = dir + "/m100.json";
    const clitest::Result made = clitest::run("make-config --from-log " + q(kData + "/cmu-m100/flights/1.csv") +
                                              " --capacity-mah 4500 -o " + q(cfg));
    INFO(made.err);
    REQUIRE(made.exit_code == 0);
    CHECK_THAT(made.err, Catch::Contains("6 cells from the pack resting at 24.22 V (4.04 V per cell)"));
    CHECK(json::parse(clitest::read_file(cfg))["battery"]["cells_in_series"] == 6);

    // One glitched row (line 500, 21.94 V read as 2.2 V) is a sensor fault below the config's
    // 2.0 V per cell, and the estimates stay the clean log's (with the core's 1.0 V floor the
    // row went in: the capacity at the landing read 6.60 Ah against 4.60 Ah).
    std::string text = clitest::read_file(kData + "/cmu-m100/flights/1.csv");
    size_t line = 0;
    for (int n = 1; n < 500; ++n) line = text.find('\n', line) + 1;
    size_t field = line;
    for (int n = 1; n < 4; ++n) field = text.find(',', field) + 1;  // battery_voltage is the 4th column
    text.replace(field, text.find(',', field) - field, "2.2");
    const std::string glitched = dir + "/1-glitched.csv";
    clitest::write_file(glitched, text);
    const std::string run = " -c " + q(cfg) + " --estimator joint --json";
    const json clean = clitest::run_json("replay " + q(kData + "/cmu-m100/flights/1.csv") + run);
    const json glitch = clitest::run_json("replay " + q(glitched) + run);
    CHECK(glitch["samples"]["rejected"]["pack_voltage_low"] == 1);
    CHECK(glitch["flight"]["capacity_ah"]["final"].get<double>() ==
          Approx(clean["flight"]["capacity_ah"]["final"].get<double>()).epsilon(0.01));
    CHECK(glitch["flight"]["resistance_ohm"]["final"].get<double>() ==
          Approx(clean["flight"]["resistance_ohm"]["final"].get<double>()).epsilon(0.01));
}

TEST_CASE("battsim make-config --board: a calibrated monitor's settings carried to a new pack's config", "[cli][make_config]") {
    const std::string dir = clitest::temp_dir();
    json board = json::parse(clitest::read_file(kSource + "/configs/sim-4s.json"));
    board["sensor"]["shunt_offset_ma"] = -20.0;
    board["battery"]["extensions"]["current_sensor"] = {{"gain", 1.02}};
    clitest::write_file(dir + "/board.json", board.dump());
    const std::string out = dir + "/pack.json";
    const clitest::Result r =
        clitest::run("make-config --cells 6 --capacity-mah 5000 --board " + q(dir + "/board.json") + " -o " + q(out));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(r.err.find("from the board's config " + dir + "/board.json: sensor.shunt_offset_ma, "
                     "battery.extensions.current_sensor\n") != std::string::npos);
    // sim-4s.json carries the dissertation logger's lead-cell calibration, measured on 4S packs:
    // not taken to a 6S pack (the share depends on the cell count), and said.
    CHECK_THAT(r.err, Catch::Contains("note: not taken from " + dir + "/board.json: joint.first_cell_lead_excess, "
                                      "joint.last_cell_lead_excess (measured on 4-cell packs"));
    const json made = json::parse(clitest::read_file(out));
    CHECK_FALSE(made["joint"].contains("last_cell_lead_excess"));
    CHECK(made["sensor"]["shunt_offset_ma"] == -20.0);
    CHECK(made["battery"]["extensions"]["current_sensor"]["gain"] == 1.02);
    CHECK(made["battery"]["cells_in_series"] == 6);
    CHECK(made["description"].get<std::string>().find("from " + dir + "/board.json.") != std::string::npos);

    const clitest::Result same = clitest::run("make-config --cells 6 --capacity-mah 5000 --board " +
                                              q(kSource + "/configs/reference-modified.json"));
    CHECK(same.exit_code == 0);
    CHECK(same.err.find("has the reference logger's board settings; nothing to take") != std::string::npos);
    // A board config that is no config: exit 4 with its position, nothing written.
    clitest::write_file(dir + "/bad.json", "{\"schema\": \"battsim.config\", \"sensor\": {\"shunt_ofset_ma\": 1}}");
    const clitest::Result bad = clitest::run("make-config --cells 6 --capacity-mah 5000 --board " + q(dir + "/bad.json") +
                                             " -o " + q(dir + "/never.json"));
    CHECK(bad.exit_code == 4);
    CHECK(bad.err.find("bad.json:1:") != std::string::npos);
    CHECK(bad.err.find("$.sensor.shunt_ofset_ma: unknown key") != std::string::npos);
    CHECK_FALSE(std::ifstream(dir + "/never.json").good());
}


TEST_CASE("battsim make-config: a large pack's polarisation in its own ohms, its voltage and its cell count", "[cli][make_config]") {
    const std::string dir = clitest::temp_dir();
    // 8S 22 Ah: R = 5 mOhm per cell x 8 / (22 / 1.55) = 2.818 mOhm, written 0.00282 Ohm; the
    // filters' polarisation prior (set for the reference pack's 0.02 Ohm) scales by 0.141,
    // its spread and drift by the square root, 0.3755.
    const clitest::Result big = clitest::run("make-config --cells 8 --capacity-mah 22000 -o " + q(dir + "/8s.json"));
    INFO(big.err);
    REQUIRE(big.exit_code == 0);
    CHECK(big.err.empty());  // 8 x 4.2 = 33.6 V: within the reference board's 36 V
    const json made = json::parse(clitest::read_file(dir + "/8s.json"));
    CHECK(made["battery"]["internal_resistance_ohm"].get<double>() == Approx(0.00282));
    const json& joint = made["joint"];
    CHECK(joint["polarisation_initial_ohm"].get<double>() == Approx(0.0053 * 0.141).epsilon(1e-4));
    CHECK(joint["polarisation_sigma0_ohm"].get<double>() == Approx(0.022 * 0.3755).epsilon(1e-3));
    CHECK(joint["polarisation_process_ohm_per_sqrt_s"].get<double>() == Approx(2.6e-4 * 0.3755).epsilon(1e-3));
    for (const char* filter : {"health_filter", "verdict_filter"}) {
        CHECK(joint[filter]["polarisation_initial_ohm"].get<double>() == Approx(0.0045 * 0.141).epsilon(1e-4));
        CHECK(joint[filter]["polarisation_sigma0_ohm"].get<double>() == Approx(0.013 * 0.3755).epsilon(1e-3));
        CHECK(joint[filter]["polarisation_process_ohm_per_sqrt_s"].get<double>() == Approx(1.4e-4 * 0.3755).epsilon(1e-3));
    }
    // The reference rating keeps the core's values (nothing written).
    const clitest::Result ref = clitest::run("make-config --cells 4 --capacity-mah 1550 -o " + q(dir + "/4s.json"));
    REQUIRE(ref.exit_code == 0);
    CHECK_FALSE(json::parse(clitest::read_file(dir + "/4s.json"))["joint"].contains("polarisation_initial_ohm"));

    // 12S reaches 50.4 V: beyond the reference board's INA226, said when the config is made.
    const clitest::Result twelve = clitest::run("make-config --cells 12 --capacity-mah 22000 -o " + q(dir + "/12s.json"));
    CHECK(twelve.exit_code == 0);
    CHECK_THAT(twelve.err, Catch::Contains("the pack reaches 50.40 V") && Catch::Contains("36 V bus input range"));

    // A log with 14 cell columns is a 14S pack: refused, not written as 12S from its first twelve.
    std::string header = "time_s,voltage_v,current_a";
    std::string row0 = "0,58.8,0.2", row1 = "1,58.7,20";
    for (int c = 1; c <= 14; ++c) {
        header += ",cell" + std::to_string(c) + "_v";
        row0 += ",4.2";
        row1 += ",4.19";
    }
    clitest::write_file(dir + "/14s.csv", header + "\n" + row0 + "\n" + row1 + "\n");
    const clitest::Result fourteen = clitest::run("make-config --from-log " + q(dir + "/14s.csv") + " --capacity-mah 16000 -o " +
                                                  q(dir + "/14s.json"));
    CHECK(fourteen.exit_code == 2);
    CHECK_THAT(fourteen.err, Catch::Contains("the log's pack has 14 cells in series; battsim handles at most 12"));
    CHECK_FALSE(std::filesystem::exists(dir + "/14s.json"));
}

TEST_CASE("battsim make-config --chemistry li-ion: a Li-ion cell read with its own curve", "[cli][make_config][data]") {
    // The Samsung 30Q's 3C discharge drew 2.925 Ah to 2.5 V (data README). With the LiPo curve
    // the joint estimator read 2.29 Ah and warned of a short flight; with the Li-ion curve
    // (read off the same cell's C/10 discharge) 3.03 Ah and no warning. scripts/li-ion-check.py
    // has the other rates and the 6S2P pack.
    const std::string dir = clitest::temp_dir();
    const std::string log = kData + "/samsung-30q/Q30_S001_3C.csv";
    for (const char* chemistry : {"lipo", "li-ion"}) {
        const std::string cfg = dir + "/" + chemistry + ".json";
        const clitest::Result made = clitest::run("make-config --cells 1 --capacity-mah 3000 --cutoff-v 2.5 --chemistry " +
                                                  std::string(chemistry) + " -o " + q(cfg));
        INFO(made.err);
        REQUIRE(made.exit_code == 0);
        // The LiPo config is told it may be a Li-ion pack's, and how to say so.
        CHECK((made.err.find("give --chemistry li-ion") != std::string::npos) == (std::string(chemistry) == "lipo"));
        const json s = clitest::run_json("replay " + q(log) + " -c " + q(cfg) + " --negative-discharge --estimator joint --json");
        const double capacity = s["flight"]["capacity_ah"]["final"].get<double>();
        bool short_warned = false;
        for (const json& w : s["warnings"]) short_warned = short_warned || w["name"] == "short_flight";
        if (std::string(chemistry) == "li-ion") {
            CHECK(capacity == Approx(2.925).epsilon(0.05));
            CHECK_FALSE(short_warned);
        } else {
            CHECK(capacity < 0.85 * 2.925);
            CHECK(short_warned);
        }
    }
    CHECK(clitest::run("make-config --cells 1 --capacity-mah 3000 --chemistry nimh").exit_code == 2);
}
