// make-config's library: a config scaled from the reference pack, what a log's autopilot
// parameters say about its pack, and the notes replay gives when a config does not match.
#include <algorithm>
#include <catch2/catch.hpp>

#include "host/config_json.h"
#include "host/pack_config.h"
#include "test_files.h"

using namespace battsim::host;
using nlohmann::json;

namespace {
SourceInfo with_parameters(std::vector<std::pair<std::string, double>> p) {
    SourceInfo info;
    info.parameters = std::move(p);
    return info;
}
}  // namespace

TEST_CASE("make-config: the reference rating gives the committed configs' numbers", "[pack_config]") {
    // 4S 1.55 Ah is configs/sim-4s.json itself (OCV table included); 3S is generic-3s.json
    // (its table was read off the 3S suite's own discharge, so it differs in the 4th decimal).
    for (int cells : {3, 4}) {
        PackRating r;
        r.cells = cells;
        r.capacity_ah = 1.55;
        const json made = pack_config_json(r);
        const json ref = json::parse(testsupport::read_file(std::string(BATTSIM_SOURCE_DIR) +
                                                            (cells == 4 ? "/configs/sim-4s.json" : "/configs/generic-3s.json")));
        INFO(cells << "S");
        for (const char* section : {"battery", "monitor"})
            for (auto it = ref[section].begin(); it != ref[section].end(); ++it) {
                INFO(section << "." << it.key());
                CHECK(made[section][it.key()].get<double>() == Approx(it.value().get<double>()).epsilon(1e-9));
            }
        CHECK(made["sensor"]["max_pack_voltage_v"].get<double>() == Approx(5.25 * cells));
        CHECK(made["sensor"]["min_pack_voltage_v"].get<double>() == Approx(2.0 * cells));  // not the core's 1.0 V
        CHECK(made["joint"]["cutoff_delay_s"].get<double>() == 5.0);
        if (cells == 4) CHECK(made["joint"]["ocv_cell_voltage_v"] == ref["joint"]["ocv_cell_voltage_v"]);
        CHECK(made["estimator"] == "joint");
        CHECK(made["name"] == (cells == 4 ? "pack-4s-1550" : "pack-3s-1550"));
    }
}

TEST_CASE("make-config: capacity scales the charges, the curve's current and the resistance", "[pack_config]") {
    PackRating r;
    r.cells = 6;
    r.capacity_ah = 5.2;  // k = 5.2 / 1.55 = 3.3548
    const json j = pack_config_json(r);
    const json& b = j["battery"];
    CHECK(b["capacity_ah"].get<double>() == Approx(5.2));
    CHECK(b["nominal_zone_capacity_ah"].get<double>() == Approx(1.5 * 5.2 / 1.55).margin(1e-4));  // 5.0323
    CHECK(b["exponential_capacity_ah"].get<double>() == Approx(0.3 * 5.2 / 1.55).margin(1e-4));   // 1.0065
    CHECK(b["curve_current_a"].get<double>() == Approx(23.484).margin(1e-3));                      // 7 A at the same C-rate
    CHECK(b["internal_resistance_ohm"].get<double>() == Approx(0.00894).margin(1e-9));            // 6 × 5 mΩ / 3.3548
    CHECK(b["full_voltage_v"].get<double>() == Approx(25.2));
    CHECK(j["monitor"]["min_flight_voltage_v"].get<double>() == Approx(19.95));
    // A glitched sample below 2.0 V per cell is kept out; one at 2.2 V had passed the 1.0 V default.
    CHECK(j["sensor"]["min_pack_voltage_v"].get<double>() == Approx(12.0));
    CHECK(j["monitor"]["remembered_average_power_w"].get<double>() == Approx(1590.2).margin(0.05));  // 79 W × 6 × k
    // Given values win; the description says where they came from.
    r.resistance_ohm = 0.012;
    r.cutoff_voltage_v = 21.0;
    r.cutoff_delay_s = 10.0;
    r.sources = {"capacity from the log's BATT_CAPACITY 5200 mAh"};
    const json g = pack_config_json(r);
    CHECK(g["battery"]["internal_resistance_ohm"].get<double>() == 0.012);
    CHECK(g["monitor"]["min_flight_voltage_v"].get<double>() == Approx(21.0));
    CHECK(g["joint"]["cutoff_delay_s"].get<double>() == 10.0);
    CHECK(g["description"].get<std::string>().find("BATT_CAPACITY 5200 mAh") != std::string::npos);
    // And the result is a config like any other.
    const LoadedConfig c = config_from_json(g, "test");
    CHECK(c.monitor.cells_in_series == 6);
    CHECK(c.monitor.sensor.min_pack_voltage_v == Approx(12.0f));
    CHECK(c.monitor.joint.ocv.points == 21);
}

