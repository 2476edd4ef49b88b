#include <catch2/catch.hpp>

#include "host/config_json.h"
#include "host/io/json_text.h"
#include "test_files.h"

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
    c.monitor.joint.health_time_share = 0.25f;           // default 0.5
    c.monitor.joint.health_time_fade_fraction = 0.75f;  // default 0.5
    c.monitor.joint.gap_charge_sigma_fraction = 0.4f;   // default 0.25
    c.monitor.joint.gap_hold_s = 2.5f;                  // default 5
    c.monitor.joint.verdict.enabled = false;            // default true
    c.monitor.joint.verdict.polarisation_slow_time_s = 90.0f;  // default 150
    c.monitor.joint.verdict.ekf.capacity_sigma0_fraction = 0.12f;
    CHECK_FALSE(config_to_json(c).contains("telemetry"));  // written only when set
    c.telemetry.system_id = 42;
    c.telemetry.battery_id = 1;
    c.telemetry.interval_s = 0.25f;
    c.telemetry.low_time_s = 90.0f;
    c.telemetry.text_repeat_s = 0.0f;
    c.telemetry.clear_hold_s = 12.5f;
    LoadedConfig back = config_from_json(config_to_json(c), "test");
    CHECK(back.telemetry.system_id == 42);
    CHECK(back.telemetry.component_id == 180);
    CHECK(back.telemetry.battery_id == 1);
    CHECK(back.telemetry.interval_s == 0.25f);
    CHECK(back.telemetry.low_time_s == 90.0f);
    CHECK(back.telemetry.critical_time_s == 20.0f);
    CHECK(back.telemetry.text_repeat_s == 0.0f);
    CHECK(back.telemetry.clear_hold_s == 12.5f);
    CHECK_FALSE(back.monitor.joint.health.enabled);
    CHECK(back.monitor.joint.health.ekf.voltage_sigma_v == 0.031f);
    CHECK(back.monitor.joint.health.polarisation_slow_share == 0.35f);
    CHECK_FALSE(back.monitor.joint.health.first_resistance_soc_correction);
    CHECK(back.monitor.joint.first_resistance_soc_correction);
    CHECK_FALSE(back.monitor.joint.health.solves_from_takeoff_soc);
    CHECK(back.monitor.joint.health.takeoff_soc_min_ground_s == 12.5f);
    CHECK(back.monitor.joint.cutoff_delay_s == 7.5f);
    CHECK(back.monitor.joint.health_time_share == 0.25f);
    CHECK(back.monitor.joint.health_time_fade_fraction == 0.75f);
    CHECK(back.monitor.joint.gap_charge_sigma_fraction == 0.4f);
    CHECK(back.monitor.joint.gap_hold_s == 2.5f);
    CHECK_FALSE(back.monitor.joint.verdict.enabled);
    CHECK(back.monitor.joint.verdict.polarisation_slow_time_s == 90.0f);
    CHECK(back.monitor.joint.verdict.ekf.capacity_sigma0_fraction == 0.12f);
    CHECK(back.monitor.joint.health.polarisation_slow_time_s == c.monitor.joint.health.polarisation_slow_time_s);
    CHECK(back.monitor.joint.ekf.voltage_sigma_v == c.monitor.joint.ekf.voltage_sigma_v);  // the filters' keys apart
    CHECK(back.monitor.cell_analysis.step.steady_band_fraction == 0.2f);
    CHECK(back.monitor.cell_analysis.step.max_wait_samples == 20);
    CHECK(back.monitor.battery.capacity_ah == 2.2f);
    CHECK(back.monitor.warnings.cell_outlier_score == 0.7f);
    CHECK(config_to_json(back) == config_to_json(c));
}

