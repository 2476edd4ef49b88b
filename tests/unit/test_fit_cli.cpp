// battsim fit on the command line: outputs, determinism, evaluation-only runs and the
// documented exit codes.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "host/config_json.h"
#include "test_fit_synthetic.h"

namespace {
int run(const std::string& args) {
    const int status = std::system((std::string(BATTSIM_BINARY) + " fit " + args + " > /dev/null 2>&1").c_str());
    return WEXITSTATUS(status);
}
const std::string kConfig = std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json";
}  // namespace

TEST_CASE("battsim fit writes a loadable config, byte-identical on a rerun", "[fit][cli]") {
    synth::Options o;
    o.rc_resistance_ohm = 0.01;
    o.rc_time_constant_s = 4;
    o.flight_s = 120;
    o.seed = 31;
    const std::string log = synth::write_log("cli-fit", o);
    // The held-out log is another flight of the same pack (the fitted one itself is refused).
    o.seed = 32;
    const std::string held_out = synth::write_log("cli-fit-test", o);
    const std::string out1 = log + ".1.json", out2 = log + ".2.json", report = log + ".report.json", png = log + ".png";
    const std::string args = log + " -c " + kConfig + " --add rc --test " + held_out + " --plot " + png + " --report " + report + " -o ";
    REQUIRE(run(args + out1) == 0);
    REQUIRE(run(args + out2) == 0);
    CHECK(testsupport::read_file(out1) == testsupport::read_file(out2));
    const battsim::host::LoadedConfig c = battsim::host::load_config_file(out1);
    CHECK(c.monitor.extensions.rc_count == 1);
    CHECK(c.monitor.extensions.rc[0].time_constant_s == Approx(4.0).epsilon(0.2));
    std::ifstream rin(report);
    const nlohmann::json r = nlohmann::json::parse(rin);
    CHECK(r["schema"] == "battsim.fit");
    CHECK(r["rmse_v"].get<double>() < 0.004);
    CHECK(r["test"][0]["monitor"]["all"]["rmse_v"].get<double>() < 0.01);
    bool have_sigma = false;
    for (const auto& p : r["parameters"]) {
        if (p["name"] == "rc1_tau") have_sigma = p["sigma"].is_number() && p["sigma"].get<double>() > 0;
    }
    CHECK(have_sigma);
    CHECK(testsupport::read_file(png).compare(1, 3, "PNG") == 0);
    // Evaluation only: nothing fitted, the config's own errors reported.
    REQUIRE(run(log + " -c " + out1 + " --params none --initial monitor --report " + report) == 0);
    std::ifstream ein(report);
    const nlohmann::json e = nlohmann::json::parse(ein);
    CHECK(e["parameters"].empty());
    CHECK(e["logs"][0]["monitor"]["all"]["rmse_v"] == e["start_monitor"][0]["all"]["rmse_v"]);
    for (const std::string& f : {log, held_out, out1, out2, report, png}) std::remove(f.c_str());
}

TEST_CASE("battsim fit says when it did not settle, and what to try", "[fit][cli]") {
    synth::Options o;
    o.rc_resistance_ohm = 0.01;
    o.rc_time_constant_s = 4;
    o.flight_s = 60;
    o.seed = 5;
    const std::string log = synth::write_log("cli-unsettled", o);
    const auto r = testsupport::run_program(BATTSIM_BINARY, "fit " + log + " -c " + kConfig + " --add rc --max-iterations 1");
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.out, Catch::Contains("not settled: the iteration limit (1, --max-iterations) was reached"));
    CHECK_THAT(r.out, Catch::Contains("--initial zero"));  // --initial free is the default
    const auto settled = testsupport::run_program(BATTSIM_BINARY, "fit " + log + " -c " + kConfig + " --params none");
    CHECK_THAT(settled.out, !Catch::Contains("not settled"));
    std::remove(log.c_str());
}

