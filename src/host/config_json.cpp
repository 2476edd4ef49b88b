#include "host/config_json.h"

#include <cmath>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "host/config_extensions.h"
#include "host/pack_config.h"

namespace battsim {
namespace host {

namespace {

using nlohmann::json;

constexpr const char* kSchema = "battsim.config";
constexpr int kVersion = 1;

using ObjectReader = ConfigObjectReader;

constexpr double kBig = 1e9;

}  // namespace

json config_number(float x) {
    char buf[32];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, static_cast<double>(x));
        const double y = std::strtod(buf, nullptr);
        if (static_cast<float>(y) == x) return json(y);
    }
    return json(static_cast<double>(x));
}

namespace {
// The capacity EKF's keys, read and written alike for the tracking filter (in `joint`)
// and the health filter (in `joint.health_filter`).
void read_ekf_keys(ObjectReader& r, core::CapacityEkf::Config& e) {
    r.number("voltage_sigma_v", e.voltage_sigma_v, 1e-6, 100);
    r.number("soc_sigma0", e.soc_sigma0, 0, 1);
    r.number("capacity_sigma0_fraction", e.capacity_sigma0_fraction, 0, 10);
    r.number("polarisation_initial_ohm", e.polarisation_initial_ohm, 0, 10);
    r.number("polarisation_sigma0_ohm", e.polarisation_sigma0_ohm, 0, 10);
    r.number("soc_process_per_sqrt_s", e.soc_process_per_sqrt_s, 0, 1);
    r.number("capacity_process_fraction_per_sqrt_s", e.capacity_process_fraction_per_sqrt_s, 0, 1);
    r.number("polarisation_process_ohm_per_sqrt_s", e.polarisation_process_ohm_per_sqrt_s, 0, 1);
    r.number("gate_sigmas", e.gate_sigmas, 1, 1000);
    r.number("ocv_soc_sigma", e.ocv_soc_sigma, 0, 1);
    r.number("offset_sigma0_a", e.offset_sigma0_a, 0, 100);
    r.number("offset_process_a_per_sqrt_s", e.offset_process_a_per_sqrt_s, 0, 10);
}

json ekf_keys_json(const core::CapacityEkf::Config& e) {
    return {
        {"voltage_sigma_v", e.voltage_sigma_v},
        {"soc_sigma0", e.soc_sigma0},
        {"capacity_sigma0_fraction", e.capacity_sigma0_fraction},
        {"polarisation_initial_ohm", e.polarisation_initial_ohm},
        {"polarisation_sigma0_ohm", e.polarisation_sigma0_ohm},
        {"soc_process_per_sqrt_s", e.soc_process_per_sqrt_s},
        {"capacity_process_fraction_per_sqrt_s", e.capacity_process_fraction_per_sqrt_s},
        {"polarisation_process_ohm_per_sqrt_s", e.polarisation_process_ohm_per_sqrt_s},
        {"gate_sigmas", e.gate_sigmas},
        {"ocv_soc_sigma", e.ocv_soc_sigma},
        {"offset_sigma0_a", e.offset_sigma0_a},
        {"offset_process_a_per_sqrt_s", e.offset_process_a_per_sqrt_s},
    };
}

// A filter of the health kind (`joint.health_filter`, `joint.verdict_filter`). The take-off
// state-of-charge keys are the health filter's alone (the verdict filter follows them), so in
// `verdict_filter` they are unknown keys rather than settings that would do nothing.
void read_filter_keys(ObjectReader& r, const char* key, core::JointEstimator::Config::HealthFilter& hf,
                      const std::string& origin, bool takeoff_keys) {
    const json* h = r.member(key);
    if (!h) return;
    ObjectReader rh(*h, r.child(key), origin);
    rh.boolean("enabled", hf.enabled);
    rh.number("polarisation_time_s", hf.polarisation_time_s, 0, kBig);
    rh.number("polarisation_slow_time_s", hf.polarisation_slow_time_s, 0, kBig);
    rh.number("polarisation_slow_share", hf.polarisation_slow_share, 0, 1);
    rh.boolean("polarisation_follows_resistance", hf.polarisation_follows_resistance);
    rh.boolean("first_resistance_soc_correction", hf.first_resistance_soc_correction);
    if (takeoff_keys) {
        rh.boolean("solves_from_takeoff_soc", hf.solves_from_takeoff_soc);
        rh.number("takeoff_soc_min_ground_s", hf.takeoff_soc_min_ground_s, 0, kBig);
    }
    read_ekf_keys(rh, hf.ekf);
}

json filter_keys_json(const core::JointEstimator::Config::HealthFilter& hf, bool takeoff_keys) {
    json h = ekf_keys_json(hf.ekf);
    h["enabled"] = hf.enabled;
    h["polarisation_time_s"] = hf.polarisation_time_s;
    h["polarisation_slow_time_s"] = hf.polarisation_slow_time_s;
    h["polarisation_slow_share"] = hf.polarisation_slow_share;
    h["polarisation_follows_resistance"] = hf.polarisation_follows_resistance;
    h["first_resistance_soc_correction"] = hf.first_resistance_soc_correction;
    if (takeoff_keys) {
        h["solves_from_takeoff_soc"] = hf.solves_from_takeoff_soc;
        h["takeoff_soc_min_ground_s"] = hf.takeoff_soc_min_ground_s;
    }
    return h;
}

// Every float of the config in its shortest exact form (the fields are all float).
void shorten_floats(json& j) {
    if (j.is_number_float()) {
        j = config_number(static_cast<float>(j.get<double>()));
    } else if (j.is_structured()) {
        for (auto& v : j) shorten_floats(v);
    }
}
}  // namespace