TEST_CASE("make-config: a small pack's current thresholds shrink with it, not below its ground electronics", "[pack_config]") {
    PackRating r;
    r.cells = 1;
    r.capacity_ah = 0.3;  // s = 0.3 / 1.55 = 0.19355
    const json w = pack_config_json(r);
    // Take-off bar: max(1 A × s, 3 W / 3.7 V) = max(0.194, 0.811); the ground's bar
    // max(3 A × s, 1.25 × 0.811) = max(0.581, 1.01375).
    CHECK(w["monitor"]["min_flying_current_a"].get<double>() == Approx(0.811));
    CHECK(w["monitor"]["max_resting_current_a"].get<double>() == Approx(0.811));
    CHECK(w["joint"]["rest_capacity_max_current_a"].get<double>() == Approx(0.811));
    CHECK(w["joint"]["offset_learn_max_current_a"].get<double>() == Approx(1.014));
    CHECK(w["joint"]["resistance_min_step_a"].get<double>() == Approx(0.097));            // 0.5 A × s
    CHECK(w["joint"]["resistance_min_excitation_a2"].get<double>() == Approx(14.98));     // 400 A² × s²
    CHECK(w["joint"]["cell_resistance_min_excitation_a2"].get<double>() == Approx(749.22));  // 20000 A² × s²
    CHECK(w["joint"]["cell_min_charge_ah"].get<double>() == Approx(0.019));               // 0.1 Ah × s
    r.cells = 3;
    r.capacity_ah = 0.45;  // s = 0.29032; 3 W / 11.1 V = 0.270 is below 1 A × s
    const json t = pack_config_json(r);
    CHECK(t["monitor"]["min_flying_current_a"].get<double>() == Approx(0.29));
    CHECK(t["joint"]["offset_learn_max_current_a"].get<double>() == Approx(0.871));
    CHECK(t["joint"]["cell_step_min_a"].get<double>() == Approx(1.161));                  // 4 A × s
    // The keys are read back into the core's config.
    const LoadedConfig c = config_from_json(t, "test");
    CHECK(c.monitor.joint.offset_learn_max_current_a == Approx(0.871f));
    CHECK(c.monitor.cell_analysis.min_excitation_a2 == Approx(1685.74f).margin(0.01f));
    // From the reference's size up, the core's own bars (the Matrice 100's 4.5 Ah fleet was measured with them).
    r.capacity_ah = 1.55;
    const json big = pack_config_json(r);
    CHECK(big["monitor"]["min_flying_current_a"].get<double>() == 1.0);
    CHECK_FALSE(big["joint"].contains("offset_learn_max_current_a"));
    CHECK_FALSE(big["joint"].contains("resistance_min_excitation_a2"));
}

TEST_CASE("make-config: below 4S the filters' voltage sigma is per cell", "[pack_config]") {
    PackRating r;
    r.cells = 1;
    r.capacity_ah = 2.0;  // not a small pack: the σ follows the cells, not the capacity
    json j = pack_config_json(r);
    CHECK(j["joint"]["voltage_sigma_v"].get<double>() == Approx(0.0035));  // 0.014 V × 1/4
    CHECK(j["joint"]["health_filter"]["voltage_sigma_v"].get<double>() == Approx(0.01));   // 0.04 V × 1/4
    CHECK(j["joint"]["verdict_filter"]["voltage_sigma_v"].get<double>() == Approx(0.01));
    r.cells = 3;
    const LoadedConfig c = config_from_json(pack_config_json(r), "test");
    CHECK(c.monitor.joint.ekf.voltage_sigma_v == Approx(0.0105f));
    CHECK(c.monitor.joint.health.ekf.voltage_sigma_v == Approx(0.03f));
    CHECK(c.monitor.joint.verdict.ekf.voltage_sigma_v == Approx(0.03f));
    // 4S and up keep the core's own.
    for (int cells : {4, 6}) {
        r.cells = cells;
        j = pack_config_json(r);
        CHECK_FALSE(j["joint"].contains("voltage_sigma_v"));
        CHECK_FALSE(j["joint"]["health_filter"].contains("voltage_sigma_v"));
    }
}

