// The truth simulator: deterministic maths and random numbers, the OCV table, the
// plant's conservation laws, the truth's remaining time, seeded determinism, scenario
// files, and the plant against one real flight.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/monitor.h"
#include "host/config_json.h"
#include "host/sim/sensor.h"
#include "host/sim/det_math.h"
#include "host/sim/ocv.h"
#include "host/sim/plant.h"
#include "host/sim/profile.h"
#include "host/sim/rng.h"
#include "host/sim/scenario.h"
#include "host/sim/simulate.h"
#include "sim_scenarios.h"
#include "test_files.h"

using namespace battsim::host;
using namespace battsim::host::sim;
using nlohmann::json;

namespace {

// A short 4S flight built in code (the monitor config embedded, no files).
Scenario small_scenario(const std::string& extra_json = "{}") {
    return simtest::code_scenario(R"({
      "schema": "battsim.scenario", "version": 1, "name": "unit", "seed": 7,
      "monitor_config": "embedded",
      "pack": {"cells": 4, "capacity_ah": 1.55},
      "profile": {"kind": "racing", "idle_before_s": 8, "armed_s": 2, "flight_s": 60, "idle_after_s": 5,
                  "mean_power_w": 420}
    })", extra_json);
}


bool file_exists(const std::string& path) { return std::ifstream(path).good(); }

}  // namespace

TEST_CASE("det_exp and det_log match the C library to the last bits", "[sim]") {
    CHECK(det_exp(0.0) == 1.0);
    CHECK(det_log(1.0) == 0.0);
    for (double x = -40.0; x <= 40.0; x += 0.173) {
        CHECK(det_exp(x) == Approx(std::exp(x)).epsilon(1e-15));
    }
    for (double x = 1e-6; x < 1e6; x *= 1.37) {
        CHECK(det_log(x) == Approx(std::log(x)).epsilon(1e-15).margin(1e-15));
    }
    CHECK(det_exp(-800.0) == 0.0);
    CHECK(std::isinf(det_exp(800.0)));
    CHECK(std::isnan(det_log(-1.0)));
    CHECK(round_fixed(1.23456789, 3) == 1.235);
    CHECK(round_fixed(-2.5, 0) == -3.0);
    CHECK(round_fixed(-0.0004, 3) == 0.0);
    CHECK(!std::signbit(round_fixed(-0.0004, 3)));
}

TEST_CASE("Rng: xoshiro256** reference sequence, seeding and distributions", "[sim]") {
    // The published generator from state {1, 2, 3, 4} starts 11520, 0, 1509978240.
    Rng ref = Rng::from_state(1, 2, 3, 4);
    CHECK(ref.next_u64() == 11520u);
    CHECK(ref.next_u64() == 0u);
    CHECK(ref.next_u64() == 1509978240u);

    Rng a(42), b(42), c(43);
    for (int i = 0; i < 100; ++i) {
        const uint64_t x = a.next_u64();
        CHECK(x == b.next_u64());
        CHECK(x != c.next_u64());
    }
    Rng s1 = Rng::stream(42, 1), s2 = Rng::stream(42, 2);
    CHECK(s1.next_u64() != s2.next_u64());

    Rng r(2024);
    const int n = 200000;
    double su = 0, su2 = 0, sn = 0, sn2 = 0, se = 0;
    int beyond3 = 0;
    for (int i = 0; i < n; ++i) {
        const double u = r.uniform();
        REQUIRE(u >= 0.0);
        REQUIRE(u < 1.0);
        su += u;
        su2 += u * u;
        const double z = r.normal();
        sn += z;
        sn2 += z * z;
        if (std::fabs(z) > 3.0) ++beyond3;
        se += r.exponential(2.0);
    }
    CHECK(su / n == Approx(0.5).margin(0.005));
    CHECK(su2 / n - (su / n) * (su / n) == Approx(1.0 / 12.0).margin(0.002));
    CHECK(sn / n == Approx(0.0).margin(0.01));
    CHECK(sn2 / n == Approx(1.0).margin(0.015));
    CHECK(beyond3 == Approx(0.0027 * n).epsilon(0.15));  // the normal's tails
    CHECK(se / n == Approx(2.0).epsilon(0.02));
    for (int i = 0; i < 1000; ++i) {
        const int k = r.uniform_int(3, 6);
        CHECK(k >= 3);
        CHECK(k <= 6);
    }
}