LoadedConfig default_config() {
    LoadedConfig c;
    c.name = "reference-4s-modified";
    return c;
}

LoadedConfig builtin_config() {
    LoadedConfig c = default_config();
    // What configs/reference-modified.json sets beyond the defaults every file starts from
    // (a unit test holds the two equal): without them a log with no -c "flew" from an arming
    // blip two minutes early, and blamed the dissertation logger's cell 1 for its ground lead.
    c.description = "CNHL Black Series 1500 mAh 4S (dissertation battery 5), parameters hand-tuned by the dissertation "
                    "author to fit flight 30: nominal-zone capacity 1.5 Ah, exponential zone 0.3 Ah, curve current 7 A, "
                    "R 0.02 ohm.";
    c.monitor.flying.takeoff_confirm_s = 0.5f;
    c.monitor.power_average.initial_value = 316.0f;
    c.monitor.cell_analysis.first_cell_includes_lead = true;
    // A file without sensor.min_pack_voltage_v reads the per-cell floor (config_from_json).
    c.monitor.sensor.min_pack_voltage_v = kGlitchFloorCellV * static_cast<float>(c.monitor.cells_in_series);
    return c;
}

LoadedConfig config_from_json(const json& j, const std::string& origin) {
    LoadedConfig out = default_config();
    core::MonitorConfig& m = out.monitor;
    ObjectReader root(j, "$", origin);
    std::string schema = kSchema;
    int version = kVersion;
    root.string("schema", schema);
    root.number("version", version, 1, 1000);
    if (schema != kSchema) root.fail("$.schema", "expected \"" + std::string(kSchema) + "\", found \"" + schema + "\"");
    if (version != kVersion) root.fail("$.version", "unsupported version " + std::to_string(version));
    root.string("name", out.name);
    root.string("description", out.description);

    if (const json* b = root.member("battery")) {
        ObjectReader r(*b, root.child("battery"), origin);
        core::TremblayParams& p = m.battery;
        r.number("cells_in_series", m.cells_in_series, 1, core::kMaxCells);
        r.number("full_voltage_v", p.full_voltage_v, 0.1, 1000);
        r.number("exponential_voltage_v", p.exponential_voltage_v, 0.1, 1000);
        r.number("exponential_capacity_ah", p.exponential_capacity_ah, 1e-6, 10000);
        r.number("nominal_zone_voltage_v", p.nominal_zone_voltage_v, 0.1, 1000);
        r.number("nominal_zone_capacity_ah", p.nominal_zone_capacity_ah, 1e-6, 10000);
        r.number("capacity_ah", p.capacity_ah, 1e-3, 10000);
        r.number("internal_resistance_ohm", p.internal_resistance_ohm, 0, 100);
        r.number("curve_current_a", p.curve_current_a, 0, 10000);
        r.number("nominal_voltage_v", m.flight_time.nominal_voltage_v, 0.1, 1000);
        r.number("max_voltage_v", m.max_voltage_v, 0.1, 1000);
        r.number("min_voltage_v", m.min_voltage_v, 0.1, 1000);
        if (!(p.exponential_voltage_v < p.full_voltage_v))
            r.fail(r.child("exponential_voltage_v"), "must be below full_voltage_v");
        if (!(p.exponential_capacity_ah < p.capacity_ah))
            r.fail(r.child("exponential_capacity_ah"), "must be below capacity_ah");
        if (!(m.min_voltage_v < m.max_voltage_v)) r.fail(r.child("min_voltage_v"), "must be below max_voltage_v");
        if (const json* e = r.member("extensions")) m.extensions = extensions_from_json(*e, origin, r.child("extensions"));
    }
    if (const json* s = root.member("monitor")) {
        ObjectReader r(*s, root.child("monitor"), origin);
        r.number("reaction_time_s", m.current_filter.time_constant_s, 0, kBig);
        r.number("min_flight_voltage_v", m.flight_time.min_flight_voltage_v, 0, 1000);
        r.number("capacity_step_fraction", m.capacity.capacity_step_fraction, 1e-6, 1);
        m.flight_time.step_fraction = m.capacity.capacity_step_fraction;
        r.number("max_voltage_variance_v", m.capacity.max_voltage_variance_v, 0, 100);
        r.number("variance_persistence_updates", m.capacity.persistence_updates, 1, 1e6);
        r.boolean("resistance_keeps_e0", m.capacity.resistance_keeps_e0);
        r.number("short_average_time_s", m.power_average.short_time_s, 0, kBig);
        r.number("long_average_time_s", m.power_average.long_time_s, 0, kBig);
        m.current_average.short_time_s = m.power_average.short_time_s;
        m.current_average.long_time_s = m.power_average.long_time_s;
        r.number("remembered_average_power_w", m.power_average.initial_value, 0, kBig);
        // The remaining time divides by it: 1e-38 W had written `inf` on every row before the flight.
        if (m.power_average.initial_value > 0.0f && m.power_average.initial_value < 0.01f)
            r.fail(r.child("remembered_average_power_w"), "expected 0 (none) or at least 0.01 W, found " +
                                                              config_number(m.power_average.initial_value).dump());
        r.number("min_flying_current_a", m.flying.min_flying_current_a, 0, kBig);
        r.number("landed_hold_s", m.flying.landed_hold_s, 0, kBig);
        r.number("takeoff_confirm_s", m.flying.takeoff_confirm_s, 0, kBig);
        r.number("max_resting_current_a", m.initial.max_resting_current_a, 0, kBig);
        r.number("stabilisation_time_s", m.initial.stabilisation_time_s, 0, kBig);
        if (const json* e = r.member("resistance")) {
            ObjectReader rr(*e, r.child("resistance"), origin);
            // Above 0: alpha = dt/(dt + tc) is 0/0 on a repeated time stamp, and NaN stays in the filter.
            rr.number("filter_time_constant_s", m.resistance.filter_time_constant_s, 0.001, kBig);
            rr.number("max_filter_alpha", m.resistance.max_filter_alpha, 0, 1);
            rr.number("blend_gain", m.resistance.blend_gain, 0, kBig);
            rr.number("initial_resistance_ohm", m.resistance.initial_resistance_ohm, 0, 100);
        }
        if (const json* w = r.member("warnings")) {
            ObjectReader rw(*w, r.child("warnings"), origin);
            rw.number("low_capacity_fraction", m.warnings.low_capacity_fraction, 0, 10);
            rw.number("high_resistance_factor", m.warnings.high_resistance_factor, 0, 1000);
            rw.number("min_resistance_updates", m.warnings.min_resistance_updates, 0, 1e9);
            rw.number("cell_outlier_score", m.warnings.cell_outlier_score, 0, 1);
            rw.number("min_cell_outlier_samples", m.warnings.min_cell_outlier_samples, 0, 1e9);
        }
    }
    std::string estimator = m.estimator == core::EstimatorKind::Joint ? "joint" : "reference";
    root.string("estimator", estimator);
    if (estimator == "reference") m.estimator = core::EstimatorKind::Reference;
    else if (estimator == "joint") m.estimator = core::EstimatorKind::Joint;
    else root.fail("$.estimator", "expected \"reference\" or \"joint\", found \"" + estimator + "\"");
    if (const json* s = root.member("joint")) {
        ObjectReader r(*s, root.child("joint"), origin);
        core::JointEstimator::Config& jc = m.joint;
        r.number("resistance_lag_s", jc.resistance.lag_s, 0, 60);
        r.number("resistance_memory_s", jc.resistance.memory_s, 0, kBig);
        r.number("resistance_min_step_a", jc.resistance.min_step_a, 0, kBig);
        r.number("resistance_min_excitation_a2", jc.resistance.min_excitation_a2, 0.001, kBig);  // a bar: the garbled-reading gate lets pairs through below it
        r.number("resistance_trend_sigma_per_s", jc.resistance.trend_sigma_per_s, 0, 1);
        r.number("hover_resistance_lag_s", jc.hover_resistance.lag_s, 0, 60);
        r.number("hover_resistance_min_step_a", jc.hover_resistance.min_step_a, 0, kBig);
        r.number("hover_resistance_min_excitation_a2", jc.hover_resistance.min_excitation_a2, 0.001, kBig);
        r.number("polarisation_time_s", jc.polarisation_time_s, 0, kBig);
        r.number("polarisation_slow_time_s", jc.polarisation_slow_time_s, 0, kBig);
        r.number("polarisation_slow_share", jc.polarisation_slow_share, 0, 1);
        read_ekf_keys(r, jc.ekf);
        read_filter_keys(r, "health_filter", jc.health, origin, true);
        read_filter_keys(r, "verdict_filter", jc.verdict, origin, false);
        r.number("offset_fault_a", jc.offset_fault_a, 0, kBig);
        r.number("offset_learn_max_current_a", jc.offset_learn_max_current_a, 0, kBig);
        r.number("rest_capacity_min_rest_s", jc.rest_capacity_min_rest_s, 0, kBig);
        r.number("rest_capacity_max_current_a", jc.rest_capacity_max_current_a, 0, kBig);
        r.number("rest_capacity_min_soc_drop", jc.rest_capacity_min_soc_drop, 0.01, 1);
        r.number("capacity_sigma_fraction_of_charge", jc.capacity_sigma_fraction_of_charge, 0, 10);
        r.number("ground_soc_process_scale", jc.ground_soc_process_scale, 0, 100);
        r.number("resistance_settle_s", jc.resistance_settle_s, 0, kBig);
        r.boolean("learn_offset_in_flight", jc.learn_offset_in_flight);
        r.boolean("polarisation_follows_resistance", jc.polarisation_follows_resistance);
        r.boolean("first_resistance_soc_correction", jc.first_resistance_soc_correction);
        r.number("solver_steps", jc.solver_steps, 2, 1000);
        r.number("cutoff_delay_s", jc.cutoff_delay_s, 0, 600);
        r.number("health_time_share", jc.health_time_share, 0, 1);
        r.number("health_time_fade_fraction", jc.health_time_fade_fraction, 0, 1);
        r.number("gap_charge_sigma_fraction", jc.gap_charge_sigma_fraction, 0, 2);
        r.number("gap_hold_s", jc.gap_hold_s, 0, 60);
        r.number("solver_steps_per_update", jc.solver_steps_per_update, 1, 1000);
        r.number("short_flight_fraction", jc.short_flight_fraction, 0, 1);
        r.number("cause_fraction", jc.cause_fraction, 0, 1);
        r.number("min_flight_s", jc.min_flight_s, 0, kBig);
        r.number("persistence", jc.persistence, 1, 1e6);
        r.number("max_sample_gap_s", jc.max_sample_gap_s, 0, kBig);
        core::CellAnalyzer::Config& ca = m.cell_analysis;
        r.number("cell_resistance_ratio", ca.resistance_ratio, 1, 100);
        r.number("cell_capacity_deficit", ca.capacity_deficit, 0, 1);
        r.number("cell_significance_sigmas", ca.significance_sigmas, 0, 100);
        r.number("cell_capacity_significance_sigmas", ca.capacity_significance_sigmas, 0, 100);
        r.number("cell_pack_deficit_sigmas", ca.pack_deficit_sigmas, 0, 100);
        r.number("cell_min_charge_ah", ca.min_charge_ah, 0, kBig);
        r.number("cell_resistance_min_step_a", ca.min_step_a, 0, kBig);
        r.number("cell_resistance_min_excitation_a2", ca.min_excitation_a2, 0, kBig);
        r.number("cell_min_drift_v", ca.min_drift_v, 0, kBig);
        r.number("cell_slow_current_time_s", ca.slow_current_time_s, 0, kBig);
        r.number("cell_current_ridge_a2", ca.current_ridge_a2, 0, kBig);
        r.number("cell_slow_current_ridge_a2", ca.slow_current_ridge_a2, 0, kBig);
        r.number("cell_tap_artifact_ratio", ca.tap_artifact_ratio, 0, 100);
        r.boolean("last_cell_includes_lead", ca.last_cell_includes_lead);
        r.boolean("first_cell_includes_lead", ca.first_cell_includes_lead);
        // −1 (or any negative): not calibrated, the lead cell is not judged for resistance.
        r.number("last_cell_lead_excess", ca.last_lead_excess, -1, 100);
        r.number("first_cell_lead_excess", ca.first_lead_excess, -1, 100);
        r.number("cell_lead_excess_sigma", ca.lead_excess_sigma, 0, 100);
        r.number("cell_step_min_a", ca.step.min_step_a, 0, kBig);
        r.number("cell_step_band_a", ca.step.steady_band_a, 0, kBig);
        r.number("cell_step_band_fraction", ca.step.steady_band_fraction, 0, 1);
        r.number("cell_step_noise_floor_v", ca.step.noise_floor_v, 0, 1);
        r.number("cell_step_max_wait_samples", ca.step.max_wait_samples, 1, 60000);
        if (const json* t = r.member("ocv_cell_voltage_v")) {
            if (!t->is_array() || t->size() < 2 || t->size() > static_cast<size_t>(core::kOcvTableMaxPoints))
                r.fail(r.child("ocv_cell_voltage_v"), "expected an array of 2.." + std::to_string(core::kOcvTableMaxPoints) +
                                                          " cell voltages at evenly spaced SOC from 0 to 1");
            jc.ocv.points = static_cast<int>(t->size());
            for (size_t k = 0; k < t->size(); ++k) {
                const json& v = (*t)[k];
                if (!v.is_number() || !(v.get<double>() > 0) || v.get<double>() > 10)
                    r.fail(r.child("ocv_cell_voltage_v") + "[" + std::to_string(k) + "]", "expected a cell voltage in (0, 10] V");
                jc.ocv.cell_voltage_v[k] = v.get<float>();
                if (k > 0 && !(jc.ocv.cell_voltage_v[k] >= jc.ocv.cell_voltage_v[k - 1]))
                    r.fail(r.child("ocv_cell_voltage_v") + "[" + std::to_string(k) + "]", "must not fall as SOC rises");
            }
            // A flat table has no slope anywhere: the filter could never read charge off the
            // voltage, and the capacity stayed at its rated value without a word.
            if (!(jc.ocv.cell_voltage_v[jc.ocv.points - 1] > jc.ocv.cell_voltage_v[0]))
                r.fail(r.child("ocv_cell_voltage_v"), "expected the full end above the empty end; a flat table reads no charge");
        }
    }
    // Unset, the glitch floor is 2.0 V per cell (make-config's), below what a loaded lithium
    // pack shows: the core's 1.0 V of any pack had let one 2.2 V row on a 6S Matrice 100
    // flight through to the estimators. Where that would not be below the ceiling, 1.0 V stays.
    const float per_cell_floor_v = kGlitchFloorCellV * static_cast<float>(m.cells_in_series);
    bool floor_set = false;
    if (const json* s = root.member("sensor")) {
        ObjectReader r(*s, root.child("sensor"), origin);
        floor_set = s->is_object() && s->contains("min_pack_voltage_v");
        r.number("shunt_offset_ma", m.shunt.offset_ma, -kBig, kBig);
        r.number("shunt_scale_mv_per_10a", m.shunt.scale_mv_per_10a, 1e-9, kBig);
        r.number("max_pack_voltage_v", m.sensor.max_pack_voltage_v, 0, 10000);
        // The per-cell floor before the key is read, so that the reference lists it as the
        // key's default (it had listed the core's 1.0 V).
        if (!floor_set && per_cell_floor_v < m.sensor.max_pack_voltage_v) m.sensor.min_pack_voltage_v = per_cell_floor_v;
        r.number("min_pack_voltage_v", m.sensor.min_pack_voltage_v, 0, 10000);
        r.number("max_current_a", m.sensor.max_current_a, -kBig, kBig);
        r.number("min_current_a", m.sensor.min_current_a, -kBig, kBig);
        r.number("min_cell_voltage_v", m.sensor.min_cell_voltage_v, 0, 100);
        r.number("max_cell_voltage_v", m.sensor.max_cell_voltage_v, 0, 100);
        r.number("max_cell_sum_error_v", m.sensor.max_cell_sum_error_v, 0, 100);
        // Limits the wrong way round keep every sample out (or every cell reading, with a
        // sensor-fault warning on a good log): said here, where the mistake is.
        if (!(m.sensor.min_pack_voltage_v < m.sensor.max_pack_voltage_v))
            r.fail(r.child("min_pack_voltage_v"), "must be below max_pack_voltage_v");
        if (!(m.sensor.min_current_a < m.sensor.max_current_a))
            r.fail(r.child("min_current_a"), "must be below max_current_a");
        if (!(m.sensor.min_cell_voltage_v < m.sensor.max_cell_voltage_v))
            r.fail(r.child("min_cell_voltage_v"), "must be below max_cell_voltage_v");
    }
    if (!floor_set && per_cell_floor_v < m.sensor.max_pack_voltage_v) m.sensor.min_pack_voltage_v = per_cell_floor_v;
    if (const json* s = root.member("telemetry")) {
        ObjectReader r(*s, root.child("telemetry"), origin);
        telemetry::TelemetryConfig& t = out.telemetry;
        r.number("system_id", t.system_id, 1, 255);
        r.number("component_id", t.component_id, 1, 255);
        r.number("battery_id", t.battery_id, 0, 255);
        r.number("interval_s", t.interval_s, 0.05, 3600);
        r.number("low_time_s", t.low_time_s, 0, 36000);
        r.number("critical_time_s", t.critical_time_s, 0, 36000);
        r.number("text_repeat_s", t.text_repeat_s, 0, 36000);
        r.number("clear_hold_s", t.clear_hold_s, 0, 36000);
        if (t.critical_time_s > t.low_time_s)
            r.fail(r.child("critical_time_s"), "expected at most low_time_s (" + json_text(json(t.low_time_s)) + ")");
    }
    return out;
}

