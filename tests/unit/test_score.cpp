// The scoreboard: the coulomb-counting baseline by hand, the judging arithmetic with
// columns whose answers are known, the table and JSON, and determinism across threads.
#include <catch2/catch.hpp>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "host/score/coulomb_baseline.h"
#include "host/config_json.h"
#include "host/io/sample_reader.h"
#include "host/score/estimator.h"
#include "host/score/scoreboard.h"
#include "host/sim/scenario.h"
#include "host/sim/simulate.h"
#include "test_files.h"

using namespace battsim;
using namespace battsim::host;
using namespace battsim::host::score;
using nlohmann::json;

namespace {

sim::Scenario scenario(const std::string& name, const std::string& extra_json = "{}") {
    json j = json::parse(R"({
      "schema": "battsim.scenario", "version": 1, "seed": 5, "monitor_config": "embedded",
      "pack": {"cells": 4, "capacity_ah": 1.55},
      "profile": {"kind": "racing", "idle_before_s": 20, "armed_s": 2, "flight_s": 80, "idle_after_s": 5,
                  "mean_power_w": 400}
    })");
    j["name"] = name;
    j.merge_patch(json::parse(extra_json));
    const json cfg = config_to_json(default_config());
    return sim::scenario_from_json(j, name + ".json", "", &cfg);
}

// A column that answers from the truth, with a chosen bias and chosen warnings.
EstimatorColumn known_column(double time_bias_s, double capacity_factor, uint8_t warnings, double warn_at_fraction) {
    EstimatorColumn c;
    c.name = "known";
    c.run = [=](const FlightInput& in) {
        const sim::Truth& t = in.truth->truth;
        std::vector<Estimate> out;
        for (const core::Sample& s : *in.samples) {
            Estimate e;
            e.time_s = s.time_us * 1e-6;
            if (e.time_s >= t.takeoff_s) {
                e.has_remaining_time = true;
                e.remaining_time_s = t.cutoff_s - e.time_s + time_bias_s;
                e.has_capacity = true;
                e.capacity_ah = t.pack_capacity_ah * capacity_factor;
            }
            if (e.time_s >= t.takeoff_s + warn_at_fraction * t.total_flight_time_s) e.warnings = warnings;
            out.push_back(e);
        }
        return out;
    };
    return c;
}

}  // namespace

TEST_CASE("Coulomb baseline: rated capacity, 50 s average current, by hand", "[score][estimate]") {
    host::score::CoulombBaseline b;
    host::score::CoulombBaseline::Config c;
    c.rated_capacity_ah = 1.5f;
    b.configure(c);
    CHECK(b.status().remaining_mah == Approx(1500.0f));
    CHECK_FALSE(b.status().time_valid);
    b.update(0.0f, 0.0f);  // the first sample seeds the average
    CHECK(b.status().average_current_a == 0.0f);
    CHECK_FALSE(b.status().time_valid);
    for (int k = 0; k < 50; ++k) b.update(10.0f, 1.0f);
    // 10 A for 50 s = 138.89 mAh; average 10·(1 − 0.98^50) = 6.3583 A.
    CHECK(b.status().consumed_mah == Approx(138.889f).epsilon(1e-5));
    CHECK(b.status().average_current_a == Approx(10.0 * (1.0 - std::pow(0.98, 50))).epsilon(1e-5));
    CHECK(b.status().remaining_time_s == Approx((1500.0 - 138.889) * 3.6 / 6.35830).epsilon(1e-4));
    CHECK(b.status().soc == Approx((1500.0 - 138.889) / 1500.0).epsilon(1e-5));
    for (int k = 0; k < 3600; ++k) b.update(10.0f, 1.0f);
    CHECK(b.status().remaining_mah == 0.0f);  // never negative
    CHECK(b.status().remaining_time_s == 0.0f);
    b.update(NAN, 1.0f);  // a bad sample changes nothing
    CHECK(b.status().consumed_mah == Approx(10138.9f).epsilon(1e-4));
}