TEST_CASE("OCV table: 3.3 V empty, 4.2 V full, strictly rising everywhere", "[sim]") {
    const OcvCurve& ocv = OcvCurve::generic_lipo();
    REQUIRE(ocv.points() == 21);
    CHECK(ocv.voltage_v(0.0) == Approx(3.3));
    CHECK(ocv.voltage_v(1.0) == Approx(4.2));
    for (int i = 0; i < ocv.points(); ++i) CHECK(ocv.voltage_v(ocv.soc_at(i)) == Approx(ocv.voltage_at(i)).margin(1e-12));
    double prev = ocv.voltage_v(-0.1);
    for (double soc = -0.1 + 1e-4; soc <= 1.05; soc += 1e-4) {
        const double v = ocv.voltage_v(soc);
        REQUIRE(v > prev);
        prev = v;
    }
    // Past empty the cell collapses steeply.
    CHECK(ocv.voltage_v(-0.05) == Approx(3.3 - 0.05 * ocv.empty_slope_v));
    OcvCurve bad;
    const double soc[3] = {0.0, 0.5, 1.0}, falling[3] = {3.3, 3.9, 3.8};
    CHECK_FALSE(bad.set_table(soc, falling, 3));
    CHECK(bad.points() == 0);
}


TEST_CASE("Plant conserves charge and energy under a varying power demand", "[sim]") {
    PlantParams p;
    p.cells = 4;
    for (int c = 0; c < 4; ++c) p.cell[c].capacity_ah = 1.5 + 0.03 * c;
    Plant plant;
    plant.configure(p, 1.0, 20.0);
    ProfileParams prof;
    FlightPower demand(prof, 99);
    const double dt = 0.002;
    double charge_ah = 0.0, energy_wh = 0.0, i_prev = 0.0, i_first = -1.0;
    for (int n = 0; n < 60000; ++n) {  // two minutes of racing
        const double power = demand.next(dt);
        const PlantOutput out = plant.step_power(power, dt, true);
        REQUIRE_FALSE(out.brownout);
        // Constant power at the terminals: the solved current meets the demand.
        CHECK(out.voltage_v * out.current_a == Approx(power).epsilon(1e-9).margin(1e-9));
        charge_ah += out.current_a * dt / 3600.0;
        energy_wh += out.voltage_v * out.current_a * dt / 3600.0;
        if (i_first < 0.0) i_first = out.current_a;
        i_prev = out.current_a;
    }
    (void)i_prev;
    CHECK(plant.state().charge_ah == Approx(charge_ah).epsilon(1e-12));
    CHECK(plant.state().energy_wh == Approx(energy_wh).epsilon(1e-12));
    // ∫I dt equals each cell's drop in state of charge times its capacity.
    for (int c = 0; c < 4; ++c) {
        CHECK((1.0 - plant.state().soc[c]) * p.cell[c].capacity_ah == Approx(charge_ah).epsilon(1e-9));
    }
    CHECK(charge_ah > 0.5);
}

TEST_CASE("Plant: constant power draws more current as the pack sags", "[sim]") {
    PlantParams p;
    Plant plant;
    plant.configure(p, 1.0, 20.0);
    PlantOutput first = plant.step_power(300.0, 0.01, true), last = first;
    for (int n = 0; n < 20000; ++n) last = plant.step_power(300.0, 0.01, true);
    CHECK(last.voltage_v < first.voltage_v - 1.0);
    CHECK(last.current_a > first.current_a * 1.05);
    CHECK(last.voltage_v * last.current_a == Approx(300.0).epsilon(1e-9));
}

TEST_CASE("Plant: Arrhenius resistance and the lumped heat balance", "[sim]") {
    PlantParams p;
    p.conductance_flight_w_per_k = 0.0;  // adiabatic: every joule of loss heats the pack
    p.conductance_ground_w_per_k = 0.0;
    Plant plant;
    plant.configure(p, 1.0, 25.0);
    CHECK(plant.temperature_factor() == Approx(1.0));
    const double expect0 = std::exp(20000.0 / 8.314462618 * (1.0 / 273.15 - 1.0 / 298.15));
    CHECK(plant.temperature_factor_at(0.0) == Approx(expect0).epsilon(1e-12));
    CHECK(expect0 == Approx(2.09).margin(0.01));
    CHECK(plant.temperature_factor_at(40.0) < 0.7);
    for (int n = 0; n < 30000; ++n) plant.step_power(500.0, 0.005, true);
    const double rise = plant.state().temperature_c - 25.0;
    CHECK(rise > 1.0);
    CHECK(rise == Approx(plant.state().heat_j / p.heat_capacity_j_per_k).epsilon(1e-9));
    // With convection the pack settles back to ambient.
    PlantParams q;
    q.ambient_c = 10.0;
    Plant cool;
    cool.configure(q, 0.8, 35.0);
    for (int n = 0; n < 60000; ++n) cool.step_power(0.0, 0.1, false);  // 6000 s, 12 time constants
    CHECK(cool.state().temperature_c == Approx(10.0).margin(0.2));
}