TEST_CASE("make-config: a Li-ion pack's curve, resistance and cutoff", "[pack_config]") {
    PackRating r;
    r.cells = 6;
    r.capacity_ah = 8.4;  // 6S2P of 4.2 Ah cells: the pack's capacity
    r.chemistry = "li-ion";
    const json j = pack_config_json(r);
    // 88.5 mOhm Ah per cell x 6 / 8.4 Ah = 63.21 mOhm; cutoff 3.0 V per cell; empty at 2.5 V.
    CHECK(j["battery"]["internal_resistance_ohm"].get<double>() == Approx(0.06321));
    CHECK(j["monitor"]["min_flight_voltage_v"].get<double>() == Approx(18.0));
    CHECK(j["battery"]["min_voltage_v"].get<double>() == Approx(15.0));
    CHECK(j["battery"]["full_voltage_v"].get<double>() == Approx(24.8514));  // 4.1419 x 6
    CHECK(j["battery"]["nominal_zone_capacity_ah"].get<double>() == Approx(6.6822));  // 0.7955 x 8.4
    CHECK(j["battery"]["curve_current_a"].get<double>() == Approx(0.84));  // C/10
    CHECK(j["joint"]["ocv_cell_voltage_v"][0].get<double>() == Approx(2.5082));
    CHECK(j["joint"]["ocv_cell_voltage_v"][20].get<double>() == Approx(4.1417));
    CHECK(j["description"].get<std::string>().find("lithium-ion pack") != std::string::npos);
    r.chemistry = "nimh";
    CHECK_THROWS_WITH(pack_config_json(r), Catch::Contains("chemistry: expected lipo or li-ion, found \"nimh\""));
}

TEST_CASE("make-config: the filters' polarisation follows the pack's resistance", "[pack_config]") {
    PackRating r;
    r.cells = 6;
    r.capacity_ah = 2.0;
    // R = 5 mOhm x 6 / (2.0 / 1.55) = 23.25 mOhm: 1.1625 x the reference's 20 mOhm. The prior
    // scales by that, its spread and drift by its square root (1.07819), to 4 digits.
    const json j = pack_config_json(r);
    CHECK(j["battery"]["internal_resistance_ohm"].get<double>() == Approx(0.02325));
    CHECK(j["joint"]["polarisation_initial_ohm"].get<double>() == Approx(0.006161));       // 0.0053 x 1.1625
    CHECK(j["joint"]["polarisation_sigma0_ohm"].get<double>() == Approx(0.02372));         // 0.022 x 1.07819
    CHECK(j["joint"]["polarisation_process_ohm_per_sqrt_s"].get<double>() == Approx(2.803e-4));  // 2.6e-4 x 1.07819
    for (const char* filter : {"health_filter", "verdict_filter"}) {
        CHECK(j["joint"][filter]["polarisation_initial_ohm"].get<double>() == Approx(0.005231));   // 0.0045 x 1.1625
        CHECK(j["joint"][filter]["polarisation_sigma0_ohm"].get<double>() == Approx(0.01402));     // 0.013 x 1.07819
        CHECK(j["joint"][filter]["polarisation_process_ohm_per_sqrt_s"].get<double>() == Approx(1.509e-4));
    }
    // A resistance given is the one scaled by: 40 mOhm, twice the reference.
    r.resistance_ohm = 0.04;
    const LoadedConfig c = config_from_json(pack_config_json(r), "test");
    CHECK(c.monitor.joint.ekf.polarisation_initial_ohm == Approx(0.0106f));
    CHECK(c.monitor.joint.health.ekf.polarisation_sigma0_ohm == Approx(0.01838f).epsilon(1e-3));  // 0.013 x 1.41421
    // The reference pack's own rating keeps the core's values, unwritten.
    r.cells = 4;
    r.capacity_ah = 1.55;
    r.resistance_ohm = NAN;
    CHECK_FALSE(pack_config_json(r)["joint"].contains("polarisation_initial_ohm"));
}