TEST_CASE("Judging: known answers give known errors, hits and false warnings", "[score]") {
    sim::SimulateOptions so;
    so.keep_snapshots = true;
    const sim::SimulationResult aged = sim::simulate(scenario("aged", R"({"pack": {"capacity_factor": 0.65}})"), so);
    REQUIRE(aged.truth.short_flight());
    // The samples as the reader would give them: one per logged row, at the row's time.
    std::vector<core::Sample> samples;
    for (const sim::RowSnapshot& r : aged.snapshots) {
        core::Sample s;
        s.time_us = static_cast<uint64_t>(r.time_ms) * 1000u;
        samples.push_back(s);
    }
    const uint8_t low_cap = 1u << core::kWarnLowCapacity, high_r = 1u << core::kWarnHighResistance;
    const double total = aged.truth.total_flight_time_s;
    const FlightScore f = score_flight(aged, samples,
                                       {known_column(0.0, 1.0, low_cap, 0.1), known_column(0.05 * total, 1.1, high_r, 0.1),
                                        known_column(0.0, 1.0, low_cap, 0.3)});
    REQUIRE(f.columns.size() == 3);
    const ColumnFlight& exact = f.columns[0];
    for (int p = 0; p < 3; ++p) {
        if (!exact.has_rt[p]) continue;  // past the landing
        CHECK(exact.rt_err_pct[p] == Approx(0.0).margin(1e-9));
    }
    CHECK(exact.has_rt[0]);
    CHECK(exact.has_rt[1]);
    CHECK(exact.cap_err20_pct == Approx(0.0).margin(1e-9));
    CHECK_FALSE(exact.has_res20);
    CHECK(exact.warned_in_time);
    CHECK(exact.false_warnings.empty());
    const ColumnFlight& biased = f.columns[1];
    CHECK(biased.rt_err_pct[1] == Approx(5.0).epsilon(1e-9));
    CHECK(biased.cap_err20_pct == Approx(10.0).epsilon(1e-9));
    CHECK_FALSE(biased.warned_in_time);  // the wrong cause
    CHECK(biased.false_warnings == std::vector<std::string>{"high_resistance"});
    CHECK_FALSE(f.columns[2].warned_in_time);  // the right cause, too late
    CHECK(f.columns[2].first_warning_s[core::kWarnLowCapacity] == Approx(0.3 * total).margin(0.4));
}

TEST_CASE("Scoreboard: table and JSON, every column; the same output on any thread count", "[score]") {
    const std::vector<sim::Scenario> suite = {
        scenario("healthy"),
        scenario("aged", R"({"pack": {"capacity_factor": 0.7}, "seed": 6})"),
        scenario("weak", R"({"pack": {"weak_cells": [{"cell": 2, "capacity_factor": 0.7}]}, "seed": 7})"),
        scenario("fault", R"({"sensor": {"faults": {"loose_tap": 1}}, "seed": 8})"),
    };
    const std::vector<EstimatorColumn> cols = standard_columns();
    ScoreOptions one, three;
    one.jobs = 1;
    three.jobs = 3;
    const ScoreResult a = score_scenarios(suite, cols, one);
    const ScoreResult b = score_scenarios(suite, cols, three);
    const json ja = to_json(a);
    CHECK(ja.dump() == to_json(b).dump());
    CHECK(format_table(a) == format_table(b));

    REQUIRE(ja["flights"].size() == 4);
    CHECK(ja["schema"] == kScoreSchema);
    std::vector<std::string> names;
    for (const auto& c : ja["columns"]) names.push_back(c["name"]);
    CHECK(names.size() >= 3);
    CHECK(names[0] == "reference");
    CHECK(names[1] == "baseline");
    CHECK(names[2] == "oracle");
    for (const char* key : {"remaining_time_10", "remaining_time_20", "remaining_time_20_above_oracle", "remaining_time_50", "remaining_energy_20", "capacity_20",
                            "capacity_end", "resistance_20", "resistance_end", "early_warnings", "false_warnings",
                            "cell_outlier_true_positives", "cell_outlier_false_positives", "sensor_faults_flagged",
                            "sensor_faults_blamed_on_cells"}) {
        INFO(key);
        REQUIRE(ja["summary"].contains(key));
        for (const std::string& n : names) CHECK(ja["summary"][key].contains(n));
    }
    // The oracle knows the pack: its capacity and resistance are exact, its warnings right.
    CHECK(ja["summary"]["capacity_20"]["oracle"]["median_abs"] == 0.0);
    CHECK(ja["summary"]["resistance_end"]["oracle"]["worst"] == 0.0);
    CHECK(ja["summary"]["early_warnings"]["oracle"]["count"] == ja["summary"]["early_warnings"]["oracle"]["of"]);
    CHECK(ja["summary"]["early_warnings"]["oracle"]["of"] == 2);  // aged and weak are short
    // The baseline estimates no resistance and never warns.
    CHECK(ja["summary"]["resistance_20"]["baseline"]["median_abs"].is_null());
    CHECK(ja["summary"]["false_warnings"]["baseline"]["count"] == 0);
    CHECK(ja["summary"]["remaining_time_20"]["reference"]["n"] == 4);
    CHECK(ja["summary"]["remaining_time_20_above_oracle"]["oracle"]["median"] == 0.0);

    // The text table: a header naming every column, then one line per metric.
    const std::string table = format_table(a);
    std::stringstream in(table);
    std::string title, header, line;
    std::getline(in, title);
    std::getline(in, header);
    CHECK(title.find("4 flights") != std::string::npos);
    for (const std::string& n : names) CHECK(header.find(n) != std::string::npos);
    int lines = 0;
    while (std::getline(in, line)) {
        ++lines;
        CHECK(line.size() == header.size());
    }
    CHECK(lines >= 20);
}