TEST_CASE("Truth: remaining time falls at 1 s per s and the continuation is consistent", "[sim]") {
    const Scenario s = small_scenario();
    const SimulationResult r = simulate(s);
    const Truth& t = r.truth;
    REQUIRE(t.total_flight_time_s > 60.0);  // the planned landing comes before the cutoff
    CHECK_FALSE(t.landed_by_cutoff);
    CHECK(t.landing_s == Approx(t.planned_landing_s));
    // The cutoff found by flying on after the landing equals that of a straight run
    // of the same pack: the copy of plant and demand at landing is exact.
    CHECK(flight_time_to_cutoff(s, false) == t.total_flight_time_s);
    CHECK(t.healthy_total_flight_time_s == t.total_flight_time_s);  // an undegraded pack is its own twin
    int in_flight = 0;
    const TruthPoint* prev = nullptr;
    for (const TruthPoint& p : t.series) {
        if (!p.in_flight) {
            prev = nullptr;
            continue;
        }
        ++in_flight;
        CHECK(p.remaining_time_s == Approx(t.cutoff_s - p.time_s));
        if (prev) {
            CHECK((p.remaining_time_s - prev->remaining_time_s) / (p.time_s - prev->time_s) == Approx(-1.0).epsilon(1e-9));
            // Energy left falls by what was delivered in between.
            CHECK(prev->remaining_energy_wh - p.remaining_energy_wh == Approx(p.energy_wh - prev->energy_wh).epsilon(1e-9));
            CHECK(p.remaining_energy_wh < prev->remaining_energy_wh);
        }
        prev = &p;
    }
    CHECK(in_flight >= 59);
    CHECK(t.energy_to_cutoff_wh > 0.0);
    CHECK(t.mean_flight_power_w == Approx(420.0).epsilon(0.1));

    // A pack without enough charge ends the flight at its cutoff.
    const Scenario low = small_scenario(R"({"pack": {"initial_soc": 0.3}})");
    const SimulationResult rl = simulate(low);
    CHECK(rl.truth.landed_by_cutoff);
    CHECK(rl.truth.landing_s == Approx(rl.truth.cutoff_s));
    CHECK(rl.truth.total_flight_time_s < 60.0);
    CHECK(flight_time_to_cutoff(low, false) == Approx(rl.truth.total_flight_time_s).margin(1e-9));
}

TEST_CASE("Truth: degraded packs fly shorter than their healthy twin and say why", "[sim]") {
    const SimulationResult healthy = simulate(small_scenario());
    const SimulationResult aged = simulate(small_scenario(R"({"pack": {"capacity_factor": 0.7}})"));
    CHECK(aged.truth.healthy_total_flight_time_s == healthy.truth.total_flight_time_s);
    CHECK(aged.truth.total_flight_time_s < 0.8 * aged.truth.healthy_total_flight_time_s);
    CHECK(aged.truth.short_flight());
    CHECK(aged.truth.degraded);
    CHECK(aged.truth.justified_warnings == std::vector<std::string>{"low_capacity"});
    CHECK(aged.truth.pack_capacity_ah == Approx(0.7 * healthy.truth.pack_capacity_ah).epsilon(1e-12));
    CHECK_FALSE(healthy.truth.degraded);

    const SimulationResult weak = simulate(small_scenario(R"({"pack": {"weak_cells": [{"cell": 3, "resistance_factor": 1.6}]}})"));
    CHECK(weak.truth.weak_cell == 2);
    CHECK(weak.truth.justified_warnings == std::vector<std::string>{"cell_outlier"});
    const SimulationResult hot_r = simulate(small_scenario(R"({"pack": {"resistance_factor": 1.8}})"));
    CHECK(hot_r.truth.justified_warnings == std::vector<std::string>{"high_resistance"});
    CHECK(hot_r.truth.pack_r0_reference_ohm == Approx(1.8 * healthy.truth.pack_r0_reference_ohm).epsilon(1e-12));
}

