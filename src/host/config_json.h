// Monitor configuration from and to JSON (schema "battsim.config", version 1). Unknown
// keys are errors, so a typo never silently falls back to a default.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/config.h"
#include "host/config_reader.h"  // ConfigError
#include "telemetry/mavlink.h"

namespace battsim {
namespace host {

// The lowest pack voltage per cell a reading can be true at: Li-ion is flown to 2.5 V per
// cell, and sag under a punch goes briefly below (the dissertation's sad 4S pack reached
// 2.65 V per cell under load). Below this a sample is a glitch, kept out of the estimators:
// a config without sensor.min_pack_voltage_v reads it so, and make-config writes it.
constexpr float kGlitchFloorCellV = 2.0f;

struct LoadedConfig {
    std::string name;
    std::string description;
    core::MonitorConfig monitor;
    telemetry::TelemetryConfig telemetry;  // the MAVLink output (section "telemetry")
};

// `origin` names the source in messages (a file path).
LoadedConfig config_from_json(const nlohmann::json& j, const std::string& origin);
LoadedConfig load_config_file(const std::string& path);
nlohmann::json config_to_json(const LoadedConfig& config);
// The defaults every config file starts from (the reference 4S pack's curve, hand-modified
// parameters).
LoadedConfig default_config();
// The config of a command given no -c: configs/reference-modified.json, the dissertation's own
// pack and logger (the defaults plus its take-off confirmation, remembered power and first-cell lead).
LoadedConfig builtin_config();

// What a valid config still does badly, as sentences for the user (empty: nothing): the
// joint estimator without an OCV table; and, given what a log shows (its cell columns, 0 =
// none; its first voltage at rest, NaN = not at rest), a config for another pack. `replay`
// puts them in the summary's `config_notes`; `export-config` prints them.
struct LogFacts {
    int cells = 0;
    double resting_voltage_v = NAN;
    // What the log's autopilot was set for (pack_config.h, log_pack()), with the parameter
    // it came from; and the log's path, for the advice.
    int declared_cells = 0;
    std::string declared_cells_from;
    double declared_capacity_ah = NAN;
    std::string declared_capacity_from;
    std::string path;
    // Log time (s) at which the charge counted since full first passed the config's
    // capacity; NaN = never.
    double capacity_passed_s = NAN;
    // Log time (s) at which the configured model, the count past kPoleShare of the capacity,
    // first ran more than 1 V per cell off the measurement, and the count's share then; NaN = never.
    static constexpr double kPoleShare = 0.8;
    double pole_runaway_s = NAN;
    double pole_runaway_share = NAN;
    // Samples that carry a temperature; -1 = no log read.
    long temperature_samples = -1;
};
std::vector<std::string> config_notes(const core::MonitorConfig& config, const LogFacts& log = LogFacts());
// Whether a note of config_notes says the config is for another pack than the log's (its
// cell count, its resting voltage, what its autopilot was set for).
bool is_other_pack_note(const std::string& note);
// Whether it is the one that asks whether the log's voltage is in mV (a rest a thousand times a cell's).
bool is_millivolts_note(const std::string& note);
// The note config_notes makes when the config's model depends on the temperature
// (battery.extensions.temperature, with no lumped thermal state to drive it) and the log
// carries none: the model then runs at its reference temperature throughout, and a cold
// pack reads as a warm one. Empty when that is not so.
std::string missing_temperature_note(const core::MonitorConfig& config, bool log_has_temperature);
// The note config_notes makes when the config's temperature terms are driven by its lumped
// thermal state (battery.extensions.thermal: a fit on logs without a temperature) and the log
// carries one, which replaces that state: terms fitted to the state's rise from its ambient
// read the measurement's distance from that ambient as a change of temperature. Empty when
// that is not so.
std::string measured_temperature_note(const core::MonitorConfig& config, bool log_has_temperature);
// Whether a note of config_notes is about the log read with the config, not the config alone:
// is_other_pack_note, missing_temperature_note's or measured_temperature_note's.
bool is_log_note(const std::string& note);

}  // namespace host
}  // namespace battsim
