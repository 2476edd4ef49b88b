// What `replay --config-out` writes (host/report/config_out.h), on hand-made summaries.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <string>

#include "host/config_json.h"
#include "host/config_reader.h"
#include "host/io/json_text.h"
#include "host/report/config_out.h"
#include "test_files.h"

using namespace battsim;
using nlohmann::json;

namespace {
json offset_fault(double offset_a) {
    return json{{"name", "sensor_fault"}, {"cause", json::array({"current_offset"})}, {"current_offset_a", offset_a}};
}
}  // namespace

TEST_CASE("config-out takes the charger check's suggested gain", "[report][config-out]") {
    const host::LoadedConfig filed = host::builtin_config();
    const json summary{{"charger_check", {{"suggested_current_gain", 0.97}}}, {"warnings", json::array()}};
    const host::ConfigCorrections c = host::with_corrections(filed, summary);
    CHECK(c.gain_taken);
    CHECK(c.offset_taken_a == 0.0);
    CHECK(c.found());
    CHECK(c.config.monitor.extensions.current_sensor.gain == 0.97f);
    CHECK(c.config.monitor.extensions.current_sensor.offset_a == filed.monitor.extensions.current_sensor.offset_a);
}

TEST_CASE("config-out takes a learnt offset out of the config's, and both corrections together", "[report][config-out]") {
    host::LoadedConfig filed = host::builtin_config();
    filed.monitor.extensions.current_sensor.offset_a = 0.10f;
    // The estimator learnt 0.25 A on the already corrected current: 0.10 - 0.25 = -0.15 A.
    json summary{{"warnings", json::array({json{{"name", "low_voltage"}}, offset_fault(0.25)})}};
    host::ConfigCorrections c = host::with_corrections(filed, summary);
    CHECK_FALSE(c.gain_taken);
    CHECK(c.offset_taken_a == 0.25);
    CHECK(c.found());
    CHECK(c.config.monitor.extensions.current_sensor.offset_a == Approx(-0.15f));
    CHECK(c.config.monitor.extensions.current_sensor.gain == filed.monitor.extensions.current_sensor.gain);

    summary["charger_check"] = {{"suggested_current_gain", 1.04}};
    c = host::with_corrections(filed, summary);
    CHECK(c.gain_taken);
    CHECK(c.offset_taken_a == 0.25);
    CHECK(c.config.monitor.extensions.current_sensor.gain == 1.04f);
    CHECK(c.config.monitor.extensions.current_sensor.offset_a == Approx(-0.15f));
}

TEST_CASE("config-out finds nothing without a gain or an offset fault, and leaves the summary alone", "[report][config-out]") {
    const host::LoadedConfig filed = host::builtin_config();
    const json none[] = {
        json{{"warnings", json::array()}},                                                     // not checked
        json{{"charger_check", {{"suggested_current_gain", nullptr}}}, {"warnings", json::array()}},  // no gain suggested
        // A sensor fault for another cause than the offset.
        json{{"warnings", json::array({json{{"name", "sensor_fault"}, {"cause", json::array({"current_gain"})},
                                            {"current_offset_a", 0.3}}})}},
    };
    for (const json& summary : none) {
        INFO(summary.dump());
        const std::string before = summary.dump();
        const host::ConfigCorrections c = host::with_corrections(filed, summary);
        CHECK_FALSE(c.found());
        CHECK(host::json_text(host::config_to_json(c.config), 2) == host::json_text(host::config_to_json(filed), 2));
        CHECK(summary.dump() == before);
    }
}

TEST_CASE("config-out writes the file's estimator, not the one --estimator chose for the run", "[report][config-out]") {
    host::LoadedConfig run = host::builtin_config();
    REQUIRE(run.monitor.estimator == core::EstimatorKind::Reference);  // the built-in config's
    run.monitor.estimator = core::EstimatorKind::Joint;                  // as --estimator joint sets it
    CHECK(host::filed_config(run, "", true).monitor.estimator == core::EstimatorKind::Reference);
    CHECK(host::filed_config(run, "", false).monitor.estimator == core::EstimatorKind::Joint);

    // A file that names the joint estimator, run with --estimator reference.
    testsupport::TempDir dir("config-out");
    host::LoadedConfig joint = host::builtin_config();
    joint.monitor.estimator = core::EstimatorKind::Joint;
    const std::string path = dir.write("joint.json", host::json_text(host::config_to_json(joint), 2) + "\n");
    host::LoadedConfig run_reference = host::load_config_file(path);
    REQUIRE(run_reference.monitor.estimator == core::EstimatorKind::Joint);
    run_reference.monitor.estimator = core::EstimatorKind::Reference;
    run_reference.monitor.extensions.current_sensor.gain = 0.9f;  // the rest stays the run's
    const host::LoadedConfig filed = host::filed_config(run_reference, path, true);
    CHECK(filed.monitor.estimator == core::EstimatorKind::Joint);
    CHECK(filed.monitor.extensions.current_sensor.gain == 0.9f);

    dir.write("joint.json", "{");  // changed since the run read it
    CHECK_THROWS_AS(host::filed_config(run_reference, path, true), host::ConfigError);
    CHECK_NOTHROW(host::filed_config(run_reference, path, false));  // not read again without --estimator
}