TEST_CASE("Seeded determinism: same seed, same bytes; the sensors never touch the plant", "[sim]") {
    const Scenario s = small_scenario();
    const SimulationResult a = simulate(s), b = simulate(s);
    CHECK(a.log_text == b.log_text);
    CHECK(truth_to_json(a).dump() == truth_to_json(b).dump());
    const SimulationResult c = simulate(small_scenario(R"({"seed": 8})"));
    CHECK(a.log_text != c.log_text);
    // A sensor fault changes the log but not the flight.
    const SimulationResult f = simulate(small_scenario(R"({"sensor": {"faults": {"current_offset_a": 2.0}}})"));
    CHECK(f.log_text != a.log_text);
    CHECK(f.truth.total_flight_time_s == a.truth.total_flight_time_s);
    CHECK(truth_to_json(f)["series"] == truth_to_json(a)["series"]);
    // The resolved scenario written into the truth file simulates the same flight.
    const json tj = truth_to_json(a);
    const Scenario again = scenario_from_json(tj["scenario"], "truth", "", &tj["monitor_config"]);
    CHECK(simulate(again).log_text == a.log_text);
}

TEST_CASE("The bundled example log is what `battsim simulate` makes", "[sim]") {
    const std::string dir = BATTSIM_SOURCE_DIR;
    const std::string log = dir + "/logs/example-4s.csv";
    REQUIRE(file_exists(log));  // committed: missing is a failure, not a skip
    // battsim simulate configs/scenarios/4s-racing-healthy-a.json -o logs/example-4s.csv
    const SimulationResult r = simulate(load_scenario(dir + "/configs/scenarios/4s-racing-healthy-a.json"));
    CHECK(r.log_text == testsupport::read_file(log));
    // The truth file's flight, pack and series (its embedded copy of the monitor config
    // follows the config code and is left out).
    const json written = json::parse(testsupport::read_file(dir + "/logs/example-4s.truth.json"));
    const json now = truth_to_json(r);
    for (const char* key : {"scenario", "pack", "flight", "degradation", "sensor", "series", "log"}) {
        INFO(key);
        CHECK(written[key] == now[key]);
    }
    CHECK(r.log_text.size() > 100000);
    CHECK(r.log_text.size() < 400000);
}

TEST_CASE("Scenario files: the suite loads, covers what it must, and bad files are named", "[sim]") {
    const std::string dir = std::string(BATTSIM_SOURCE_DIR) + "/configs/scenarios";
    const std::vector<std::string> files = find_scenario_files({dir});
    CHECK(files.size() >= 30);
    std::set<std::string> names;
    std::set<int> cells;
    std::set<std::string> kinds;
    int faults = 0, weak = 0, aged = 0, partial = 0, cold = 0, hot = 0;
    for (const std::string& f : files) {
        const Scenario s = load_scenario(f);
        CHECK(names.insert(s.name).second);
        CHECK(f == dir + "/" + s.name + ".json");
        cells.insert(s.pack.cells);
        kinds.insert(to_string(s.profile.kind));
        faults += s.sensor.faults.any();
        weak += !s.pack.weak_cells.empty();
        aged += s.pack.capacity_factor < 1.0 || s.pack.resistance_factor > 1.0;
        partial += s.pack.initial_soc < 1.0;
        cold += s.ambient_c <= 5.0;
        hot += s.ambient_c >= 35.0;
        CHECK(s.config.monitor.cells_in_series == s.pack.cells);
    }
    CHECK(cells == std::set<int>{3, 4, 6});
    CHECK(kinds == std::set<std::string>{"hover", "racing"});
    CHECK(faults >= 4);
    CHECK(weak >= 4);
    CHECK(aged >= 6);
    CHECK(partial >= 2);
    CHECK(cold >= 2);
    CHECK(hot >= 2);

    const testsupport::TempDir temp("sim");
    const std::string tmp = temp.path();
    const auto write = [&](const std::string& name, const std::string& text) { return temp.write(name, text); };
    const std::string cfg = std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json";
    const std::string head = R"({"schema": "battsim.scenario", "version": 1, "name": "x", "monitor_config": ")" + cfg + "\"";
    const auto error_of = [](const std::string& path) -> std::string {
        try {
            load_scenario(path);
        } catch (const ScenarioError& e) {
            return e.what();
        }
        return "";
    };
    CHECK(error_of(write("ok.json", head + "}")).empty());
    const std::string typo = write("typo.json", head + R"(, "pack": {"capcity_ah": 1.5}})");
    CHECK(error_of(typo) == typo + ":1:" + std::to_string(head.size() + 12) + ": $.pack.capcity_ah: unknown key");
    const std::string syntax = write("syntax.json", head + ",\n  \"seed\": 1,,\n}");
    INFO(error_of(syntax));
    CHECK(error_of(syntax) == syntax + ":2:13: not valid JSON: syntax error while parsing object key - unexpected ','; expected string literal");
    const std::string range = write("range.json", head + R"(, "pack": {"capacity_ah": -1}})");
    CHECK(error_of(range).find(range + ":1:" + std::to_string(head.size() + 27) + ": $.pack.capacity_ah: expected a number in [") == 0);
    const std::string cells6 = write("cells.json", head + R"(, "pack": {"cells": 6}})");
    CHECK(error_of(cells6) == cells6 + ":1:" + std::to_string(head.size() - cfg.size() - 1) +
                                   ": $.monitor_config: the config is for 4 cells, the pack has 6");
    const std::string raw6 = write("raw6.json", R"({"schema": "battsim.scenario", "version": 1, "name": "x", "monitor_config": ")" +
                                                    std::string(BATTSIM_SOURCE_DIR) +
                                                    R"(/configs/generic-6s.json", "pack": {"cells": 6}, "log": {"format": "raw"}})");
    CHECK(error_of(raw6).find("$.log.format: the raw logger format has exactly 4 cells") != std::string::npos);
    const std::string weakc = write("weak.json", head + R"(, "pack": {"weak_cells": [{"cell": 5}]}})");
    CHECK(error_of(weakc).find("$.pack.weak_cells[0].cell: expected a whole number in [1, 4]") != std::string::npos);
    const std::string nocfg = write("nocfg.json", R"({"schema": "battsim.scenario", "version": 1, "name": "x", "monitor_config": "missing.json"})");
    CHECK(error_of(nocfg).find(nocfg + ":1:77: $.monitor_config: " + tmp + "/missing.json: cannot open config file: no such file") == 0);
    CHECK(error_of(write("empty.json", "")).find("file is empty") != std::string::npos);
    CHECK(error_of(tmp + "/absent.json") == tmp + "/absent.json: cannot open scenario file: no such file");
    CHECK_THROWS_AS(find_scenario_files({tmp + "/nothing"}), ScenarioError);
}