LoadedConfig load_config_file(const std::string& path) {
    std::string text;
    const json j = load_json_document<ConfigError>(path, "config file", "a \"" + std::string(kSchema) + "\" JSON object", text);
    try {
        return config_from_json(j, path);
    } catch (const ConfigError& e) {
        throw located(e, JsonLocator(text));
    }
}

json config_to_json(const LoadedConfig& c) {
    const core::MonitorConfig& m = c.monitor;
    const core::TremblayParams& p = m.battery;
    json j;
    j["schema"] = kSchema;
    j["version"] = kVersion;
    j["name"] = c.name;
    if (!c.description.empty()) j["description"] = c.description;
    j["battery"] = {
        {"cells_in_series", m.cells_in_series},
        {"full_voltage_v", p.full_voltage_v},
        {"exponential_voltage_v", p.exponential_voltage_v},
        {"exponential_capacity_ah", p.exponential_capacity_ah},
        {"nominal_zone_voltage_v", p.nominal_zone_voltage_v},
        {"nominal_zone_capacity_ah", p.nominal_zone_capacity_ah},
        {"capacity_ah", p.capacity_ah},
        {"internal_resistance_ohm", p.internal_resistance_ohm},
        {"curve_current_a", p.curve_current_a},
        {"nominal_voltage_v", m.flight_time.nominal_voltage_v},
        {"max_voltage_v", m.max_voltage_v},
        {"min_voltage_v", m.min_voltage_v},
    };
    if (core::extensions_active(m.extensions)) j["battery"]["extensions"] = extensions_to_json(m.extensions);
    j["monitor"] = {
        {"reaction_time_s", m.current_filter.time_constant_s},
        {"min_flight_voltage_v", m.flight_time.min_flight_voltage_v},
        {"capacity_step_fraction", m.capacity.capacity_step_fraction},
        {"max_voltage_variance_v", m.capacity.max_voltage_variance_v},
        {"variance_persistence_updates", m.capacity.persistence_updates},
        {"resistance_keeps_e0", m.capacity.resistance_keeps_e0},
        {"short_average_time_s", m.power_average.short_time_s},
        {"long_average_time_s", m.power_average.long_time_s},
        {"remembered_average_power_w", m.power_average.initial_value},
        {"min_flying_current_a", m.flying.min_flying_current_a},
        {"landed_hold_s", m.flying.landed_hold_s},
        {"takeoff_confirm_s", m.flying.takeoff_confirm_s},
        {"max_resting_current_a", m.initial.max_resting_current_a},
        {"stabilisation_time_s", m.initial.stabilisation_time_s},
        {"resistance",
         {{"filter_time_constant_s", m.resistance.filter_time_constant_s},
          {"max_filter_alpha", m.resistance.max_filter_alpha},
          {"blend_gain", m.resistance.blend_gain},
          {"initial_resistance_ohm", m.resistance.initial_resistance_ohm}}},
        {"warnings",
         {{"low_capacity_fraction", m.warnings.low_capacity_fraction},
          {"high_resistance_factor", m.warnings.high_resistance_factor},
          {"min_resistance_updates", m.warnings.min_resistance_updates},
          {"cell_outlier_score", m.warnings.cell_outlier_score},
          {"min_cell_outlier_samples", m.warnings.min_cell_outlier_samples}}},
    };
    j["estimator"] = m.estimator == core::EstimatorKind::Joint ? "joint" : "reference";
    {
        const core::JointEstimator::Config& jc = m.joint;
        json jj = {
            {"resistance_lag_s", jc.resistance.lag_s},
            {"resistance_memory_s", jc.resistance.memory_s},
            {"resistance_min_step_a", jc.resistance.min_step_a},
            {"resistance_min_excitation_a2", jc.resistance.min_excitation_a2},
            {"resistance_trend_sigma_per_s", jc.resistance.trend_sigma_per_s},
            {"hover_resistance_lag_s", jc.hover_resistance.lag_s},
            {"hover_resistance_min_step_a", jc.hover_resistance.min_step_a},
            {"hover_resistance_min_excitation_a2", jc.hover_resistance.min_excitation_a2},
            {"polarisation_time_s", jc.polarisation_time_s},
            {"polarisation_slow_time_s", jc.polarisation_slow_time_s},
            {"polarisation_slow_share", jc.polarisation_slow_share},
            {"offset_fault_a", jc.offset_fault_a},
            {"offset_learn_max_current_a", jc.offset_learn_max_current_a},
            {"rest_capacity_min_rest_s", jc.rest_capacity_min_rest_s},
            {"rest_capacity_max_current_a", jc.rest_capacity_max_current_a},
            {"rest_capacity_min_soc_drop", jc.rest_capacity_min_soc_drop},
            {"capacity_sigma_fraction_of_charge", jc.capacity_sigma_fraction_of_charge},
            {"ground_soc_process_scale", jc.ground_soc_process_scale},
            {"resistance_settle_s", jc.resistance_settle_s},
            {"learn_offset_in_flight", jc.learn_offset_in_flight},
            {"polarisation_follows_resistance", jc.polarisation_follows_resistance},
            {"first_resistance_soc_correction", jc.first_resistance_soc_correction},
            {"solver_steps", jc.solver_steps},
            {"cutoff_delay_s", jc.cutoff_delay_s},
            {"health_time_share", jc.health_time_share},
            {"health_time_fade_fraction", jc.health_time_fade_fraction},
            {"gap_charge_sigma_fraction", jc.gap_charge_sigma_fraction},
            {"gap_hold_s", jc.gap_hold_s},
            {"solver_steps_per_update", jc.solver_steps_per_update},
            {"short_flight_fraction", jc.short_flight_fraction},
            {"cause_fraction", jc.cause_fraction},
            {"min_flight_s", jc.min_flight_s},
            {"persistence", jc.persistence},
            {"max_sample_gap_s", jc.max_sample_gap_s},
            {"cell_resistance_ratio", m.cell_analysis.resistance_ratio},
            {"cell_capacity_deficit", m.cell_analysis.capacity_deficit},
            {"cell_significance_sigmas", m.cell_analysis.significance_sigmas},
            {"cell_capacity_significance_sigmas", m.cell_analysis.capacity_significance_sigmas},
            {"cell_pack_deficit_sigmas", m.cell_analysis.pack_deficit_sigmas},
            {"cell_min_charge_ah", m.cell_analysis.min_charge_ah},
            {"cell_resistance_min_step_a", m.cell_analysis.min_step_a},
            {"cell_resistance_min_excitation_a2", m.cell_analysis.min_excitation_a2},
            {"cell_min_drift_v", m.cell_analysis.min_drift_v},
            {"cell_slow_current_time_s", m.cell_analysis.slow_current_time_s},
            {"cell_current_ridge_a2", m.cell_analysis.current_ridge_a2},
            {"cell_slow_current_ridge_a2", m.cell_analysis.slow_current_ridge_a2},
            {"cell_tap_artifact_ratio", m.cell_analysis.tap_artifact_ratio},
            {"last_cell_includes_lead", m.cell_analysis.last_cell_includes_lead},
            {"first_cell_includes_lead", m.cell_analysis.first_cell_includes_lead},
            {"last_cell_lead_excess", m.cell_analysis.last_lead_excess},
            {"first_cell_lead_excess", m.cell_analysis.first_lead_excess},
            {"cell_lead_excess_sigma", m.cell_analysis.lead_excess_sigma},
            {"cell_step_min_a", m.cell_analysis.step.min_step_a},
            {"cell_step_band_a", m.cell_analysis.step.steady_band_a},
            {"cell_step_band_fraction", m.cell_analysis.step.steady_band_fraction},
            {"cell_step_noise_floor_v", m.cell_analysis.step.noise_floor_v},
            {"cell_step_max_wait_samples", m.cell_analysis.step.max_wait_samples},
        };
        jj.update(ekf_keys_json(jc.ekf));
        jj["health_filter"] = filter_keys_json(jc.health, true);
        jj["verdict_filter"] = filter_keys_json(jc.verdict, false);
        if (jc.ocv.points >= 2) {
            json t = json::array();
            for (int k = 0; k < jc.ocv.points; ++k) t.push_back(jc.ocv.cell_voltage_v[k]);
            jj["ocv_cell_voltage_v"] = t;
        }
        j["joint"] = jj;
    }
    j["sensor"] = {
        {"shunt_offset_ma", m.shunt.offset_ma},
        {"shunt_scale_mv_per_10a", m.shunt.scale_mv_per_10a},
        {"max_pack_voltage_v", m.sensor.max_pack_voltage_v},
        {"min_pack_voltage_v", m.sensor.min_pack_voltage_v},
        {"max_current_a", m.sensor.max_current_a},
        {"min_current_a", m.sensor.min_current_a},
        {"min_cell_voltage_v", m.sensor.min_cell_voltage_v},
        {"max_cell_voltage_v", m.sensor.max_cell_voltage_v},
        {"max_cell_sum_error_v", m.sensor.max_cell_sum_error_v},
    };
    // Only when set: configs that never mention the telemetry read back as they were.
    const auto telemetry_json = [](const telemetry::TelemetryConfig& t) {
        return json{{"system_id", t.system_id},   {"component_id", t.component_id}, {"battery_id", t.battery_id},
                    {"interval_s", t.interval_s}, {"low_time_s", t.low_time_s},     {"critical_time_s", t.critical_time_s},
                    {"text_repeat_s", t.text_repeat_s}, {"clear_hold_s", t.clear_hold_s}};
    };
    const json tj = telemetry_json(c.telemetry);
    if (tj != telemetry_json(telemetry::TelemetryConfig{})) j["telemetry"] = tj;
    shorten_floats(j);
    return j;
}

