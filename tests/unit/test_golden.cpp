// Golden replays ("change indication"): the shared dissertation flights through the
// monitor must give the committed summaries. A change here is either a bug or an
// intended change of the numbers, regenerated with scripts/update-goldens.sh.
#include <catch2/catch.hpp>

#include <fstream>

#include "host/replay.h"
#include "host/report/json_compare.h"
#include "host/score/estimator.h"
#include "host/score/scoreboard.h"
#include "host/sim/scenario.h"

using namespace battsim::host;

namespace {
std::string golden_diff(const std::string& golden_path, const nlohmann::json& actual, CompareOptions co) {
    std::ifstream in(golden_path);
    if (!in.good()) return "  cannot read " + golden_path + "\n";
    const nlohmann::json golden = nlohmann::json::parse(in);
    co.relative_tolerance = 1e-5;  // 6-significant-digit rounding may flip a last digit
    std::string report;
    for (const auto& d : compare_json(golden, actual, co)) report += "  " + d.path + ": golden " + d.expected + ", now " + d.actual + "\n";
    return report;
}
}  // namespace

// The reference estimator with both parameter sets, and the joint estimator on the
// simulator's table config.
TEST_CASE("Golden summaries of the predictive-bms flights", "[golden][data]") {
    struct Set {
        const char* config;
        const char* golden_dir;
        bool joint;
    };
    const Set sets[] = {{"reference-modified", "predictive-bms-modified", false},
                        {"reference-original", "predictive-bms-original", false},
                        {"sim-4s", "predictive-bms-joint", true}};
    for (const Set& set : sets) {
        ReplayOptions opt;
        opt.config = load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/" + set.config + ".json");
        if (set.joint) opt.config.monitor.estimator = battsim::core::EstimatorKind::Joint;
        for (const char* flight : {"29", "30", "32", "34"}) {
            const nlohmann::json actual =
                replay_log(std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/" + flight + ".csv", opt);
            CompareOptions co;
            co.ignore = {"/input/path", "/battsim_version"};
            const std::string report = golden_diff(
                std::string(BATTSIM_SOURCE_DIR) + "/tests/golden/" + set.golden_dir + "/" + flight + ".json", actual, co);
            INFO(set.golden_dir << ", flight " << flight << " changed:\n" << report);
            CHECK(report.empty());
        }
    }
}

// The scoreboard as change indication: every estimator's numbers on both simulated suites,
// the last-cell set (a weak cell read across the positive lead), the rest-polarisation
// stress suite (the real packs' polarisation time constants), the small craft on make-config's
// packs (1S to 4S, 300 to 850 mAh), the large ones (4S 5 Ah to 8S 22 Ah), the lead-cell set (the
// logger's slower INA3221, a cell high in resistance on either lead) and the tuning suite flown
// through a radio's telemetry log (the reader's wall clock, the 0.1 V steps) and through an
// ArduPilot and a PX4 log (the binary writers and readers, 10 and 5 Hz).
// A change is either a bug or an intended change of the numbers (scripts/update-goldens.sh;
// say in the commit what moved and why).
TEST_CASE("Golden scoreboards of the simulated suites", "[golden]") {
    for (const std::string golden :
         {"scenarios", "scenarios-holdout", "scenarios-last-cell", "scenarios-rest-polarisation", "scenarios-small",
          "scenarios-large", "scenarios-lead-cells", "scenarios-edgetx", "scenarios-dataflash", "scenarios-ulog"}) {
        // scenarios-FORMAT: the tuning suite flown through that log format.
        const std::string format = golden == "scenarios-edgetx" ? "edgetx"
                                   : golden == "scenarios-dataflash" ? "dataflash"
                                   : golden == "scenarios-ulog" ? "ulog"
                                                                  : "";
        const std::string suite = format.empty() ? golden : "scenarios";
        const std::string dir = std::string(BATTSIM_SOURCE_DIR) + "/configs/" + suite;
        std::vector<sim::Scenario> scenarios;
        for (const std::string& f : sim::find_scenario_files({dir})) {
            scenarios.push_back(sim::load_scenario(f));
            if (!format.empty()) scenarios.back().log_format = format;  // as `battsim score --log-format FORMAT`
        }
        score::ScoreOptions so;
        so.jobs = 2;
        const nlohmann::json actual = score::to_json(score::score_scenarios(scenarios, score::standard_columns(), so));
        CompareOptions co;
        co.ignore = {"/battsim_version"};
        const std::string report =
            golden_diff(std::string(BATTSIM_SOURCE_DIR) + "/tests/golden/score/" + golden + ".json", actual, co);
        INFO(golden << " changed:\n" << report);
        CHECK(report.empty());
    }
}

TEST_CASE("Replay is deterministic", "[golden][data]") {
    const std::string log = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/34.csv";
    ReplayOptions opt;
    opt.config = default_config();
    CHECK(replay_log(log, opt).dump() == replay_log(log, opt).dump());
}

TEST_CASE("json_compare reports changed, missing and extra fields", "[golden]") {
    using nlohmann::json;
    json a = {{"x", 1.0}, {"o", {{"y", "s"}, {"z", json::array({1, 2})}}}};
    json b = a;
    CHECK(compare_json(a, b, {}).empty());
    b["x"] = 1.0 + 1e-9;
    CHECK(compare_json(a, b, {}).empty());
    b["x"] = 1.01;
    b["o"]["z"][1] = 3;
    b["extra"] = true;
    b["o"].erase("y");
    auto d = compare_json(a, b, {});
    REQUIRE(d.size() == 4);
    CompareOptions ig;
    ig.ignore = {"/x", "/extra", "/o/y", "/o/z"};
    CHECK(compare_json(a, b, ig).empty());
}