TEST_CASE("make-config: a rating out of range is refused with what was expected", "[pack_config]") {
    PackRating r;
    r.cells = 4;
    r.capacity_ah = 1.5;
    r.cutoff_voltage_v = 8.0;  // 2.0 V per cell
    CHECK_THROWS_WITH(pack_config_json(r), Catch::Contains("2.5..3.9 V per cell, found 2 V") &&
                                               Catch::Contains("it is the pack's voltage: 4 cells x the per-cell figure"));
    r.cutoff_voltage_v = NAN;
    r.cells = 13;
    CHECK_THROWS_WITH(pack_config_json(r), Catch::Contains("cells: expected 1..12, found 13"));
    r.cells = 4;
    r.capacity_ah = 0.01;
    CHECK_THROWS_WITH(pack_config_json(r), Catch::Contains("found 10 mAh"));
}

TEST_CASE("make-config: the curve's floor is no higher than a cutoff below it", "[pack_config]") {
    // A Li-ion cell flown to 2.5 V: the floor had stayed 3.325 V per cell, where a bench
    // discharge read with the config stopped, its last sixth unread.
    PackRating r;
    r.cells = 1;
    r.capacity_ah = 3.0;
    r.cutoff_voltage_v = 2.5;
    const auto j = pack_config_json(r);
    CHECK(j["battery"]["min_voltage_v"].get<double>() == Approx(2.5));
    CHECK(j["monitor"]["min_flight_voltage_v"].get<double>() == Approx(2.5));
    r.cutoff_voltage_v = 3.5;  // above the floor: the floor stays
    CHECK(pack_config_json(r)["battery"]["min_voltage_v"].get<double>() == Approx(3.325));
}

TEST_CASE("The cell count from how high a pack rests", "[pack_config]") {
    CHECK(cells_from_resting_voltage(11.98) == 3);  // underpowered.log: 3.99 V as 3S, 3.00 V as 4S
    CHECK(cells_from_resting_voltage(14.99) == 4);  // the octocopter's: 3.75 V
    CHECK(cells_from_resting_voltage(16.54) == 4);  // log171.bin: 4.135 V, 3.31 V as 5S
    CHECK(cells_from_resting_voltage(22.8) == 6);  // 3.80 V; 4.56 V as 5S, 3.26 V as 7S
    CHECK(cells_from_resting_voltage(25.2) == 0);  // a full 6S pack (4.2 V) or a 7S one at 3.6 V
    CHECK(cells_from_resting_voltage(21.9) == 0);  // 3.65 V as 6S and 4.38 V as 5S: cannot tell
    // Two counts rest in 3.45-4.40 V, but only one where a pack takes off from (3.6 V and up).
    CHECK(cells_from_resting_voltage(24.22) == 6);  // CMU Matrice 100 flight 1: 4.04 V; 3.46 V as 7S
    CHECK(cells_from_resting_voltage(17.5) == 4);   // 4.375 V; 3.50 V as 5S
    CHECK(cells_from_resting_voltage(10.5) == 3);   // none takes off: 3.50 V as 3S, 2.63 V as 4S
    CHECK(cells_from_resting_voltage(2.0) == 0);
    CHECK(cells_from_resting_voltage(NAN) == 0);
}

