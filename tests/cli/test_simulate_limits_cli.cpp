// battsim simulate and score at the edges of what a scenario may say: one cell, more cells
// than the reference sensors read, a pack without resistance, a thermal step that would run
// away, a healthy twin that outlasts the continuation, a cutoff of 0, a log that cannot be
// read back. Each either runs or is refused naming the scenario and the key.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "cli_util.h"

using clitest::q;
using clitest::run;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;

// A hover scenario in `dir` for `cells` cells (with a made config for them) and `extra` keys.
std::string scenario(const std::string& dir, const std::string& name, int cells, nlohmann::json extra = nlohmann::json::object(),
                     const std::string& config_dir = "") {
    const std::string cfg = (config_dir.empty() ? dir : config_dir) + "/" + name + "-config.json";
    const auto made = run("make-config --cells " + std::to_string(cells) + " --capacity-mah 1550 -o " + q(cfg));
    INFO(made.err);
    REQUIRE(made.exit_code == 0);
    nlohmann::json s = {{"schema", "battsim.scenario"}, {"version", 1}, {"name", name}, {"seed", 7},
                        {"monitor_config", cfg},
                        {"pack", {{"cells", cells}, {"capacity_ah", 1.55}}},
                        {"profile", {{"kind", "hover"}, {"idle_before_s", 20}, {"flight_s", 120}, {"idle_after_s", 10}}}};
    s.merge_patch(extra);
    const std::string path = dir + "/" + name + ".json";
    clitest::write_file(path, s.dump(2));
    return path;
}
}  // namespace

TEST_CASE("simulate: one cell flies; more than the sensors read, no resistance and a runaway step are refused", "[cli][sim]") {
    const std::string dir = clitest::temp_dir();
    // One cell: no other cells to differ from (it had crashed on an empty median).
    const auto one = run("simulate " + q(scenario(dir, "one", 1)) + " -o " + q(dir + "/one.csv"));
    INFO(one.err);
    CHECK(one.exit_code == 0);
    const auto truth = nlohmann::json::parse(clitest::read_file(dir + "/one.truth.json"));
    CHECK(truth["sensor"]["current_clipped_reads"] == 0);

    const auto refused = [&](const std::string& path, const std::string& says) {
        const auto r = run("simulate " + q(path) + " -o " + q(dir + "/x.csv"));
        INFO(r.err);
        CHECK(r.exit_code == 4);
        CHECK_THAT(r.err, Catch::Contains(says));
    };
    // Nine cells read 37.8 V, within the bus, but the eighth tap reads 33.6 V: it would clip.
    refused(scenario(dir, "nine", 9), "$.pack.cells: 9 cells read up to 37.8");
    refused(scenario(dir, "nine", 9), "at most 8 cells");
    refused(scenario(dir, "r0", 4, {{"pack", {{"r0_ohm", 0}}}}), "$.pack.r0_ohm: expected a number in [");
    refused(scenario(dir, "hot", 4, {{"pack", {{"heat_capacity_j_per_k", 0.002}}}}),
            "$.pack.heat_capacity_j_per_k: the pack's thermal time constant");
    // A hover at 12 W on a pack of 30 % capacity: the healthy twin flies far past the hour of
    // continuation, so how short this flight is cannot be known (it had been counted "not short").
    refused(scenario(dir, "twin", 4, {{"pack", {{"capacity_factor", 0.3}}}, {"profile", {{"mean_power_w", 12}}}}),
            "the healthy twin pack did not reach its cutoff");
    // A cutoff of 0 V per cell is no cutoff (it had passed as "not given").
    const auto zero = run("simulate " + q(scenario(dir, "z", 4)) + " -o " + q(dir + "/z.csv") + " --cutoff-v-per-cell 0");
    CHECK(zero.exit_code == 2);
    CHECK_THAT(zero.err, Catch::Contains("--cutoff-v-per-cell: expected a number in [2, 4.5], found 0"));
    // Nor is "nan" (NaN is the option's unset value: it had read as not given).
    const auto nan = run("simulate " + q(scenario(dir, "z", 4)) + " -o " + q(dir + "/z.csv") + " --cutoff-v-per-cell nan");
    CHECK(nan.exit_code == 2);
    CHECK_THAT(nan.err, Catch::Contains("--cutoff-v-per-cell: expected a number in [2, 4.5], found nan"));
}

TEST_CASE("score names the scenario whose simulated log cannot be read back", "[cli][sim]") {
    const std::string dir = clitest::temp_dir();
    const std::string suite = dir + "/suite";
    std::filesystem::create_directory(suite);
    // The sensor's first read after the whole flight: an empty log.
    scenario(suite, "late", 4, {{"sensor", {{"first_read_ms", 600000}}}}, dir);  // its config beside, not in, the suite
    const auto r = run("score " + q(suite));
    CHECK(r.exit_code != 0);
    CHECK_THAT(r.err, Catch::Contains("scenario late: its simulated log cannot be read back"));
    CHECK(r.err.find("/battsim-score-") == std::string::npos);
}

