// The "battery.extensions" config block: round trip, errors that name the key.
#include <catch2/catch.hpp>

#include "host/config_json.h"

using namespace battsim::host;
using nlohmann::json;

namespace {
json with_extensions(const json& ext) {
    json j = config_to_json(default_config());
    j["battery"]["extensions"] = ext;
    return j;
}
}  // namespace

TEST_CASE("Extensions round-trip through the config JSON", "[extension][config]") {
    LoadedConfig c = default_config();
    battsim::core::ModelExtensions& e = c.monitor.extensions;
    e.rc_count = 2;
    e.rc[0] = {0.004f, 1.5f};
    e.rc[1] = {0.01f, 40.0f};
    e.temperature.enabled = true;
    e.temperature.resistance_activation_k = 3100.0f;
    e.temperature.e0_v_per_c = 2e-4f;
    e.thermal.enabled = true;
    e.thermal.ambient_c = 7.0f;
    e.hysteresis.magnitude_v = 0.01f;
    e.ocv.count = 3;
    e.ocv.span_ah = 1.5f;
    e.ocv.delta_v[1] = -0.02f;
    e.current_sensor.gain = 1.02f;
    const json j = config_to_json(c);
    const LoadedConfig back = config_from_json(j, "test");
    CHECK(back.monitor.extensions.rc_count == 2);
    CHECK(back.monitor.extensions.rc[1].time_constant_s == 40.0f);
    CHECK(back.monitor.extensions.temperature.enabled);
    CHECK(back.monitor.extensions.temperature.resistance_activation_k == 3100.0f);
    CHECK(back.monitor.extensions.thermal.ambient_c == 7.0f);
    CHECK(back.monitor.extensions.hysteresis.magnitude_v == 0.01f);
    CHECK(back.monitor.extensions.ocv.count == 3);
    CHECK(back.monitor.extensions.ocv.delta_v[1] == -0.02f);
    CHECK(back.monitor.extensions.current_sensor.gain == 1.02f);
    CHECK(config_to_json(back) == j);
    CHECK(back.monitor.battery.capacity_ah == c.monitor.battery.capacity_ah);
}

TEST_CASE("A config without extensions writes none and reads back plain", "[extension][config]") {
    const LoadedConfig c = default_config();
    const json j = config_to_json(c);
    CHECK_FALSE(j["battery"].contains("extensions"));
    // Floats are written in their shortest exact form: 0.02, not 0.019999999552965164.
    CHECK(j["battery"]["internal_resistance_ohm"].dump() == "0.02");
    CHECK(config_to_json(config_from_json(j, "t")) == j);
    CHECK_FALSE(battsim::core::extensions_active(config_from_json(j, "t").monitor.extensions));
}

TEST_CASE("Extension errors name the key", "[extension][config]") {
    CHECK_THROWS_WITH(config_from_json(with_extensions({{"rc_branch", json::array()}}), "x.json"),
                      Catch::Contains("x.json: $.battery.extensions.rc_branch: unknown key"));
    CHECK_THROWS_WITH(config_from_json(with_extensions({{"rc_branches", {{{"resistance_ohm", 0.01}, {"tau", 2}}}}}), "x.json"),
                      Catch::Contains("$.battery.extensions.rc_branches[0].tau: unknown key"));
    CHECK_THROWS_WITH(config_from_json(with_extensions({{"rc_branches", {{{"time_constant_s", -1}}}}}), "x.json"),
                      Catch::Contains("rc_branches[0].time_constant_s: value -1 out of range"));
    json four = json::array();
    for (int k = 0; k < 4; ++k) four.push_back({{"resistance_ohm", 0.01}});
    CHECK_THROWS_WITH(config_from_json(with_extensions({{"rc_branches", four}}), "x.json"),
                      Catch::Contains("at most 3 branches"));
    CHECK_THROWS_WITH(config_from_json(with_extensions({{"ocv_correction", {{"span_ah", 1}, {"delta_v", {0.1}}}}}), "x.json"),
                      Catch::Contains("delta_v: expected an array of 2 to 16 numbers"));
    CHECK_THROWS_WITH(config_from_json(with_extensions({{"temperature", {{"reference_c", "warm"}}}}), "x.json"),
                      Catch::Contains("$.battery.extensions.temperature.reference_c: expected a number"));
    CHECK_THROWS_WITH(config_from_json(with_extensions(json::array()), "x.json"),
                      Catch::Contains("$.battery.extensions: expected an object"));
    // The rest of the config is still checked by the base parser.
    json j = with_extensions(json::object());
    j["battery"]["capacity_ahh"] = 1;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.battery.capacity_ahh: unknown key"));
    CHECK_THROWS_WITH(load_config_file("/nonexistent/c.json"), Catch::Contains("cannot open"));
}

TEST_CASE("The shipped fitted configs load", "[extension][config]") {
    for (const char* name : {"pbms-flight29-dinogy1.json", "pbms-flight30-cnhl5.json", "pbms-flight32-cnhl3.json",
                             "pbms-flight34-dinogy2.json", "samsung-30q.json", "panasonic-18650pf.json", "cmu-m100-flight1.json"}) {
        INFO(name);
        const LoadedConfig c = load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/fitted/" + name);
        CHECK(battsim::core::extensions_active(c.monitor.extensions));
    }
}