TEST_CASE("What an autopilot log says about its pack", "[pack_config]") {
    SECTION("ArduPilot: capacity, failsafe voltage and timer; cells from the voltage") {
        const LogPack p = log_pack(with_parameters({{"BATT_MONITOR", 4}, {"BATT_CAPACITY", 1760}, {"LOW_VOLT", 10.5}}), 14.99);
        CHECK(p.cells == 4);
        CHECK(p.cells_from.find("14.99 V") != std::string::npos);
        CHECK(p.capacity_ah == Approx(1.76));
        CHECK(p.capacity_from == "the log's BATT_CAPACITY 1760 mAh");
        CHECK(p.cutoff_voltage_v == Approx(10.5));  // 2.625 V per cell: low, but a cutoff
        const LogPack q = log_pack(with_parameters({{"BATT_CAPACITY", 0}, {"BATT_LOW_VOLT", 20.0}, {"BATT_LOW_TIMER", 10}}), 14.99);
        CHECK(std::isnan(q.capacity_ah));  // 0 = unset
        CHECK(std::isnan(q.cutoff_voltage_v));  // 5 V per cell is no cutoff
        REQUIRE(q.ignored.size() == 1);
        CHECK(q.ignored[0].find("BATT_LOW_VOLT 20") != std::string::npos);
        CHECK(q.cutoff_delay_s == 10.0);
    }
    SECTION("a count given against the log's rest is noted when it puts a cell outside a lithium cell's") {
        // 16.54 V as 6S: 2.76 V per cell; as 4S 4.135 V.
        LogPack p = log_pack(with_parameters({{"BATT_CAPACITY", 5200}}), 16.54, 6);
        REQUIRE(p.notes.size() == 1);
        CHECK(p.notes[0] ==
              "the log's pack rests at 16.54 V, 2.76 V per cell on the 6 cells given, outside where a lithium cell rests "
              "(3.45-4.40 V); on 4 cells it is 4.13 V per cell: check --cells");
        p = log_pack(with_parameters({{"BATT_CAPACITY", 5200}}), 16.54, 4);
        CHECK(p.notes.empty());
        p = log_pack(with_parameters({{"BATT_CAPACITY", 5200}}), NAN, 6);  // no rest: nothing to judge
        CHECK(p.notes.empty());
    }
    SECTION("PX4: cells, capacity and a per-cell resistance; -1 = unset") {
        const LogPack p = log_pack(with_parameters({{"BAT1_N_CELLS", 3}, {"BAT1_CAPACITY", 2200}, {"BAT1_R_INTERNAL", 0.005}}), NAN);
        CHECK(p.cells == 3);
        CHECK(p.cells_from == "the log's BAT1_N_CELLS 3");
        CHECK(p.cells_declared);
        CHECK(p.capacity_ah == Approx(2.2));
        CHECK(p.resistance_ohm == Approx(0.015));
        const LogPack q = log_pack(with_parameters({{"BAT1_N_CELLS", 0}, {"BAT1_CAPACITY", -1}, {"BAT1_R_INTERNAL", -1}}), NAN);
        CHECK(q.cells == 0);
        CHECK(std::isnan(q.capacity_ah));
        CHECK(std::isnan(q.resistance_ohm));
    }
    SECTION("values per cell judged with the count the config will have; a failsafe that does nothing said") {
        // No cell count in the log (loaded at the start): with --cells 4 the cutoff and PX4's
        // resistance still count (they had been dropped without a word).
        const SourceInfo both = with_parameters({{"LOW_VOLT", 10.5}, {"BAT1_R_INTERNAL", 0.005}});
        const LogPack none = log_pack(both, NAN);
        CHECK(std::isnan(none.cutoff_voltage_v));
        CHECK(std::isnan(none.resistance_ohm));
        REQUIRE(none.ignored.size() == 2);
        CHECK(none.ignored[0] == "LOW_VOLT 10.5 V: with no cell count it cannot be judged per cell; the default 3.325 V "
                                 "per cell is used");
        const LogPack given = log_pack(both, NAN, 4);
        CHECK(given.cutoff_voltage_v == Approx(10.5));
        CHECK(given.cutoff_from == "the log's LOW_VOLT 10.5 V (2.62 V per cell)");
        CHECK(given.resistance_ohm == Approx(0.020));  // 4 x 5 mOhm, not the log's count's
        // Judged with the given count: 14 V over 6 cells is no cutoff, and the note says 6.
        const LogPack six = log_pack(with_parameters({{"FS_BATT_VOLTAGE", 14.0}}), 16.54, 6);
        REQUIRE(six.ignored.size() == 1);
        CHECK(six.ignored[0] == "FS_BATT_VOLTAGE 14 V: 2.33 V per cell (6 cells) is no cutoff (2.5-3.9 V); the default "
                                "3.325 V per cell is used");
        const LogPack off = log_pack(with_parameters({{"FS_BATT_ENABLE", 0}, {"LOW_VOLT", 10.5}}), 14.99);
        CHECK(off.cutoff_voltage_v == Approx(10.5));
        REQUIRE(off.cutoff_notes.size() == 2);
        CHECK(off.cutoff_notes[0].find("takes no action (FS_BATT_ENABLE 0)") != std::string::npos);
        CHECK(off.notes.empty());
        // More cells than battsim handles: not guessed from the voltage instead.
        const LogPack many = log_pack(with_parameters({{"BAT1_N_CELLS", 14}}), 58.0);
        CHECK(many.cells == 0);
        CHECK(many.declared_cells_beyond == 14);
    }
    SECTION("a cutoff below a LiPo's is said, with the count it would fit") {
        // ArduCopter 3's default LOW_VOLT on a 4S pack (robert_lefebvre_octo_PM.log): 2.62 V per
        // cell, taken without a word, ran the remaining time to a depth no LiPo is flown to.
        const LogPack four = log_pack(with_parameters({{"LOW_VOLT", 10.5}}), 14.99);
        CHECK(four.cutoff_voltage_v == Approx(10.5));  // still the cutoff: a Li-ion pack is flown there
        REQUIRE(four.cutoff_notes.size() == 1);
        CHECK(four.cutoff_notes[0] ==
              "the log's LOW_VOLT 10.5 V is 2.62 V per cell on 4 cells, below where a LiPo is flown (3.0 V per cell or "
              "more under load); it is 3.50 V per cell on 3 cells: set for another pack? The remaining time runs to it, "
              "which lengthens it; give --cutoff-v (e.g. 13.30 for 4 cells at 3.325 V) unless this is a Li-ion pack "
              "flown that low");
        // An ordinary LiPo cutoff says nothing (underpowered.log: 9.4 V on 3S, 3.13 V per cell).
        CHECK(log_pack(with_parameters({{"LOW_VOLT", 9.4}}), 12.10).cutoff_notes.empty());
        // 2.6 V per cell on 6S fits no single other count in the band: no guess named.
        const LogPack six = log_pack(with_parameters({{"BATT_LOW_VOLT", 15.6}}), 24.2);
        REQUIRE(six.cells == 6);
        REQUIRE(six.cutoff_notes.size() == 1);
        CHECK(six.cutoff_notes[0].find("set for another pack") == std::string::npos);
    }
    SECTION("a log's cell columns count before its voltage") {
        SourceInfo info;
        info.cell_count = 4;
        CHECK(log_pack(info, 11.98).cells == 4);
        CHECK_FALSE(log_pack(info, 11.98).cells_declared);  // columns, not a setting
    }
}