TEST_CASE("battsim fit names the parameters its logs barely determine", "[fit][cli]") {
    // 20 s of flight: a 1.55 Ah pack's capacity cannot be read off 0.1 Ah drawn on the curve's
    // flat part ("q = 0.031 ± 0.020 Ah" on 20 rows of a 3 Ah cell had passed without a word).
    synth::Options o;
    o.rest_s = 5;
    o.flight_s = 20;
    o.after_s = 0;
    o.seed = 7;
    const std::string log = synth::write_log("cli-loose", o);
    const auto r = testsupport::run_program(BATTSIM_BINARY, "fit " + log + " -c " + kConfig);
    CHECK(r.exit_code == 0);
    INFO(r.out);
    CHECK_THAT(r.out, Catch::Contains("barely determined by these logs (standard error over a third of the value):"));
    // A long flight determines them.
    o.rest_s = 20;
    o.flight_s = 240;
    o.after_s = 30;
    const std::string full = synth::write_log("cli-determined", o);
    const auto f = testsupport::run_program(BATTSIM_BINARY, "fit " + full + " -c " + kConfig);
    INFO(f.out);
    CHECK_THAT(f.out, !Catch::Contains("barely determined"));
    std::remove(log.c_str());
    std::remove(full.c_str());
}

TEST_CASE("battsim fit --starts reports every start, the same whatever -j", "[fit][cli]") {
    // A short flight: five starts, each in the report.
    synth::Options o;
    o.rest_s = 5;
    o.flight_s = 20;
    o.after_s = 0;
    o.seed = 7;
    const std::string log = synth::write_log("cli-starts", o);
    const std::string args = "fit " + log + " -c " + kConfig + " --starts 5";
    const auto a = testsupport::run_program(BATTSIM_BINARY, args + " --json -j 1");
    const auto b = testsupport::run_program(BATTSIM_BINARY, args + " --json -j 2");
    REQUIRE(a.exit_code == 0);
    CHECK(a.out == b.out);
    const nlohmann::json r = nlohmann::json::parse(a.out);
    CHECK(r["options"]["starts"] == 5);
    REQUIRE(r["solver"]["starts"].size() == 5);
    const int best = r["solver"]["best_start"].get<int>();
    CHECK(r["solver"]["starts"][best]["cost_ratio"] == 1.0);
    CHECK(r["solver"]["near_best"].get<int>() >= 1);
    for (const auto& p : r["parameters"]) {
        INFO(p.dump());
        REQUIRE(p.contains("near_best_range"));
        CHECK(p["near_best_range"][0].get<double>() <= p["value"].get<double>());
        CHECK(p["value"].get<double>() <= p["near_best_range"][1].get<double>());
    }
    const auto text = testsupport::run_program(BATTSIM_BINARY, args);
    INFO(text.out);
    CHECK_THAT(text.out, Catch::Contains("5 starts: the best from start " + std::to_string(best) +
                                         (best == 0 ? " (the config's values); " : " (start 0, the config's values, ended ")));
    // One start (the default): no multi-start report.
    const auto one = testsupport::run_program(BATTSIM_BINARY, "fit " + log + " -c " + kConfig + " --json");
    CHECK_FALSE(nlohmann::json::parse(one.out)["solver"].contains("starts"));
    CHECK(testsupport::run_program(BATTSIM_BINARY, args.substr(0, args.size() - 1) + "0").exit_code == 2);
    std::remove(log.c_str());
}

TEST_CASE("battsim fit exit codes", "[fit][cli]") {
    synth::Options o;
    o.flight_s = 30;
    const std::string log = synth::write_log("cli-exit", o);
    CHECK(run("/nonexistent.csv") == 3);
    CHECK(run(log + " -c /nonexistent.json") == 4);
    CHECK(run(log + " --params e0,resistance") == 2);
    CHECK(run(log + " --initial guess") == 2);
    CHECK(run(log + " --add warp") == 2);
    CHECK(run(log + " --per-log r -o /tmp/x.json") == 2);  // per-log parameters need --output-dir
    // Said before any log is read: a log that cannot be read (exit 3) is not reached.
    CHECK(run("/nonexistent.csv --per-log r -o /tmp/x.json") == 2);
    CHECK(run("/nonexistent.csv --per-log r --test " + log) == 2);
    CHECK(run(log + " -o /nonexistent-dir/out.json") == 5);
    std::remove(log.c_str());
}