namespace {
// How config_notes ends the notes that say the config is for another pack than the log's.
const char* const kOtherPackEnd = ": does the config match this pack?";
const char* const kMillivoltsEnd = ": a voltage in mV read as volts?";  // the pack's rest a thousand times a cell's
const char* const kMakeConfigAdvice = ": battsim make-config --from-log ";
// An ordinary CSV records no capacity, and make-config asks for one (the advice alone had
// exited 2 on a Matrice 100 flight).
const char* const kMakeConfigAdviceEnd = " writes one for it (with --capacity-mah if the log does not record the capacity)";
bool ends_with_text(const std::string& s, const std::string& end) {
    return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
}
}  // namespace

bool is_millivolts_note(const std::string& note) { return ends_with_text(note, kMillivoltsEnd); }

bool is_other_pack_note(const std::string& note) {
    return ends_with_text(note, kOtherPackEnd) || ends_with_text(note, kMillivoltsEnd) ||
           (note.find(kMakeConfigAdvice) != std::string::npos && ends_with_text(note, kMakeConfigAdviceEnd));
}

namespace {
const char* const kNoTemperatureStart = "the config's model depends on the temperature";
// Whether the temperature block moves anything (an enabled block of zeros does not).
bool temperature_terms(const core::TemperatureDependence& t) {
    return t.enabled && (t.resistance_activation_k != 0.0f || t.polarisation_activation_k != 0.0f ||
                         t.capacity_ah_per_c != 0.0f || t.e0_v_per_c != 0.0f);
}
}  // namespace