TEST_CASE("Replay notes a config for another pack than the log's autopilot flew", "[pack_config][config]") {
    const battsim::core::MonitorConfig m = default_config().monitor;  // 4S, 1.55 Ah
    LogFacts f;
    f.path = "flight.bin";
    f.declared_capacity_ah = 1.76;
    f.declared_capacity_from = "the log's BATT_CAPACITY 1760 mAh";
    std::vector<std::string> notes = config_notes(m, f);
    REQUIRE(notes.size() == 1);
    CHECK(notes[0] == "the log's autopilot was set for a 1.76 Ah pack (the log's BATT_CAPACITY 1760 mAh), the config's is "
                      "1.55 Ah: battsim make-config --from-log flight.bin writes one for it (with --capacity-mah if the log does not "
                      "record the capacity)");
    f.declared_capacity_ah = 1.6;  // within 10 %: labels differ that much
    CHECK(config_notes(m, f).empty());
    f.declared_cells = 6;
    f.declared_cells_from = "the log's BAT1_N_CELLS 6";
    notes = config_notes(m, f);
    REQUIRE(notes.size() == 1);
    CHECK(notes[0].find("set for 6 cells (the log's BAT1_N_CELLS 6), the config has 4") != std::string::npos);
    // A 3S pack at rest read as 4S: 3.00 V per cell is inside the resting range, so only
    // the likelier count says it.
    LogFacts rest;
    rest.resting_voltage_v = 12.0;
    notes = config_notes(m, rest);
    REQUIRE(notes.size() == 1);
    CHECK(notes[0] == "the pack rests at 12.00 V: 4.00 V per cell as 3 cells, 3.00 V as the config's 4: does the config "
                      "match this pack?");
    rest.resting_voltage_v = 14.99;
    CHECK(config_notes(m, rest).empty());
    // A 6S Matrice 100 pack read as 7S: 3.46 V per cell rests, but no pack takes off from it.
    battsim::core::MonitorConfig seven = m;
    seven.cells_in_series = 7;
    rest.resting_voltage_v = 24.22;
    notes = config_notes(seven, rest);
    REQUIRE(notes.size() == 1);
    CHECK(notes[0] == "the pack rests at 24.22 V: 4.04 V per cell as 6 cells, 3.46 V as the config's 7: does the config "
                      "match this pack?");
    LogFacts passed;
    passed.capacity_passed_s = 22.4;
    notes = config_notes(m, passed);
    REQUIRE(notes.size() == 1);
    CHECK(notes[0].rfind("the charge counted since full passed the config's capacity (1.55 Ah) 22.4 s into the log: the "
                         "model's voltage past there is not a battery's", 0) == 0);
}

