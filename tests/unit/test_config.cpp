#include <catch2/catch.hpp>

#include "host/config_json.h"

using namespace battsim::host;
using nlohmann::json;

TEST_CASE("Config JSON round-trips", "[config]") {
    LoadedConfig c = default_config();
    c.monitor.battery.capacity_ah = 2.2f;
    c.monitor.warnings.cell_outlier_score = 0.7f;
    c.monitor.cell_analysis.step.steady_band_fraction = 0.2f;
    c.monitor.cell_analysis.step.max_wait_samples = 20;
    c.monitor.joint.health.enabled = false;
    c.monitor.joint.health.ekf.voltage_sigma_v = 0.031f;
    c.monitor.joint.health.polarisation_slow_share = 0.35f;
    c.monitor.joint.health.first_resistance_soc_correction = false;  // default true
    c.monitor.joint.first_resistance_soc_correction = true;          // default false
    c.monitor.joint.health.solves_from_takeoff_soc = false;          // default true
    c.monitor.joint.health.takeoff_soc_min_ground_s = 12.5f;
    c.monitor.joint.cutoff_delay_s = 7.5f;  // default 0
    LoadedConfig back = config_from_json(config_to_json(c), "test");
    CHECK_FALSE(back.monitor.joint.health.enabled);
    CHECK(back.monitor.joint.health.ekf.voltage_sigma_v == 0.031f);
    CHECK(back.monitor.joint.health.polarisation_slow_share == 0.35f);
    CHECK_FALSE(back.monitor.joint.health.first_resistance_soc_correction);
    CHECK(back.monitor.joint.first_resistance_soc_correction);
    CHECK_FALSE(back.monitor.joint.health.solves_from_takeoff_soc);
    CHECK(back.monitor.joint.health.takeoff_soc_min_ground_s == 12.5f);
    CHECK(back.monitor.joint.cutoff_delay_s == 7.5f);
    CHECK(back.monitor.joint.ekf.voltage_sigma_v == c.monitor.joint.ekf.voltage_sigma_v);  // the two filters' keys apart
    CHECK(back.monitor.cell_analysis.step.steady_band_fraction == 0.2f);
    CHECK(back.monitor.cell_analysis.step.max_wait_samples == 20);
    CHECK(back.monitor.battery.capacity_ah == 2.2f);
    CHECK(back.monitor.warnings.cell_outlier_score == 0.7f);
    CHECK(config_to_json(back) == config_to_json(c));
}

TEST_CASE("Config errors name the key", "[config]") {
    json j = config_to_json(default_config());
    j["battery"]["capacity_ahh"] = 1.0;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("x.json: $.battery.capacity_ahh: unknown key"));

    j = config_to_json(default_config());
    j["battery"]["capacity_ah"] = "big";
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.battery.capacity_ah: expected a number"));

    j = config_to_json(default_config());
    j["battery"]["capacity_ah"] = -3;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("out of range"));

    j = config_to_json(default_config());
    j["battery"]["exponential_capacity_ah"] = 5;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("must be below capacity_ah"));

    j = config_to_json(default_config());
    j["joint"]["cell_step_band_fraction"] = 2;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.joint.cell_step_band_fraction") &&
                                                           Catch::Contains("out of range"));

    j = config_to_json(default_config());
    j["joint"]["health_filter"]["enable"] = true;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.joint.health_filter.enable: unknown key"));
    j = config_to_json(default_config());
    j["joint"]["health_filter"]["polarisation_slow_share"] = 1.5;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.joint.health_filter.polarisation_slow_share") &&
                                                           Catch::Contains("out of range"));

    j = config_to_json(default_config());
    j["schema"] = "other";
    CHECK_THROWS_AS(config_from_json(j, "x.json"), ConfigError);

    CHECK_THROWS_WITH(load_config_file("/nonexistent/c.json"), Catch::Contains("cannot open"));
}