std::string missing_temperature_note(const core::MonitorConfig& config, bool log_has_temperature) {
    const core::TemperatureDependence& t = config.extensions.temperature;
    const bool terms = temperature_terms(t);
    // A lumped thermal state drives the terms without a measurement: such a config was made
    // for logs without one.
    if (log_has_temperature || !terms || config.extensions.thermal.enabled) return std::string();
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s (battery.extensions.temperature) but the log has no temperature: it runs at %.3g degC "
                  "throughout", kNoTemperatureStart, static_cast<double>(t.reference_c));
    return std::string(buf) +
           ", and a colder pack's resistance and capacity read as a warm one's: give the log's temperature column "
           "(--temperature-col NAME), or a config without the temperature terms";
}

namespace {
const char* const kSelfHeatingStart = "the config's temperature terms are driven by its self-heating state";
}  // namespace

std::string measured_temperature_note(const core::MonitorConfig& config, bool log_has_temperature) {
    const core::LumpedThermal& th = config.extensions.thermal;
    if (!log_has_temperature || !th.enabled || !temperature_terms(config.extensions.temperature)) return std::string();
    char buf[96];
    std::snprintf(buf, sizeof buf, " (battery.extensions.thermal, from %.3g degC)", static_cast<double>(th.ambient_c));
    return std::string(kSelfHeatingStart) + buf +
           ", as a fit on logs without a temperature makes them, but this log's measured temperature replaces that "
           "state, and terms fitted to the state's rise read the measurement's distance from its ambient as a change "
           "of temperature (flight 30's fitted config, given the flight's 7 degC, ran 9.85 V off the measurement "
           "instead of 0.009 V): read the log with --no-temperature (a manifest's \"no_temperature\"), or use a "
           "config fitted on logs with a temperature";
}