TEST_CASE("Scoreboard: reading the logs from files gives the same result as in memory", "[score]") {
    const std::vector<sim::Scenario> suite = {scenario("one"), scenario("two", R"({"pack": {"cells": 4}, "seed": 9})")};
    const testsupport::TempDir temp("score");
    const std::string dir = temp.path();
    for (const sim::Scenario& s : suite) {
        const sim::SimulationResult r = sim::simulate(s);
        sim::write_simulation(r, dir + "/" + s.name + ".csv", dir + "/" + s.name + ".truth.json");
    }
    ScoreOptions mem, files;
    files.logs_dir = dir;
    const std::vector<EstimatorColumn> cols = standard_columns();
    const ScoreResult a = score_scenarios(suite, cols, mem), b = score_scenarios(suite, cols, files);
    CHECK(to_json(a).dump() == to_json(b).dump());
    ScoreOptions missing;
    missing.logs_dir = dir + "/nowhere";
    CHECK_THROWS_AS(score_scenarios(suite, cols, missing), InputError);
}

TEST_CASE("Scoreboard: copies of the suite with other seeds, pooled, with each copy's own figures", "[score]") {
    const std::vector<sim::Scenario> suite = {scenario("healthy"), scenario("aged", R"({"pack": {"capacity_factor": 0.7}, "seed": 6})")};
    const sim::Scenario copy2 = sim::reseeded(suite[1], 2);
    CHECK(copy2.seed == 6u + 2u * 7919u);
    CHECK(copy2.name == "aged@2");
    CHECK(sim::reseeded(suite[1], 0).seed == 6u);
    CHECK(sim::reseeded(suite[1], 0).name == "aged");

    const std::vector<EstimatorColumn> cols = {known_column(0.0, 1.0, 0, 0.0)};
    ScoreOptions opt;
    opt.jobs = 2;
    opt.copies = 3;
    const ScoreResult r = score_scenarios(suite, cols, opt);
    REQUIRE(r.flights.size() == 6);
    const std::vector<std::string> names = {"healthy", "aged", "healthy@1", "aged@1", "healthy@2", "aged@2"};
    for (size_t i = 0; i < names.size(); ++i) {
        CHECK(r.flights[i].name == names[i]);
        CHECK(r.flights[i].copy == static_cast<int>(i / 2));
    }
    // A copy is the reseeded scenario flown on its own; copy 0 is the suite as written.
    const ScoreResult alone = score_scenarios({copy2}, cols, ScoreOptions{});
    const json j = to_json(r);
    CHECK(j["flights"][5]["estimators"].dump() == to_json(alone)["flights"][0]["estimators"].dump());
    CHECK(j["flights"][5]["total_flight_time_s"] == to_json(alone)["flights"][0]["total_flight_time_s"]);
    CHECK(j["flights"][1]["total_flight_time_s"] != j["flights"][3]["total_flight_time_s"]);
    const json once = to_json(score_scenarios(suite, cols, ScoreOptions{}));
    REQUIRE(j["summary_by_copy"].size() == 3);
    CHECK(j["summary_by_copy"][0].dump() == once["summary"].dump());
    CHECK(j["copies"] == 3);
    CHECK_FALSE(once.contains("summary_by_copy"));
    // Pooled counts are the copies' counts added up.
    int of = 0, count = 0;
    for (const json& c : j["summary_by_copy"]) {
        of += c["false_warnings"]["known"]["of"].get<int>();
        count += c["remaining_time_20"]["known"]["n"].get<int>();
    }
    CHECK(j["summary"]["false_warnings"]["known"]["of"] == of);
    CHECK(j["summary"]["remaining_time_20"]["known"]["n"] == count);
    CHECK(of == 6);
    // The table shows the pooled figure, then the copies' range; every line as wide as the header.
    const std::string table = format_table(r);
    CHECK(table.find("3 copies of the suite") != std::string::npos);
    CHECK(table.find("0/6 (0/2..0/2)") != std::string::npos);
    std::stringstream in(table);
    std::string line, header;
    std::getline(in, line);
    std::getline(in, line);
    std::getline(in, header);
    while (std::getline(in, line)) CHECK(line.size() == header.size());

    ScoreOptions bad = opt;
    bad.logs_dir = "/tmp";
    CHECK_THROWS_AS(score_scenarios(suite, cols, bad), std::invalid_argument);
    bad = ScoreOptions{};
    bad.copies = 0;
    CHECK_THROWS_AS(score_scenarios(suite, cols, bad), std::invalid_argument);
}

