// `battsim export-config --firmware`: the monitor configuration as a C++ header the
// firmware compiles in, from the same JSON that `battsim` reads, so the device and the
// host run one configuration. The header defines
//     namespace battsim_generated { constexpr battsim::core::MonitorConfig monitor_config(); }
// starting from the core's defaults and assigning every field, floats with the fewest
// digits that read back as the same float (so the firmware's floats equal the host's).
//
// visit_monitor_config() is the one list of MonitorConfig's fields. Tests check that it
// covers every byte of the struct, so a field added to the core without being added here
// fails the build's tests instead of silently keeping its default on the device.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "core/config.h"
#include "host/config_json.h"

namespace battsim {
namespace host {

// The capacity EKF's fields under `prefix` (the tracking, health and verdict filters share them).
template <typename Ekf, typename F>
void visit_ekf_config(const std::string& prefix, Ekf& e, F& f) {
    f(prefix + "voltage_sigma_v", e.voltage_sigma_v);
    f(prefix + "soc_sigma0", e.soc_sigma0);
    f(prefix + "capacity_sigma0_fraction", e.capacity_sigma0_fraction);
    f(prefix + "polarisation_initial_ohm", e.polarisation_initial_ohm);
    f(prefix + "polarisation_sigma0_ohm", e.polarisation_sigma0_ohm);
    f(prefix + "soc_process_per_sqrt_s", e.soc_process_per_sqrt_s);
    f(prefix + "capacity_process_fraction_per_sqrt_s", e.capacity_process_fraction_per_sqrt_s);
    f(prefix + "polarisation_process_ohm_per_sqrt_s", e.polarisation_process_ohm_per_sqrt_s);
    f(prefix + "gate_sigmas", e.gate_sigmas);
    f(prefix + "ocv_soc_sigma", e.ocv_soc_sigma);
    f(prefix + "offset_sigma0_a", e.offset_sigma0_a);
    f(prefix + "offset_process_a_per_sqrt_s", e.offset_process_a_per_sqrt_s);
    f(prefix + "min_capacity_fraction", e.min_capacity_fraction);
    f(prefix + "max_capacity_fraction", e.max_capacity_fraction);
}

// Calls f(path, member) for every field of a MonitorConfig (const or not). Array
// elements come one by one ("joint.ocv.cell_voltage_v[3]").
template <typename Config, typename F>
void visit_monitor_config(Config& c, F&& f) {
    f("estimator", c.estimator);
    f("cells_in_series", c.cells_in_series);
    f("battery.full_voltage_v", c.battery.full_voltage_v);
    f("battery.exponential_voltage_v", c.battery.exponential_voltage_v);
    f("battery.exponential_capacity_ah", c.battery.exponential_capacity_ah);
    f("battery.nominal_zone_voltage_v", c.battery.nominal_zone_voltage_v);
    f("battery.nominal_zone_capacity_ah", c.battery.nominal_zone_capacity_ah);
    f("battery.capacity_ah", c.battery.capacity_ah);
    f("battery.internal_resistance_ohm", c.battery.internal_resistance_ohm);
    f("battery.curve_current_a", c.battery.curve_current_a);
    f("extensions.rc_count", c.extensions.rc_count);
    for (int i = 0; i < core::kMaxRcBranches; ++i) {
        const std::string b = "extensions.rc[" + std::to_string(i) + "].";
        f(b + "resistance_ohm", c.extensions.rc[i].resistance_ohm);
        f(b + "time_constant_s", c.extensions.rc[i].time_constant_s);
    }
    f("extensions.temperature.enabled", c.extensions.temperature.enabled);
    f("extensions.temperature.reference_c", c.extensions.temperature.reference_c);
    f("extensions.temperature.resistance_activation_k", c.extensions.temperature.resistance_activation_k);
    f("extensions.temperature.polarisation_activation_k", c.extensions.temperature.polarisation_activation_k);
    f("extensions.temperature.capacity_ah_per_c", c.extensions.temperature.capacity_ah_per_c);
    f("extensions.temperature.e0_v_per_c", c.extensions.temperature.e0_v_per_c);
    f("extensions.thermal.enabled", c.extensions.thermal.enabled);
    f("extensions.thermal.ambient_c", c.extensions.thermal.ambient_c);
    f("extensions.thermal.thermal_resistance_k_per_w", c.extensions.thermal.thermal_resistance_k_per_w);
    f("extensions.thermal.time_constant_s", c.extensions.thermal.time_constant_s);
    f("extensions.hysteresis.magnitude_v", c.extensions.hysteresis.magnitude_v);
    f("extensions.hysteresis.rate_per_ah", c.extensions.hysteresis.rate_per_ah);
    f("extensions.ocv.count", c.extensions.ocv.count);
    f("extensions.ocv.span_ah", c.extensions.ocv.span_ah);
    for (int i = 0; i < core::kMaxOcvPoints; ++i) {
        f("extensions.ocv.delta_v[" + std::to_string(i) + "]", c.extensions.ocv.delta_v[i]);
    }
    f("extensions.current_sensor.gain", c.extensions.current_sensor.gain);
    f("extensions.current_sensor.offset_a", c.extensions.current_sensor.offset_a);
    f("extensions.current_sensor.lead_s", c.extensions.current_sensor.lead_s);
    f("max_voltage_v", c.max_voltage_v);
    f("min_voltage_v", c.min_voltage_v);
    f("current_filter.time_constant_s", c.current_filter.time_constant_s);
    f("resistance.filter_time_constant_s", c.resistance.filter_time_constant_s);
    f("resistance.max_filter_alpha", c.resistance.max_filter_alpha);
    f("resistance.blend_gain", c.resistance.blend_gain);
    f("resistance.initial_resistance_ohm", c.resistance.initial_resistance_ohm);
    f("resistance.min_current_a", c.resistance.min_current_a);
    f("capacity.max_voltage_variance_v", c.capacity.max_voltage_variance_v);
    f("capacity.capacity_step_fraction", c.capacity.capacity_step_fraction);
    f("capacity.persistence_updates", c.capacity.persistence_updates);
    f("capacity.min_capacity_fraction", c.capacity.min_capacity_fraction);
    f("capacity.max_capacity_fraction", c.capacity.max_capacity_fraction);
    f("capacity.resistance_keeps_e0", c.capacity.resistance_keeps_e0);
    f("flight_time.min_flight_voltage_v", c.flight_time.min_flight_voltage_v);
    f("flight_time.nominal_voltage_v", c.flight_time.nominal_voltage_v);
    f("flight_time.step_fraction", c.flight_time.step_fraction);
    f("flight_time.max_capacity_factor", c.flight_time.max_capacity_factor);
    f("current_average.short_time_s", c.current_average.short_time_s);
    f("current_average.long_time_s", c.current_average.long_time_s);
    f("current_average.initial_value", c.current_average.initial_value);
    f("power_average.short_time_s", c.power_average.short_time_s);
    f("power_average.long_time_s", c.power_average.long_time_s);
    f("power_average.initial_value", c.power_average.initial_value);
    f("flying.min_flying_current_a", c.flying.min_flying_current_a);
    f("flying.landed_hold_s", c.flying.landed_hold_s);
    f("flying.takeoff_confirm_s", c.flying.takeoff_confirm_s);
    f("initial.max_resting_current_a", c.initial.max_resting_current_a);
    f("initial.stabilisation_time_s", c.initial.stabilisation_time_s);
    f("cells.min_std_v", c.cells.min_std_v);
    f("joint.resistance.lag_s", c.joint.resistance.lag_s);
    f("joint.resistance.memory_s", c.joint.resistance.memory_s);
    f("joint.resistance.min_step_a", c.joint.resistance.min_step_a);
    f("joint.resistance.min_excitation_a2", c.joint.resistance.min_excitation_a2);
    f("joint.resistance.initial_resistance_ohm", c.joint.resistance.initial_resistance_ohm);
    f("joint.resistance.trend_sigma_per_s", c.joint.resistance.trend_sigma_per_s);
    f("joint.hover_resistance.lag_s", c.joint.hover_resistance.lag_s);
    f("joint.hover_resistance.memory_s", c.joint.hover_resistance.memory_s);
    f("joint.hover_resistance.min_step_a", c.joint.hover_resistance.min_step_a);
    f("joint.hover_resistance.min_excitation_a2", c.joint.hover_resistance.min_excitation_a2);
    f("joint.hover_resistance.initial_resistance_ohm", c.joint.hover_resistance.initial_resistance_ohm);
    f("joint.hover_resistance.trend_sigma_per_s", c.joint.hover_resistance.trend_sigma_per_s);
    visit_ekf_config("joint.ekf.", c.joint.ekf, f);
    // The health and verdict filters: the same fields.
    const char* const names[2] = {"joint.health.", "joint.verdict."};
    decltype(&c.joint.health) const filters[2] = {&c.joint.health, &c.joint.verdict};
    for (int k = 0; k < 2; ++k) {
        auto& h = *filters[k];
        const std::string p = names[k];
        f(p + "enabled", h.enabled);
        visit_ekf_config(p + "ekf.", h.ekf, f);
        f(p + "polarisation_time_s", h.polarisation_time_s);
        f(p + "polarisation_slow_time_s", h.polarisation_slow_time_s);
        f(p + "polarisation_slow_share", h.polarisation_slow_share);
        f(p + "polarisation_follows_resistance", h.polarisation_follows_resistance);
        f(p + "first_resistance_soc_correction", h.first_resistance_soc_correction);
        f(p + "solves_from_takeoff_soc", h.solves_from_takeoff_soc);
        f(p + "takeoff_soc_min_ground_s", h.takeoff_soc_min_ground_s);
    }
    f("joint.ocv.points", c.joint.ocv.points);
    for (int i = 0; i < core::kOcvTableMaxPoints; ++i) {
        f("joint.ocv.cell_voltage_v[" + std::to_string(i) + "]", c.joint.ocv.cell_voltage_v[i]);
    }
    f("joint.resistance_prior_fraction", c.joint.resistance_prior_fraction);
    f("joint.polarisation_time_s", c.joint.polarisation_time_s);
    f("joint.polarisation_slow_time_s", c.joint.polarisation_slow_time_s);
    f("joint.polarisation_slow_share", c.joint.polarisation_slow_share);
    f("joint.min_voltage_v", c.joint.min_voltage_v);
    f("joint.solver_steps", c.joint.solver_steps);
    f("joint.cutoff_delay_s", c.joint.cutoff_delay_s);
    f("joint.health_time_share", c.joint.health_time_share);
    f("joint.health_time_fade_fraction", c.joint.health_time_fade_fraction);
    f("joint.gap_charge_sigma_fraction", c.joint.gap_charge_sigma_fraction);
    f("joint.gap_hold_s", c.joint.gap_hold_s);
    f("joint.solver_steps_per_update", c.joint.solver_steps_per_update);
    f("joint.short_flight_fraction", c.joint.short_flight_fraction);
    f("joint.cause_fraction", c.joint.cause_fraction);
    f("joint.min_flight_s", c.joint.min_flight_s);
    f("joint.persistence", c.joint.persistence);
    f("joint.max_sample_gap_s", c.joint.max_sample_gap_s);
    f("joint.min_flying_current_a", c.joint.min_flying_current_a);
    f("joint.landed_hold_s", c.joint.landed_hold_s);
    f("joint.offset_fault_a", c.joint.offset_fault_a);
    f("joint.learn_offset_in_flight", c.joint.learn_offset_in_flight);
    f("joint.polarisation_follows_resistance", c.joint.polarisation_follows_resistance);
    f("joint.first_resistance_soc_correction", c.joint.first_resistance_soc_correction);
    f("joint.offset_learn_max_current_a", c.joint.offset_learn_max_current_a);
    f("joint.rest_capacity_min_rest_s", c.joint.rest_capacity_min_rest_s);
    f("joint.rest_capacity_max_current_a", c.joint.rest_capacity_max_current_a);
    f("joint.rest_capacity_min_soc_drop", c.joint.rest_capacity_min_soc_drop);
    f("joint.capacity_sigma_fraction_of_charge", c.joint.capacity_sigma_fraction_of_charge);
    f("joint.ground_soc_process_scale", c.joint.ground_soc_process_scale);
    f("joint.resistance_settle_s", c.joint.resistance_settle_s);
    f("cell_analysis.lag_s", c.cell_analysis.lag_s);
    f("cell_analysis.min_step_a", c.cell_analysis.min_step_a);
    f("cell_analysis.min_excitation_a2", c.cell_analysis.min_excitation_a2);
    f("cell_analysis.min_pairs", c.cell_analysis.min_pairs);
    f("cell_analysis.current_ridge_a2", c.cell_analysis.current_ridge_a2);
    f("cell_analysis.slow_current_ridge_a2", c.cell_analysis.slow_current_ridge_a2);
    f("cell_analysis.tap_artifact_ratio", c.cell_analysis.tap_artifact_ratio);
    f("cell_analysis.slow_current_time_s", c.cell_analysis.slow_current_time_s);
    f("cell_analysis.resistance_ratio", c.cell_analysis.resistance_ratio);
    f("cell_analysis.capacity_deficit", c.cell_analysis.capacity_deficit);
    f("cell_analysis.min_charge_ah", c.cell_analysis.min_charge_ah);
    f("cell_analysis.min_drift_v", c.cell_analysis.min_drift_v);
    f("cell_analysis.significance_sigmas", c.cell_analysis.significance_sigmas);
    f("cell_analysis.capacity_significance_sigmas", c.cell_analysis.capacity_significance_sigmas);
    f("cell_analysis.pack_deficit_sigmas", c.cell_analysis.pack_deficit_sigmas);
    f("cell_analysis.last_cell_includes_lead", c.cell_analysis.last_cell_includes_lead);
    f("cell_analysis.first_cell_includes_lead", c.cell_analysis.first_cell_includes_lead);
    f("cell_analysis.last_lead_excess", c.cell_analysis.last_lead_excess);
    f("cell_analysis.first_lead_excess", c.cell_analysis.first_lead_excess);
    f("cell_analysis.lead_excess_sigma", c.cell_analysis.lead_excess_sigma);
    f("cell_analysis.step.min_step_a", c.cell_analysis.step.min_step_a);
    f("cell_analysis.step.steady_band_a", c.cell_analysis.step.steady_band_a);
    f("cell_analysis.step.steady_band_fraction", c.cell_analysis.step.steady_band_fraction);
    f("cell_analysis.step.noise_floor_v", c.cell_analysis.step.noise_floor_v);
    f("cell_analysis.step.max_wait_samples", c.cell_analysis.step.max_wait_samples);
    f("warnings.low_capacity_fraction", c.warnings.low_capacity_fraction);
    f("warnings.high_resistance_factor", c.warnings.high_resistance_factor);
    f("warnings.min_resistance_updates", c.warnings.min_resistance_updates);
    f("warnings.cell_outlier_score", c.warnings.cell_outlier_score);
    f("warnings.min_cell_outlier_samples", c.warnings.min_cell_outlier_samples);
    f("sensor.max_pack_voltage_v", c.sensor.max_pack_voltage_v);
    f("sensor.min_pack_voltage_v", c.sensor.min_pack_voltage_v);
    f("sensor.max_current_a", c.sensor.max_current_a);
    f("sensor.min_current_a", c.sensor.min_current_a);
    f("sensor.min_cell_voltage_v", c.sensor.min_cell_voltage_v);
    f("sensor.max_cell_voltage_v", c.sensor.max_cell_voltage_v);
    f("sensor.max_cell_sum_error_v", c.sensor.max_cell_sum_error_v);
    f("shunt.offset_ma", c.shunt.offset_ma);
    f("shunt.scale_mv_per_10a", c.shunt.scale_mv_per_10a);
}

// One field's value as text in C++ source form ("1.55f", "4", "true",
// "static_cast<battsim::core::EstimatorKind>(1)"), by path, in visiting order.
struct ConfigField {
    std::string path;
    std::string cpp_value;
};
std::vector<ConfigField> monitor_config_fields(const core::MonitorConfig& c);

// The shortest decimal that reads back as exactly `v` (9 significant digits at most),
// as a C++ float literal. Throws std::invalid_argument for NaN or infinity.
std::string float_literal(float v);

// The whole header. `source` names the JSON in the header's comment. Throws
// std::invalid_argument if a value cannot be written (not finite).
std::string firmware_config_header(const LoadedConfig& config, const std::string& source);

// Loads `json_path` (throws ConfigError) and writes the header to `out_path` atomically
// ("-" = standard output; throws std::runtime_error when it cannot write). `estimator`
// ("reference" or "joint") overrides the config's, as `battsim replay --estimator` does;
// empty keeps it (anything else: std::invalid_argument). Returns the config's notes
// (config_notes) for the user.
std::vector<std::string> export_firmware_config(const std::string& json_path, const std::string& out_path,
                            const std::string& estimator = "");

// What the reference hardware cannot do with a pack so configured, or empty when it can: its
// three INA3221 taps read 2 to 4 cells; its INA226 bus, packs up to 36 V.
std::string reference_taps_note(const core::MonitorConfig& config);
std::string reference_bus_note(const core::MonitorConfig& config);

}  // namespace host
}  // namespace battsim
