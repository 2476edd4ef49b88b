// What `battsim replay --config-out` writes: the config the replay ran on, as its file has
// it, with the current-sensor corrections the replay found (the gain the charger check
// suggests, the offset the joint estimator learnt on the ground and called a fault).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "host/config_json.h"

namespace battsim {
namespace host {

struct ConfigCorrections {
    LoadedConfig config;          // the config to write, corrections applied
    bool gain_taken = false;      // extensions.current_sensor.gain set to the suggested gain
    double offset_taken_a = 0.0;  // the learnt offset taken out of extensions.current_sensor.offset_a; 0: none
    // Written only with a correction: a config carrying a gain fitted to an offset, or to a
    // pack that was not full, would be wrong on every later flight.
    bool found() const { return gain_taken || offset_taken_a != 0.0; }
};

// The config as its file (config_path; empty: the built-in one) has it: the run's, but with
// the file's estimator when --estimator chose the run's (written, it had switched every later
// replay of the file). Reads the file again only then; throws ConfigError if it no longer reads.
LoadedConfig filed_config(const LoadedConfig& run_config, const std::string& config_path, bool estimator_given);

// `filed` with the corrections `summary` holds: replay's summary, with its charger_check when
// the charge was checked (add_charger_check).
ConfigCorrections with_corrections(const LoadedConfig& filed, const nlohmann::json& summary);

}  // namespace host
}  // namespace battsim