bool is_log_note(const std::string& note) {
    return is_other_pack_note(note) || note.compare(0, std::strlen(kNoTemperatureStart), kNoTemperatureStart) == 0 ||
           note.compare(0, std::strlen(kSelfHeatingStart), kSelfHeatingStart) == 0;
}

std::vector<std::string> config_notes(const core::MonitorConfig& config, const LogFacts& log) {
    std::vector<std::string> notes;
    // A config for another pack runs without complaint (a 4S log with a 6S config read a
    // 0.5 Ah pack and a model error of 256 V), so say what the log shows.
    const int cells = config.cells_in_series;
    // Each such note says how to get the config the log asks for, when it knows the log.
    const std::string advice = log.path.empty() ? std::string(kOtherPackEnd)
                                                : kMakeConfigAdvice + log.path + kMakeConfigAdviceEnd;
    if (log.cells > 0 && log.cells != cells) {
        notes.push_back("the log has " + std::to_string(log.cells) + " cell voltages but the config " +
                        std::to_string(cells) + " cells in series (cells_in_series)" + advice);
    }
    // No LiPo, LiHV or Li-ion cell rests outside this range unless it is damaged.
    constexpr double kRestMinV = 2.9, kRestMaxV = 4.45;
    if (cells > 0 && std::isfinite(log.resting_voltage_v)) {
        const double per_cell_v = log.resting_voltage_v / cells;
        if (per_cell_v < kRestMinV || per_cell_v > kRestMaxV) {
            char buf[160];
            std::snprintf(buf, sizeof buf, "the pack rests at %.2f V, %.3f V per cell for the config's %d cells in series",
                          log.resting_voltage_v, per_cell_v, cells);
            // A thousand times a cell's volts: the log's millivolts, not another pack.
            const bool millivolts = per_cell_v > 1000.0 * kRestMinV && per_cell_v < 1000.0 * kRestMaxV;
            notes.push_back(std::string(buf) + ", outside any lithium cell's resting range (2.9-4.45 V)" +
                            (millivolts ? std::string(kMillivoltsEnd) : advice));
        }
    }
    if (log.declared_cells > 0 && log.declared_cells != cells)
        notes.push_back("the log's autopilot was set for " + std::to_string(log.declared_cells) + " cells (" +
                        log.declared_cells_from + "), the config has " + std::to_string(cells) + advice);
    // Rated capacities differ by a few percent between makers' labels; beyond this it is another pack.
    constexpr double kCapacityTolerance = 0.10;
    const double capacity_ah = config.battery.capacity_ah;
    if (std::isfinite(log.declared_capacity_ah) &&
        std::fabs(log.declared_capacity_ah / capacity_ah - 1.0) > kCapacityTolerance) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "the log's autopilot was set for a %.3g Ah pack (%s), the config's is %.3g Ah",
                      log.declared_capacity_ah, log.declared_capacity_from.c_str(), capacity_ah);
        notes.push_back(buf + advice);
    }
    // Inside the resting range, but only as the lowest charge anybody takes off with, while
    // another cell count puts it in the middle: the config's count is likely wrong (a 3S
    // pack at 3.99 V per cell read as a 4S one at 3.00 V).
    if (cells > 0 && std::isfinite(log.resting_voltage_v) && log.declared_cells == 0 && log.cells == 0) {
        const double per_cell_v = log.resting_voltage_v / cells;
        const int likely = cells_from_resting_voltage(log.resting_voltage_v);
        if (likely > 0 && likely != cells && per_cell_v >= kRestMinV && per_cell_v <= kRestMaxV) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "the pack rests at %.2f V: %.2f V per cell as %d cells, %.2f V as the config's %d",
                          log.resting_voltage_v, log.resting_voltage_v / likely, likely, per_cell_v, cells);
            notes.push_back(buf + advice);
        }
    }
    // The Tremblay model's Q/(Q − it) term runs away as the count nears Q: past it the model
    // voltage reads tens of volts negative (the octocopter log with the default config: a
    // mean error of 105 V), and the error statistics are the model's, not the pack's.
    if (std::isfinite(log.capacity_passed_s)) {
        char buf[120];
        std::snprintf(buf, sizeof buf, "the charge counted since full passed the config's capacity (%.3g Ah) %.1f s into the log",
                      capacity_ah, log.capacity_passed_s);
        notes.push_back(std::string(buf) +
                        ": the model's voltage past there is not a battery's, and voltage_error_v.model counts it (a "
                        "pack not charged full at the start reads so too: the model is no rest curve)");
    }
    // Short of the capacity the same term runs away already: Matrice 100 flight 41, read as
    // 3.93 Ah drawn of 4.65 before take-off, ran 1 V per cell off at 98 % and 105 V off after
    // the landing, 6.3 V on average, with no note (57 likewise).
    // A measured temperature driving terms fitted to a self-heating state runs the model off
    // too, and that note (below) names the cause: this one would point at the capacity.
    const bool self_heating_misread = log.temperature_samples > 0 && !measured_temperature_note(config, true).empty();
    if (!std::isfinite(log.capacity_passed_s) && std::isfinite(log.pole_runaway_s) && !self_heating_misread) {
        char buf[240];
        std::snprintf(buf, sizeof buf,
                      "the config's model ran over 1 V per cell off the measurement %.1f s into the log, with the charge "
                      "counted since full at %.0f %% of the config's capacity (%.3g Ah)",
                      log.pole_runaway_s, 100.0 * log.pole_runaway_share, capacity_ah);
        notes.push_back(std::string(buf) +
                        ": near the capacity the model's voltage runs away, and voltage_error_v.model counts it (a "
                        "capacity set too small, or a pack read as less charged than it is, does this)");
    }
    if (log.temperature_samples == 0) {
        const std::string note = missing_temperature_note(config, false);
        if (!note.empty()) notes.push_back(note);
    }
    if (log.temperature_samples > 0) {
        const std::string note = measured_temperature_note(config, true);
        if (!note.empty()) notes.push_back(note);
    }
    // Without a table the joint estimator reads the state of charge off the Tremblay curve,
    // a fit of a discharge under load, not a rest curve: on the dissertation's flights with
    // configs/reference-modified.json its final capacities read 2.55–3.08 Ah for packs of
    // 1.5–1.6 Ah (1.04–1.65 Ah with a table), and the cell check, whose weak-cell drift is
    // the curve's slope, names cell 2 of the new pack 30 for capacity (nothing with a table).
    // The numbers look as plausible as any others.
    if (config.estimator == core::EstimatorKind::Joint && config.joint.ocv.points < 2) {
        notes.push_back(
            "the joint estimator has no OCV table (joint.ocv_cell_voltage_v) and reads the state of charge off the "
            "Tremblay curve, which is no rest curve: its capacity, state of charge, remaining time and weak-cell verdicts "
            "can be far off (the dissertation's 1.5-1.6 Ah packs read 2.55-3.08 Ah, and a new pack's cell is named "
            "weak). Give the config a table: battsim discharge "
            "--ocv-points N, or battsim fit-ocv");
    }
    return notes;
}

}  // namespace host
}  // namespace battsim