TEST_CASE("Scenario files: the held-out suite shares no seed or name with the tuning suite", "[sim]") {
    const std::string tuning_dir = std::string(BATTSIM_SOURCE_DIR) + "/configs/scenarios";
    const std::string holdout_dir = std::string(BATTSIM_SOURCE_DIR) + "/configs/scenarios-holdout";
    std::set<std::string> tuning_names;
    std::set<uint64_t> tuning_seeds;
    for (const std::string& f : find_scenario_files({tuning_dir})) {
        const Scenario s = load_scenario(f);
        tuning_names.insert(s.name);
        tuning_seeds.insert(s.seed);
    }
    const std::vector<std::string> files = find_scenario_files({holdout_dir});
    CHECK(files.size() >= 20);
    std::set<std::string> names;
    std::set<uint64_t> seeds;
    for (const std::string& f : files) {
        const Scenario s = load_scenario(f);
        INFO(f);
        CHECK(s.name.rfind("ho-", 0) == 0);
        CHECK(f == holdout_dir + "/" + s.name + ".json");
        CHECK(tuning_names.count(s.name) == 0);
        CHECK(tuning_seeds.count(s.seed) == 0);
        CHECK(s.seed >= 9001);
        CHECK(s.seed <= 9099);
        CHECK(names.insert(s.name).second);
        CHECK(seeds.insert(s.seed).second);
        CHECK(s.config.monitor.cells_in_series == s.pack.cells);
        CHECK(s.config.monitor.battery.capacity_ah == Approx(s.pack.capacity_ah));
    }
}