TEST_CASE("The config of a command given no -c is configs/reference-modified.json", "[config]") {
    // The help had promised that set, and the built-in config lacked three of its settings: a
    // dissertation flight replayed without -c "flew" 271.7 s instead of 145.4 s.
    const LoadedConfig file = load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json");
    CHECK(config_to_json(builtin_config()) == config_to_json(file));
    // The defaults every file starts from stay as they were.
    CHECK(default_config().monitor.flying.takeoff_confirm_s == 0.0f);
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
    j["joint"]["verdict_filter"]["polarisation_slow_tme_s"] = 90;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"),
                      Catch::Contains("$.joint.verdict_filter.polarisation_slow_tme_s: unknown key"));
    j = config_to_json(default_config());  // the take-off keys are the health filter's alone
    j["joint"]["verdict_filter"]["solves_from_takeoff_soc"] = false;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"),
                      Catch::Contains("$.joint.verdict_filter.solves_from_takeoff_soc: unknown key"));
    j = config_to_json(default_config());
    j["joint"]["health_filter"]["polarisation_slow_share"] = 1.5;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.joint.health_filter.polarisation_slow_share") &&
                                                           Catch::Contains("out of range"));

    // 0 made the reference resistance filter's alpha 0/0 on a repeated time stamp: NaN for good.
    j = config_to_json(default_config());
    j["monitor"]["resistance"]["filter_time_constant_s"] = 0;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.monitor.resistance.filter_time_constant_s") &&
                                                           Catch::Contains("out of range"));

    j = config_to_json(default_config());
    j["schema"] = "other";
    CHECK_THROWS_AS(config_from_json(j, "x.json"), ConfigError);

    CHECK_THROWS_WITH(load_config_file("/nonexistent/c.json"), Catch::Contains("cannot open"));
}

TEST_CASE("Config files: errors give the line and column of the key or value", "[config]") {
    const testsupport::TempDir temp("config");
    const auto error_of = [](const std::string& path) -> std::string {
        try {
            load_config_file(path);
        } catch (const ConfigError& e) {
            return e.what();
        }
        return "";
    };
    // Line 3 is `  "joint": {"cutoff_delay_s": -3}`: the value starts at column 31.
    const std::string range =
        temp.write("range.json", "{\n  \"schema\": \"battsim.config\", \"version\": 1,\n  \"joint\": {\"cutoff_delay_s\": -3}\n}\n");
    CHECK(error_of(range) == range + ":3:31: $.joint.cutoff_delay_s: value -3 out of range [0, 600]");
    // An unknown key is pointed at by its name (column 13), not its value.
    const std::string typo =
        temp.write("typo.json", "{\n  \"schema\": \"battsim.config\", \"version\": 1,\n  \"joint\": {\"cutoff_delay\": 5}\n}\n");
    CHECK(error_of(typo) == typo + ":3:13: $.joint.cutoff_delay: unknown key");
    const std::string syntax = temp.write("syntax.json", "{\n  \"schema\": \"battsim.config\",\n}\n");
    CHECK(error_of(syntax) == syntax + ":3:1: not valid JSON: syntax error while parsing object key - unexpected '}'; expected string literal");
    // A number beyond a double: the parser gives no position, so its text is looked up.
    const std::string huge = temp.write("huge.json", "{\n  \"schema\": \"battsim.config\", \"version\": 1,\n  \"battery\": {\"capacity_ah\": 3.7e358}\n}\n");
    CHECK(error_of(huge) == huge + ":3:30: not valid JSON: number 3.7e358 is beyond a double's range");
    CHECK(error_of(temp.write("empty.json", " \n")).find("file is empty") != std::string::npos);
    CHECK(error_of(temp.path()) == temp.path() + ": cannot open config file: it is a directory");
    std::string text;
    CHECK(read_text_file(range, text, 16) == TextRead::TooLarge);  // a cap, not the memory, ends a runaway read
    CHECK(read_text_file(range, text) == TextRead::Ok);
    CHECK(text.size() == 82);
    CHECK(error_of(temp.path("absent.json")) == temp.path("absent.json") + ": cannot open config file: no such file");
    // A name longer than the system takes is said as such (it had read "no such file").
    const std::string long_name = temp.path(std::string(5000, 'a') + ".json");
    CHECK(error_of(long_name) == long_name + ": cannot open config file: the path is too long");
    // Values checked while parsed whole keep only the path (no text to locate in).
    json j = config_to_json(default_config());
    j["joint"]["cutoff_delay_s"] = -3;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), "x.json: $.joint.cutoff_delay_s: value -3 out of range [0, 600]");
}