TEST_CASE("simulate and replay say when a small craft's ground idle reads as flight", "[cli][sim]") {
    // A 1S 300 mAh whoop on its make-config config: the scenario's default idle (5 W, 1.2 A)
    // is above the config's 0.81 A take-off current, and the replay had read the 20 s on the
    // ground, a 240 s hop and 30 s after it as one flight "still flying", without a word.
    const std::string dir = clitest::temp_dir();
    const std::string cfg = dir + "/whoop-config.json";
    REQUIRE(run("make-config --cells 1 --capacity-mah 300 -o " + q(cfg)).exit_code == 0);
    const auto whoop = [&](const std::string& name, double idle_w) {
        nlohmann::json s = {{"schema", "battsim.scenario"}, {"version", 1}, {"name", name}, {"seed", 7},
                            {"monitor_config", cfg}, {"pack", {{"cells", 1}, {"capacity_ah", 0.3}}},
                            {"profile", {{"kind", "hover"}, {"idle_before_s", 20}, {"flight_s", 60}, {"idle_after_s", 20}}}};
        if (idle_w > 0) s["profile"]["idle_power_w"] = idle_w;
        const std::string path = dir + "/" + name + ".json";
        clitest::write_file(path, s.dump(2));
        return path;
    };
    const auto loud = run("simulate " + q(whoop("idle-5w", 0)) + " -o " + q(dir + "/idle-5w.csv"));
    INFO(loud.err);
    REQUIRE(loud.exit_code == 0);
    CHECK_THAT(loud.err, Catch::Contains("note: idle-5w: the ground idle draws 1.2"));
    CHECK_THAT(loud.err, Catch::Contains("(monitor.min_flying_current_a 0.811 A)"));
    const auto replayed = clitest::run_json("replay " + q(dir + "/idle-5w.csv") + " -c " + q(cfg) + " --json");
    CHECK_FALSE(replayed["flight"]["landed"].get<bool>());
    bool said = false;
    for (const auto& n : replayed["input"]["notes"])
        said = said || n.get<std::string>().rfind("the flight starts 0.51 s into the log, with no ground before it (take-off "
                                                   "current monitor.min_flying_current_a 0.811 A)", 0) == 0;
    CHECK(said);

    // At 1.5 W on the ground (0.36 A) the ground is ground: neither says anything, and the
    // replay sees the landing.
    const auto quiet = run("simulate " + q(whoop("idle-1w5", 1.5)) + " -o " + q(dir + "/idle-1w5.csv"));
    INFO(quiet.err);
    REQUIRE(quiet.exit_code == 0);
    CHECK(quiet.err.find("note:") == std::string::npos);
    const auto landed = clitest::run_json("replay " + q(dir + "/idle-1w5.csv") + " -c " + q(cfg) + " --json");
    CHECK(landed["flight"]["landed"].get<bool>());
    for (const auto& n : landed["input"]["notes"]) CHECK(n.get<std::string>().find("no ground before it") == std::string::npos);
}

TEST_CASE("the bundled example and its truth are what simulate writes today", "[cli]") {
    // The truth file embeds the monitor's config; it had kept a glitch floor of 1.0 V after the
    // reader's default became 2.0 V per cell, while the log itself still matched.
    const std::string dir = clitest::temp_dir();
    const clitest::Result r = clitest::run("simulate " + clitest::q(kSource + "/configs/scenarios/4s-racing-healthy-a.json") + " -o " +
                                           clitest::q(dir + "/example-4s.csv"));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(clitest::read_file(dir + "/example-4s.csv") == clitest::read_file(kSource + "/logs/example-4s.csv"));
    CHECK(clitest::read_file(dir + "/example-4s.truth.json") == clitest::read_file(kSource + "/logs/example-4s.truth.json"));
}