TEST_CASE("make-config: a given pack resistance that looks like one cell's is noted", "[pack_config]") {
    PackRating r;
    r.cells = 4;
    r.capacity_ah = 1.3;  // the reference's 5 mOhm per cell x 1.55 / 1.3 = 5.96 mOhm per cell
    r.resistance_ohm = 0.004;
    CHECK(per_cell_resistance_note(r) ==
          "--resistance-mohm is the whole pack's: 4 mOhm is 1 mOhm per cell on 4 cells, where the reference LiPo scaled "
          "to this rating has 6 mOhm per cell. If your charger showed it per cell, give the sum of the cells' (e.g. 4 x 4 "
          "= 16)");
    r.resistance_ohm = 0.0089;  // just under 1.5 x 5.96 mOhm: still a cell's
    CHECK_FALSE(per_cell_resistance_note(r).empty());
    r.resistance_ohm = 0.009;  // above: a low pack, not noted
    CHECK(per_cell_resistance_note(r).empty());
    r.resistance_ohm = 0.016;
    CHECK(per_cell_resistance_note(r).empty());
    r.cells = 1;  // one cell: the pack's is the cell's
    r.resistance_ohm = 0.004;
    CHECK(per_cell_resistance_note(r).empty());
}

TEST_CASE("make-config: a value given wins over the log's, and each says where it came from", "[pack_config]") {
    LogPack log;
    log.cells = 3;
    log.cells_from = "how high it rests";
    log.capacity_ah = 4.0;
    log.capacity_from = "BATT_CAPACITY";
    log.cutoff_voltage_v = 10.5;
    log.cutoff_from = "BATT_LOW_VOLT";
    log.cutoff_delay_s = 10.0;
    log.cutoff_delay_from = "BATT_LOW_TIMER";
    PackRating given;  // nothing given: the log's values
    given.name = "mine";
    PackRating r = merge_rating(given, log);
    CHECK(r.name == "mine");
    CHECK(r.cells == 3);
    CHECK(r.capacity_ah == 4.0);
    CHECK(std::isnan(r.resistance_ohm));  // neither says: left to the reference pack's
    CHECK(r.cutoff_voltage_v == 10.5);
    CHECK(r.cutoff_delay_s == 10.0);
    CHECK(r.sources == std::vector<std::string>{"3 cells from how high it rests", "capacity from BATT_CAPACITY",
                                                "cutoff from BATT_LOW_VOLT", "cutoff delay from BATT_LOW_TIMER"});
    given.cells = 4;
    given.capacity_ah = 1.76;
    given.resistance_ohm = 0.012;
    given.cutoff_voltage_v = 13.3;
    r = merge_rating(given, log);
    CHECK(r.cells == 4);
    CHECK(r.capacity_ah == 1.76);
    CHECK(r.resistance_ohm == 0.012);
    CHECK(r.cutoff_voltage_v == 13.3);
    CHECK(r.cutoff_delay_s == 10.0);
    CHECK(r.sources == std::vector<std::string>{"cells given", "capacity given", "resistance given", "cutoff given",
                                                "cutoff delay from BATT_LOW_TIMER"});
    // Without a log, what was given alone.
    r = merge_rating(given, LogPack());
    CHECK(r.sources.size() == 4);
    CHECK(std::isnan(r.cutoff_delay_s));
}