TEST_CASE("Diagnostic column: the flight-time solve fed the true pack, with and without the cutoff delay", "[score]") {
    // A suite flight with its own config (an OCV table read off the simulated pack, the
    // 5 s delay of the drone's filtered cutoff): the solve with every true parameter reads
    // the energy left at 20 % of the flight within 2 %, and stopping at the crossing reads
    // it low by about the delay's energy (5 s of a ~22 Wh flight's remaining ~17 Wh at
    // ~380 W: 3 %).
    const sim::Scenario s =
        sim::load_scenario(std::string(BATTSIM_SOURCE_DIR) + "/configs/scenarios/4s-racing-healthy-a.json");
    REQUIRE(s.config.monitor.joint.cutoff_delay_s == 5.0f);
    REQUIRE(s.cutoff_filter_s == 5.0);
    const std::vector<EstimatorColumn> cols = {solve_truth_column()};
    const ScoreResult with = score_scenarios({s}, cols, ScoreOptions{});
    REQUIRE(with.flights.size() == 1);
    const ColumnFlight& w = with.flights[0].columns[0];
    REQUIRE(w.has_energy20);
    CHECK(std::fabs(w.energy_err20_pct) < 2.0);
    CHECK(w.has_rt[1]);

    sim::Scenario s0 = s;
    s0.config.monitor.joint.cutoff_delay_s = 0.0f;
    const ScoreResult without = score_scenarios({s0}, cols, ScoreOptions{});
    const ColumnFlight& n = without.flights[0].columns[0];
    REQUIRE(n.has_energy20);
    CHECK(n.energy_err20_pct < w.energy_err20_pct - 2.0);
    // It is a diagnostic: not among the standard columns.
    for (const EstimatorColumn& c : standard_columns()) CHECK(c.name != "solve-truth");
    REQUIRE(diagnostic_columns().size() == 1);
    CHECK(diagnostic_columns()[0].name == "solve-truth");
}

TEST_CASE("score --columns: the columns named, in order, diagnostics included; a wrong name refused", "[score]") {
    const auto names = [](const std::vector<EstimatorColumn>& cols) {
        std::vector<std::string> n;
        for (const EstimatorColumn& c : cols) n.push_back(c.name);
        return n;
    };
    const std::vector<std::string> standard = {"reference", "baseline", "oracle", "joint"};
    CHECK(names(standard_columns()) == standard);
    CHECK(names(select_columns("")) == standard);
    CHECK(names(select_columns(",")) == standard);  // no name at all
    CHECK(names(select_columns("joint,solve-truth,reference")) == std::vector<std::string>{"joint", "solve-truth", "reference"});
    CHECK(names(select_columns(",oracle,")) == std::vector<std::string>{"oracle"});
    CHECK_THROWS_WITH(select_columns("joint,nonesuch"),
                      "unknown estimator \"nonesuch\"; expected reference, baseline, oracle, joint, solve-truth");
}
