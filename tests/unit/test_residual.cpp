// Residual tracing on logs with an effect the config does not declare: it must be named
// and must cut the error by more than half; on a log with nothing to find, nothing is added.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "host/residual/residual.h"
#include "test_fit_synthetic.h"

using namespace battsim::host;
using namespace battsim::host::fit;
using namespace battsim::host::residual;

namespace {
ResidualReport run(const synth::Options& o, const std::string& name, const ResidualOptions& ro = ResidualOptions{}) {
    const std::string path = synth::write_log(name, o);
    const LoadedConfig config = default_config();  // the modified reference set: no extensions
    const std::vector<Trace> traces = {load_trace(path, ReaderOptions{}, config)};
    std::remove(path.c_str());
    return analyse(traces, spec_from_config(config), ro);
}
}  // namespace

TEST_CASE("An undeclared RC branch is named and removed", "[residual]") {
    synth::Options o;
    o.rc_resistance_ohm = 0.015;
    o.rc_time_constant_s = 6;
    o.seed = 21;
    const ResidualReport r = run(o, "rc");
    REQUIRE_FALSE(r.effects.empty());
    CHECK(r.effects[0] == "rc_polarisation");
    const double before = r.before[0].monitor_all.rmse_v;
    const double after = r.after[0].fit_all.rmse_v;
    INFO("RMSE before " << before << " V, after " << after << " V");
    CHECK(after < 0.5 * before);
    CHECK(r.after[0].monitor_all.rmse_v < 0.5 * before);  // also as the monitor would run it
    // The branch found is the one generated.
    const battsim::core::RcBranch& b = r.final_specs[0].ext.rc[0];
    CHECK(b.time_constant_s == Approx(6.0).epsilon(0.25));
    CHECK(b.resistance_ohm == Approx(0.015).epsilon(0.25));
}

TEST_CASE("An undeclared current-sensor gain is named when the pack model is trusted", "[residual]") {
    // The pack is exactly the config's; the logged current reads 8 % high. With the pack's
    // parameters held (measured elsewhere, e.g. by a slow discharge), only the sensor can
    // explain the misfit.
    synth::Options o;
    o.sensor_gain = 1.08;
    o.flight_s = 150;
    o.seed = 22;
    ResidualOptions ro;
    ro.fixed = {"e0", "r", "kappa", "a", "b", "q"};
    const ResidualReport r = run(o, "gain", ro);
    REQUIRE_FALSE(r.effects.empty());
    CHECK(r.effects[0] == "current_sensor");
    CHECK(r.after[0].fit_all.rmse_v < 0.5 * r.before[0].monitor_all.rmse_v);
    CHECK(r.final_specs[0].ext.current_sensor.gain == Approx(1.0 / 1.08).epsilon(0.01));
}

TEST_CASE("A gain error the parameters can absorb is not reported as an effect", "[residual]") {
    // Tremblay's model in the logged current i' = g·i is again a Tremblay model (R' = R/g,
    // K' = K/g, Q' = g·Q, B' = B/g): with the parameters free, a pure gain error is not
    // identifiable, and the residual must not claim it.
    synth::Options o;
    o.sensor_gain = 1.08;
    o.flight_s = 150;
    o.seed = 22;
    const ResidualReport r = run(o, "gain-free", ResidualOptions{});
    CHECK(r.stages[1].name == "parameters");
    CHECK(r.stages[1].stats.all.rmse_v < 0.005);  // the refit alone leaves quantisation noise
    CHECK(r.effects.empty());
}

TEST_CASE("Nothing is invented when the residual is noise", "[residual]") {
    synth::Options o;
    o.noise_v = 0.004;
    o.seed = 23;
    const ResidualReport r = run(o, "clean");
    CHECK(r.effects.empty());
    CHECK_THAT(r.verdict, Catch::StartsWith("No candidate effect explains the residual"));
    // The structure is reported: close to white, about the generated noise.
    CHECK(std::fabs(r.structure_after.acf[0]) < 0.2);
    CHECK(r.structure_after.sd_v == Approx(0.0055).margin(0.002));  // noise + 10 mV quantisation
    CHECK(r.structure_after.histogram_counts.size() == 15);
}