TEST_CASE("Scenario files: each ablation is its original with only the named plant part taken out", "[sim]") {
    const std::string src = std::string(BATTSIM_SOURCE_DIR) + "/configs/";
    const std::vector<std::string> files = find_scenario_files({src + "scenarios-ablation"});
    CHECK(files.size() >= 4);
    for (const std::string& f : files) {
        INFO(f);
        const Scenario a = load_scenario(f);
        const std::string::size_type cut = a.name.find("-no");
        REQUIRE(cut != std::string::npos);
        const std::string suffix = a.name.substr(cut + 1);
        const Scenario o = load_scenario(src + "scenarios/" + a.name.substr(0, cut) + ".json");
        CHECK(a.seed == o.seed);
        CHECK(a.config.monitor.cells_in_series == o.config.monitor.cells_in_series);
        CHECK(a.profile.flight_s == o.profile.flight_s);
        const bool no_rc = suffix == "norc" || suffix == "norc-nospread";
        const bool no_spread = suffix == "nospread" || suffix == "norc-nospread";
        REQUIRE((no_rc || no_spread || suffix == "nor2"));
        CHECK(o.pack.r2_ohm > 0.0);
        CHECK(a.pack.r2_ohm == (suffix == "nospread" ? o.pack.r2_ohm : 0.0));
        CHECK(a.pack.r1_ohm == (no_rc ? 0.0 : o.pack.r1_ohm));
        CHECK(a.pack.capacity_spread == (no_spread ? 0.0 : o.pack.capacity_spread));
        CHECK(a.pack.resistance_spread == (no_spread ? 0.0 : o.pack.resistance_spread));
        CHECK(a.pack.r0_ohm == o.pack.r0_ohm);
        CHECK(a.pack.capacity_ah == o.pack.capacity_ah);
    }
}

TEST_CASE("Scenario files: the truth runs to the cutoff the monitor is asked about", "[sim]") {
    // The truth's remaining time runs to cutoff_v_per_cell (loaded); each scenario's monitor
    // config names its own minimum flight voltage. A fixed 3.3 V per cell against the
    // configs' 3.325 had every column answer another question than the truth's, so the
    // truth takes the config's unless the scenario sets its own.
    const std::string src = std::string(BATTSIM_SOURCE_DIR) + "/configs/";
    const std::vector<std::string> files =
        find_scenario_files({src + "scenarios", src + "scenarios-holdout", src + "scenarios-ablation"});
    REQUIRE(files.size() > 60);
    for (const std::string& f : files) {
        INFO(f);
        const Scenario s = load_scenario(f);
        CHECK(s.config.monitor.flight_time.min_flight_voltage_v ==
              Approx(s.cutoff_v_per_cell * s.config.monitor.cells_in_series).epsilon(1e-6));
    }
    // sim-4s.json asks for 13.3 V: 3.325 V per cell. A scenario's own value wins.
    const std::string healthy = src + "scenarios/4s-racing-healthy-a.json";
    CHECK(load_scenario(healthy).cutoff_v_per_cell == Approx(3.325).epsilon(1e-6));
    std::ifstream in(healthy);
    nlohmann::json j = nlohmann::json::parse(in);
    j["truth"]["cutoff_v_per_cell"] = 3.4;
    CHECK(scenario_from_json(j, "x.json", src + "scenarios").cutoff_v_per_cell == 3.4);
    // A config whose minimum flight voltage is no cutoff (0 V) is named, with the way out.
    json cfg = config_to_json(default_config());
    cfg["monitor"]["min_flight_voltage_v"] = 0.0;
    j.erase("truth");
    CHECK_THROWS_WITH(scenario_from_json(j, "x.json", "", &cfg),
                      Catch::Contains("x.json: $.monitor_config: its min_flight_voltage_v gives 0.0") &&
                          Catch::Contains("set $.truth.cutoff_v_per_cell"));
    j["truth"]["cutoff_v_per_cell"] = 3.3;
    CHECK(scenario_from_json(j, "x.json", "", &cfg).cutoff_v_per_cell == 3.3);
}