TEST_CASE("simulate records a cell run past empty and says so", "[cli][sim]") {
    const std::string dir = clitest::temp_dir();
    // A cell at 30 % capacity in a 400 s hover: the pack's cutoff comes after that cell is
    // empty (its log had read 1.35 V with nothing said).
    const auto weak = run("simulate " +
                          q(scenario(dir, "weak", 4, {{"pack", {{"weak_cells", {{{"cell", 2}, {"capacity_factor", 0.3}}}}}},
                                                      {"profile", {{"flight_s", 400}}}})) +
                          " -o " + q(dir + "/weak.csv"));
    INFO(weak.err);
    REQUIRE(weak.exit_code == 0);
    CHECK_THAT(weak.err, Catch::Contains("note: weak: cell 2 passed 0 % state of charge at "));
    const auto wt = nlohmann::json::parse(clitest::read_file(dir + "/weak.truth.json"))["flight"];
    CHECK(wt["empty_cell"] == 2);
    CHECK(wt["lowest_cell_soc"].get<double>() < 0.0);
    CHECK(wt["cell_empty_s"].get<double>() > wt["takeoff_s"].get<double>());
    CHECK(wt["cell_empty_s"].get<double>() < wt["log_end_s"].get<double>());
    // A healthy pack: nothing said, nothing empty.
    const auto healthy = run("simulate " + q(scenario(dir, "healthy", 4)) + " -o " + q(dir + "/healthy.csv"));
    REQUIRE(healthy.exit_code == 0);
    CHECK(healthy.err.find("state of charge") == std::string::npos);
    const auto ht = nlohmann::json::parse(clitest::read_file(dir + "/healthy.truth.json"))["flight"];
    CHECK(ht["empty_cell"].is_null());
    CHECK(ht["cell_empty_s"].is_null());
    CHECK(ht["lowest_cell_soc"].get<double>() > 0.0);
    CHECK(ht["lowest_cell_soc_at_cutoff"].get<double>() < ht["lowest_cell_soc"].get<double>());
}

TEST_CASE("simulate and score say when the flight draws below the take-off current", "[cli][sim]") {
    const std::string dir = clitest::temp_dir();
    const std::string path = scenario(dir, "low", 4, {{"profile", {{"mean_power_w", 10}}}, {"truth", {{"max_continuation_s", 36000}}}});
    const auto sim = run("simulate " + q(path) + " -o " + q(dir + "/low.csv"));
    INFO(sim.err);
    REQUIRE(sim.exit_code == 0);
    CHECK_THAT(sim.err, Catch::Contains("note: low: the flight draws "));
    CHECK_THAT(sim.err, Catch::Contains("below the monitor config's take-off current (monitor.min_flying_current_a"));
    const auto score = clitest::run_json("score " + q(path) + " --columns oracle --json");
    bool said = false;
    for (const auto& n : score["flights"][0]["notes"]) said |= n.get<std::string>().find("the flight draws ") == 0;
    CHECK(said);
    // At the scenario's default power the flight reads as flight: nothing said.
    const auto normal = run("simulate " + q(scenario(dir, "normal", 4)) + " -o " + q(dir + "/normal.csv"));
    REQUIRE(normal.exit_code == 0);
    CHECK(normal.err.find("the flight draws") == std::string::npos);
}

TEST_CASE("score names every flight-fraction point a short flight leaves out", "[cli][score]") {
    const std::string dir = clitest::temp_dir();
    const auto notes_of = [&](const std::string& name, double flight_s) {
        const std::string path = scenario(dir, name, 4, {{"profile", {{"flight_s", flight_s}}}});
        const auto j = clitest::run_json("score " + q(path) + " --columns oracle --json");
        std::string all;
        for (const auto& n : j["flights"][0]["notes"]) all += n.get<std::string>() + "\n";
        return all;
    };
    // The hover pack flies 586 s to its cutoff: 15 s is before 10 % (the note had named only
    // the 50 % point), 90 s before 20 %, 200 s before 50 %.
    CHECK_THAT(notes_of("f15", 15), Catch::Contains("landed before 10 % of the flight: the 10 %, 20 % and 50 % points are left out"));
    CHECK_THAT(notes_of("f90", 90), Catch::Contains("landed before 20 % of the flight: the 20 % and 50 % points are left out"));
    CHECK_THAT(notes_of("f200", 200), Catch::Contains("landed before 50 % of the flight: the 50 % point is left out"));
}

TEST_CASE("simulate says a log interval only the edgetx format uses is ignored", "[cli][sim]") {
    const std::string dir = clitest::temp_dir();
    const std::string path = scenario(dir, "iv", 4, {{"log", {{"interval_s", 0.5}}}});
    const auto raw = run("simulate " + q(path) + " -o " + q(dir + "/iv.csv"));
    INFO(raw.err);
    REQUIRE(raw.exit_code == 0);
    CHECK_THAT(raw.err, Catch::Contains("note: iv: log.interval_s (0.5 s) is the edgetx radio log's interval; the raw log ignores it"));
    CHECK_FALSE(nlohmann::json::parse(clitest::read_file(dir + "/iv.truth.json"))["scenario"]["log"].contains("interval_s"));
    const auto radio = run("simulate " + q(path) + " --format edgetx -o " + q(dir + "/iv-radio.csv"));
    REQUIRE(radio.exit_code == 0);
    CHECK(radio.err.find("interval_s") == std::string::npos);
    CHECK(nlohmann::json::parse(clitest::read_file(dir + "/iv-radio.truth.json"))["scenario"]["log"]["interval_s"] == 0.5);
}