TEST_CASE("make-config --board: the board's settings, not the reference logger's, as effective values", "[pack_config]") {
    PackRating r;
    r.cells = 6;
    r.capacity_ah = 5.0;
    json made = pack_config_json(r);
    // The reference logger's own config changes nothing: its board settings are make-config's.
    json same = made;
    CHECK(apply_board(same, builtin_config()).empty());
    CHECK(same == made);

    LoadedConfig board = builtin_config();
    board.monitor.shunt.offset_ma = 12.5f;
    board.monitor.shunt.scale_mv_per_10a = 3.75f;
    board.monitor.extensions.current_sensor.gain = 1.03f;
    board.monitor.cell_analysis.first_cell_includes_lead = false;  // a monitor with its own supply
    board.monitor.cell_analysis.last_lead_excess = 1.25f;          // its lead calibrated, on 4S packs
    board.telemetry.system_id = 3;
    board.monitor.sensor.max_pack_voltage_v = 99.0f;  // the pack's, not the board's: not taken
    std::vector<std::string> left;
    const std::vector<std::string> changed = apply_board(made, board, &left);
    CHECK(changed == std::vector<std::string>{"sensor.shunt_offset_ma", "sensor.shunt_scale_mv_per_10a",
                                              "battery.extensions.current_sensor", "joint.first_cell_includes_lead",
                                              "telemetry"});
    // A lead's share depends on the cell count: a 4S board's is not taken to this 6S pack.
    CHECK(left == std::vector<std::string>{"joint.last_cell_lead_excess"});
    CHECK_FALSE(made["joint"].contains("last_cell_lead_excess"));
    CHECK(made["sensor"]["shunt_offset_ma"] == 12.5);
    CHECK(made["sensor"]["shunt_scale_mv_per_10a"] == 3.75);
    CHECK(made["sensor"]["max_pack_voltage_v"] == 31.5);  // 5.25 V per cell on 6S, as made
    CHECK(made["battery"]["extensions"]["current_sensor"]["gain"] == 1.03);
    CHECK(made["joint"]["first_cell_includes_lead"] == false);
    CHECK(made["telemetry"]["system_id"] == 3);
    CHECK(made["battery"]["capacity_ah"] == 5.0);
    const LoadedConfig read = config_from_json(made, "test");
    CHECK(read.monitor.shunt.offset_ma == 12.5f);
    CHECK(read.monitor.extensions.current_sensor.gain == 1.03f);

    // A board config at the defaults takes a correction back out (an effective value, not a
    // missing key), and says so.
    const std::vector<std::string> back = apply_board(made, builtin_config());
    CHECK(back == changed);
    CHECK_FALSE(made["battery"]["extensions"].contains("current_sensor"));
    CHECK_FALSE(made.contains("telemetry"));
    CHECK(made["joint"]["first_cell_includes_lead"] == true);

    // On a pack of the board's own cell count the share is taken.
    PackRating r4;
    r4.cells = 4;
    r4.capacity_ah = 1.5;
    json made4 = pack_config_json(r4);
    const std::vector<std::string> changed4 = apply_board(made4, board);
    CHECK(std::find(changed4.begin(), changed4.end(), "joint.last_cell_lead_excess") != changed4.end());
    CHECK(made4["joint"]["last_cell_lead_excess"] == 1.25);
}