TEST_CASE("The plant at 7 degC against flight 32: voltage against charge drawn", "[sim][data]") {
    // The shared flight 32 (a new CNHL 1500 mAh 4S at about 7 degC) and a simulated racing
    // flight in the same conditions: the IR-corrected pack voltage per cell, binned by
    // charge drawn, agrees within 0.05 V/cell from 0 to 900 mAh. A sanity check of the
    // plant's OCV table and losses, not a fit.
    const std::string path = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/32.csv";
    const auto bins = [](const std::string& text) {
        std::vector<std::vector<double>> rows;
        std::stringstream in(text);
        std::string line;
        while (std::getline(in, line)) {
            std::vector<double> v;
            std::stringstream ls(line);
            std::string f;
            while (std::getline(ls, f, ',') && v.size() < 8) v.push_back(std::stod(f));
            if (v.size() == 8) rows.push_back(v);
        }
        rows.pop_back();  // the real logs' last row can be an unplugging transient
        std::vector<std::vector<double>> by_bin(9);
        double q = 0;
        for (size_t i = 1; i < rows.size(); ++i) {
            const double dt = (rows[i][0] - rows[i - 1][0]) / 1000.0, amps = rows[i][6] / 1000.0;
            q += amps * dt / 3.6;
            const int b = static_cast<int>(q / 100.0);
            if (amps > 3.0 && b < 9) by_bin[static_cast<size_t>(b)].push_back((rows[i][1] + amps * 0.025) / 4.0);
        }
        std::vector<double> med;
        for (auto& v : by_bin) {
            std::sort(v.begin(), v.end());
            med.push_back(v.empty() ? NAN : v[v.size() / 2]);
        }
        return med;
    };
    const std::vector<double> real = bins(testsupport::read_file(path));
    const Scenario s = small_scenario(
        R"({"seed": 1002, "environment": {"ambient_c": 7}, "profile": {"idle_before_s": 60, "flight_s": 150, "mean_power_w": 360}})");
    const std::string sim_text = simulate(s).log_text;
    const std::vector<double> sim = bins(sim_text);
    for (size_t b = 0; b < real.size(); ++b) {
        INFO("charge bin " << b * 100 << " mAh: real " << real[b] << " V/cell, simulated " << sim[b]);
        CHECK(std::fabs(sim[b] - real[b]) < 0.05);
    }
    // The racing demand: flying current (above 1.5 A), median and 90th percentile.
    const auto percentiles = [](const std::string& text) {
        std::vector<double> amps;
        std::stringstream in(text);
        std::string line;
        while (std::getline(in, line)) {
            std::vector<std::string> f;
            std::stringstream ls(line);
            std::string x;
            while (std::getline(ls, x, ',')) f.push_back(x);
            if (f.size() >= 8 && std::stod(f[6]) > 1500.0) amps.push_back(std::stod(f[6]) / 1000.0);
        }
        std::sort(amps.begin(), amps.end());
        return std::vector<double>{amps[amps.size() / 2], amps[amps.size() * 9 / 10]};
    };
    const std::vector<double> pr = percentiles(testsupport::read_file(path)), ps = percentiles(sim_text);
    INFO("current median / p90: real " << pr[0] << " / " << pr[1] << " A, simulated " << ps[0] << " / " << ps[1] << " A");
    CHECK(ps[0] == Approx(pr[0]).epsilon(0.2));
    CHECK(ps[1] == Approx(pr[1]).epsilon(0.2));
}

TEST_CASE("Truth names outlier cells by the 10 % bar against the other cells, not by the declaration", "[sim]") {
    // No cell-to-cell spread, so the factors alone decide: R0 +12 % and capacity −12 % are
    // beyond the bar; +8 % and −8 % are not, whatever the scenario calls them.
    const auto outliers = [](const std::string& weak) {
        const SimulationResult r = simulate(small_scenario(
            R"({"pack": {"capacity_spread": 0, "resistance_spread": 0, "weak_cells": [)" + weak + "]}}"));
        return r.truth.outlier_cells;
    };
    CHECK(outliers(R"({"cell": 2, "resistance_factor": 1.12})") == std::vector<int>{1});
    CHECK(outliers(R"({"cell": 3, "capacity_factor": 0.88})") == std::vector<int>{2});
    CHECK(outliers(R"({"cell": 2, "resistance_factor": 1.08})").empty());
    CHECK(outliers(R"({"cell": 1, "capacity_factor": 0.92})").empty());
    const SimulationResult two = simulate(small_scenario(
        R"({"pack": {"capacity_spread": 0, "resistance_spread": 0, "weak_cells": [{"cell": 1, "capacity_factor": 0.8}, {"cell": 4, "resistance_factor": 1.5}]}})"));
    CHECK(two.truth.outlier_cells == std::vector<int>{0, 3});
    CHECK(two.truth.weak_cell == 3);  // the furthest: +50 % against −20 %
    const json tj = truth_to_json(two);
    CHECK(tj["degradation"]["outlier_cells"] == json::array({1, 4}));
    CHECK(tj["pack"]["per_cell"].size() == 4);
    CHECK(tj["pack"]["per_cell"][3]["r0_ohm_25c"].get<double>() ==
          Approx(1.5 * tj["pack"]["per_cell"][0]["r0_ohm_25c"].get<double>()).epsilon(1e-5));
}

TEST_CASE("The sensor-fault causes a monitor should name for each injected fault", "[sim]") {
    using namespace battsim;
    host::sim::SensorFaults f;
    CHECK(host::sim::nameable_fault_causes(f) == 0);
    f.current_gain_error = 0.08;  // seen by a charger, never in flight
    f.missed_probability = 0.05;  // single rows: no gap
    CHECK(host::sim::nameable_fault_causes(f) == 0);
    f.current_offset_a = -1.0;
    CHECK(host::sim::nameable_fault_causes(f) == core::kFaultCurrentOffset);
    f.loose_tap = 2;
    f.missed_burst_rate_per_min = 2.0;
    CHECK(host::sim::nameable_fault_causes(f) == (core::kFaultCurrentOffset | core::kFaultCells | core::kFaultSampleGap));
}