TEST_CASE("JsonLocator: paths to positions, and text that does not parse cannot stall it", "[config]") {
    const std::string text = "{\"a\": [1, {\"b\": true}],\n \"c\": \"x\\\"y\", \"d\": {}}";
    const JsonLocator loc(text);
    CHECK(loc.location("$") == std::make_pair(1L, 1L));
    CHECK(loc.location("$.a") == std::make_pair(1L, 7L));
    CHECK(loc.location("$.a[1]") == std::make_pair(1L, 11L));
    CHECK(loc.location("$.a[1].b") == std::make_pair(1L, 17L));
    CHECK(loc.key_location("$.a[1].b") == std::make_pair(1L, 12L));
    CHECK(loc.location("$.c") == std::make_pair(2L, 7L));
    CHECK(loc.location("$.d") == std::make_pair(2L, 20L));  // after the escaped quote
    CHECK(loc.location("$.d.missing") == std::make_pair(2L, 20L));  // a missing member: its object
    CHECK(loc.key_location("$.a[0]") == loc.location("$.a[0]"));  // no key: the value

    for (const std::string bad : {"[}", "{]", "{\"a\" 1 2 :}", "]]]]", "{\"a\": [", "\"open", ":::"}) {
        const JsonLocator l(bad);  // returns
        CHECK(l.offset("$") == 0);
    }
    // Nesting far beyond the walked depth costs neither stack nor paths; the deep value is
    // located at its deepest walked ancestor.
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    const JsonLocator d(deep);
    std::string path = "$";
    for (int i = 0; i < 40; ++i) path += "[0]";
    CHECK(d.offset(path) == 32);
}

namespace {
LogFacts facts(int cells, double resting_voltage_v) {
    LogFacts f;
    f.cells = cells;
    f.resting_voltage_v = resting_voltage_v;
    return f;
}
}  // namespace

TEST_CASE("config_notes: the joint estimator without a table, and a config for another pack", "[config]") {
    using battsim::host::config_notes;
    using battsim::host::LogFacts;
    battsim::core::MonitorConfig c;  // 4 cells in series, reference estimator, no table
    CHECK(config_notes(c).empty());
    c.estimator = battsim::core::EstimatorKind::Joint;
    REQUIRE(config_notes(c).size() == 1);
    CHECK(config_notes(c)[0].rfind("the joint estimator has no OCV table", 0) == 0);
    c.joint.ocv.points = 2;  // any table
    CHECK(config_notes(c).empty());
    // 4 cells at rest at 16.0 V: 4.0 V each, fine; the log's own 4 cell columns agree.
    CHECK(config_notes(c, facts(4, 16.0)).empty());
    CHECK(config_notes(c, facts(0, NAN)).empty());  // nothing known about the log
    // A 6S log: six cell columns, and 24.0 V is 6.0 V per configured cell.
    const auto six = config_notes(c, facts(6, 24.0));
    REQUIRE(six.size() == 2);
    CHECK(six[0] == "the log has 6 cell voltages but the config 4 cells in series (cells_in_series): does the config match "
                    "this pack?");
    CHECK(six[1] == "the pack rests at 24.00 V, 6.000 V per cell for the config's 4 cells in series, outside any lithium "
                    "cell's resting range (2.9-4.45 V): does the config match this pack?");
    // A 3S log without cell columns: 11.4 V is 2.85 V per configured cell, below 2.9.
    CHECK(config_notes(c, facts(0, 11.4)).size() == 1);
    // 2.9 V per cell: a deeply discharged 4S pack, or a 3S one at 3.87 V: only asked.
    const auto eleven = config_notes(c, facts(0, 11.6));
    REQUIRE(eleven.size() == 1);
    CHECK(eleven[0] == "the pack rests at 11.60 V: 3.87 V per cell as 3 cells, 2.90 V as the config's 4: does the config "
                       "match this pack?");
    CHECK(config_notes(c, facts(0, 14.8)).empty());  // 3.7 V per cell
}