TEST_CASE("With --max-effects 0 the verdict says no effect was tried, not that none explains the residual",
          "[residual]") {
    synth::Options o;
    o.rc_resistance_ohm = 0.015;  // an effect there to find, had anything looked
    o.rc_time_constant_s = 6;
    o.flight_s = 60;
    o.seed = 25;
    ResidualOptions ro;
    ro.max_effects = 0;
    const ResidualReport r = run(o, "none-tried", ro);
    CHECK(r.effects.empty());
    CHECK_THAT(r.verdict, Catch::StartsWith("No effect was tried (--max-effects 0): the parameters were only refitted"));
    CHECK_THAT(r.verdict, !Catch::Contains("No candidate effect explains") && !Catch::Contains("the candidates do not capture"));
}

TEST_CASE("A candidate with more parameters than a short log has samples is not applicable, not an abort",
          "[residual]") {
    // 2.5 s at 10 Hz: the shape correction's many parameters exceed the fitting samples. It
    // had aborted the whole run (exit 2) after the config and parameter stages were done.
    synth::Options o;
    o.rest_s = 1.0;
    o.flight_s = 1.5;
    o.after_s = 0.0;
    o.noise_v = 0.004;
    const ResidualReport r = run(o, "short");
    REQUIRE_FALSE(r.stages.empty());
    bool seen = false;
    for (const CandidateScore& c : r.stages.back().candidates) {
        if (c.name != "soc_shape") continue;
        seen = true;
        CHECK_FALSE(c.applicable);
        CHECK_THAT(c.note, Catch::Contains("parameters: too few"));
        CHECK(c.note.find("--params") == std::string::npos);  // fit's option, not residual's
    }
    CHECK(seen);
}

TEST_CASE("battsim residual names the undeclared effect on the command line", "[residual][cli]") {
    synth::Options o;
    o.rc_resistance_ohm = 0.012;
    o.rc_time_constant_s = 3;
    o.seed = 24;
    const std::string path = synth::write_log("cli", o);
    const std::string report = path + ".json";
    const std::string cmd = std::string(BATTSIM_BINARY) + " residual " + path + " -c " + BATTSIM_SOURCE_DIR +
                            "/configs/reference-modified.json --report " + report + " -j ";
    // The candidates judged one at a time or side by side: the same report.
    REQUIRE(std::system((cmd + "2 > /dev/null 2>&1").c_str()) == 0);
    const std::string side_by_side = testsupport::read_file(report);
    REQUIRE(std::system((cmd + "1 > /dev/null 2>&1").c_str()) == 0);
    CHECK(testsupport::read_file(report) == side_by_side);
    std::ifstream in(report);
    const nlohmann::json j = nlohmann::json::parse(in);
    REQUIRE_FALSE(j["effects"].empty());
    CHECK(j["effects"][0] == "rc_polarisation");
    const double before = j["per_log"][0]["before"]["all"]["rmse_v"];
    const double after = j["per_log"][0]["after"]["all"]["rmse_v"];
    CHECK(after < 0.5 * before);
    CHECK(j["schema"] == "battsim.residual");
    CHECK(j["options"]["starts"] == 1);
    // Every refit from three starts finds the same effect, and fits no worse.
    const std::string many = std::string(BATTSIM_BINARY) + " residual " + path + " -c " + BATTSIM_SOURCE_DIR +
                             "/configs/reference-modified.json --starts 3 -j 2 --report " + report + " > /dev/null 2>&1";
    REQUIRE(std::system(many.c_str()) == 0);
    std::ifstream in3(report);
    const nlohmann::json j3 = nlohmann::json::parse(in3);
    std::remove(path.c_str());
    std::remove(report.c_str());
    CHECK(j3["options"]["starts"] == 3);
    REQUIRE_FALSE(j3["effects"].empty());
    CHECK(j3["effects"][0] == "rc_polarisation");
    CHECK(j3["per_log"][0]["after"]["all"]["rmse_v"].get<double>() <= after * 1.001);
}

TEST_CASE("battsim residual rejects bad input with the documented exit codes", "[residual][cli]") {
    const std::string bin = BATTSIM_BINARY;
    CHECK(WEXITSTATUS(std::system((bin + " residual /nonexistent.csv > /dev/null 2>&1").c_str())) == 3);
    CHECK(WEXITSTATUS(std::system((bin + " residual /dev/null -c /nonexistent.json > /dev/null 2>&1").c_str())) == 4);
    synth::Options o;
    o.flight_s = 20;
    const std::string path = synth::write_log("cli-bad", o);
    CHECK(WEXITSTATUS(std::system((bin + " residual " + path + " --candidates rcx > /dev/null 2>&1").c_str())) == 2);
    CHECK(WEXITSTATUS(std::system((bin + " residual " + path + " --blocks 3 > /dev/null 2>&1").c_str())) == 2);
    std::remove(path.c_str());
}