TEST_CASE("simulate -o LOG's default truth file: the extension of the file name replaced", "[sim]") {
    CHECK(default_truth_path("flight.csv") == "flight.truth.json");
    CHECK(default_truth_path("logs/flight.bin") == "logs/flight.truth.json");
    CHECK(default_truth_path("a.b.ulg") == "a.b.truth.json");  // the last dot only
    CHECK(default_truth_path("flight") == "flight.truth.json");
    // A dot in a directory's name is not the file's extension.
    CHECK(default_truth_path("run.2/flight") == "run.2/flight.truth.json");
    CHECK(default_truth_path("./flight") == "./flight.truth.json");
    CHECK(default_truth_path("../out/f.csv") == "../out/f.truth.json");
}

TEST_CASE("Scenario files: schema and version required, whole numbers however written, zero thermal values kept", "[sim]") {
    const testsupport::TempDir temp("sim");
    const std::string cfg = std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json";
    const std::string rest = R"("name": "x", "monitor_config": ")" + cfg + "\"";
    const std::string head = R"({"schema": "battsim.scenario", "version": 1, )" + rest;
    const auto error_of = [&](const std::string& name, const std::string& text) -> std::string {
        try {
            load_scenario(temp.write(name, text));
        } catch (const ScenarioError& e) {
            return e.what();
        }
        return "";
    };
    // Documented as required; a file without them had been read as a scenario.
    CHECK_THAT(error_of("noschema.json", "{" + rest + "}"), Catch::Contains("$.schema: missing: expected \"battsim.scenario\""));
    CHECK_THAT(error_of("noversion.json", R"({"schema": "battsim.scenario", )" + rest + "}"),
               Catch::Contains("$.version: missing: expected 1"));

    // 4.0 and 1e3 are the whole numbers 4 and 1000 ("expected a whole number, found 4.0" had
    // contradicted itself); 4.5 and -1 are not whole numbers of the range.
    const Scenario plain = load_scenario(temp.write("plain.json", head + R"(, "seed": 1000, "pack": {"cells": 4}})"));
    const Scenario floats = load_scenario(temp.write("floats.json", head + R"(, "seed": 1e3, "pack": {"cells": 4.0}})"));
    CHECK(floats.seed == 1000u);
    CHECK(floats.pack.cells == 4);
    CHECK(simulate(floats).log_text == simulate(plain).log_text);
    CHECK_THAT(error_of("half.json", head + R"(, "pack": {"cells": 4.5}})"), Catch::Contains("$.pack.cells: expected a whole number, found 4.5"));
    CHECK_THAT(error_of("neg.json", head + R"(, "seed": -1})"),
               Catch::Contains("$.seed: expected a whole number from 0 to 18446744073709551615, found -1"));
    CHECK_THAT(error_of("huge.json", head + R"(, "seed": 1e20})"), Catch::Contains("$.seed: expected a whole number from 0"));
    CHECK_THAT(error_of("weak.json", head + R"(, "pack": {"weak_cells": [{"cell": 2.0}, {"cell": 9.0}]}})"),
               Catch::Contains("$.pack.weak_cells[1].cell: expected a whole number in [1, 4], found 9.0"));

    // A conductance of 0 is an insulated pack (0 had been replaced by the default); a heat
    // capacity of 0 is no pack at all.
    const Scenario insulated = load_scenario(
        temp.write("cond0.json", head + R"(, "pack": {"conductance_ground_w_per_k": 0, "conductance_flight_w_per_k": 0}})"));
    CHECK(insulated.pack.conductance_ground_w_per_k == 0.0);
    CHECK(insulated.pack.conductance_flight_w_per_k == 0.0);
    CHECK(plain.pack.conductance_flight_w_per_k == Approx(1.6));
    const SimulationResult warm = simulate(insulated), cooled = simulate(plain);
    CHECK(warm.truth.final_temperature_c > cooled.truth.final_temperature_c + 2.0);
    CHECK(scenario_to_json(warm.scenario)["pack"]["conductance_flight_w_per_k"] == 0.0);
    CHECK_THAT(error_of("heat0.json", head + R"(, "pack": {"heat_capacity_j_per_k": 0}})"),
               Catch::Contains("$.pack.heat_capacity_j_per_k: 0 J/K is no thermal mass"));
}