TEST_CASE("config_notes: a temperature dependence on a log without a temperature", "[config]") {
    using battsim::host::config_notes;
    using battsim::host::is_log_note;
    using battsim::host::LogFacts;
    battsim::core::MonitorConfig c;
    c.extensions.temperature.enabled = true;
    c.extensions.temperature.resistance_activation_k = 7747.0f;
    LogFacts none;
    none.temperature_samples = 0;
    const auto notes = config_notes(c, none);
    REQUIRE(notes.size() == 1);
    CHECK(notes[0].rfind("the config's model depends on the temperature (battery.extensions.temperature) but the log has "
                         "no temperature: it runs at 25 degC throughout", 0) == 0);
    CHECK(is_log_note(notes[0]));  // said by the commands that fit along the log
    LogFacts some;
    some.temperature_samples = 10;
    CHECK(config_notes(c, some).empty());
    CHECK(config_notes(c).empty());  // no log read (export-config)
    // A lumped thermal state drives the terms without a measurement.
    c.extensions.thermal.enabled = true;
    CHECK(config_notes(c, none).empty());
    // Enabled with every term zero: nothing depends on the temperature.
    c.extensions.thermal.enabled = false;
    c.extensions.temperature.resistance_activation_k = 0.0f;
    CHECK(config_notes(c, none).empty());
}

TEST_CASE("Config values the reader's ranges allow but the monitor cannot use are refused by name", "[config]") {
    // Found by a sweep of every key at its range's ends: each had run without a word.
    json j = config_to_json(default_config());
    j["sensor"]["min_current_a"] = 500;  // above max_current_a: every sample kept out
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.sensor.min_current_a: must be below max_current_a"));
    j = config_to_json(default_config());
    j["sensor"]["min_pack_voltage_v"] = j["sensor"]["max_pack_voltage_v"];
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.sensor.min_pack_voltage_v: must be below max_pack_voltage_v"));
    j = config_to_json(default_config());
    j["sensor"]["min_cell_voltage_v"] = 5;  // every cell reading a fault, a warning on a good log
    CHECK_THROWS_WITH(config_from_json(j, "x.json"), Catch::Contains("$.sensor.min_cell_voltage_v: must be below max_cell_voltage_v"));
    // A flat OCV table: no slope to read charge from, the capacity frozen at its rated value.
    j = config_to_json(default_config());
    j["joint"]["ocv_cell_voltage_v"] = {3.7, 3.7, 3.7};
    CHECK_THROWS_WITH(config_from_json(j, "x.json"),
                      Catch::Contains("$.joint.ocv_cell_voltage_v: expected the full end above the empty end"));
    j["joint"]["ocv_cell_voltage_v"] = {3.3, 3.7, 3.7, 4.2};  // a plateau inside is a curve
    CHECK(config_from_json(j, "x.json").monitor.joint.ocv.points == 4);
    // A remembered power the remaining time divides by: 1e-38 W had written inf on every row.
    j = config_to_json(default_config());
    j["monitor"]["remembered_average_power_w"] = 1e-38;
    CHECK_THROWS_WITH(config_from_json(j, "x.json"),
                      Catch::Contains("$.monitor.remembered_average_power_w: expected 0 (none) or at least 0.01 W"));
    j["monitor"]["remembered_average_power_w"] = 0;
    CHECK(config_from_json(j, "x.json").monitor.power_average.initial_value == 0.0f);
    j["monitor"]["remembered_average_power_w"] = 0.01;
    CHECK(config_from_json(j, "x.json").monitor.power_average.initial_value == 0.01f);
}
