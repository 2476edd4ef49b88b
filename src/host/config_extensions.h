// The optional model extensions in the config JSON, under "battery": {"extensions": {...}}:
//
//   "extensions": {
//     "rc_branches":    [{"resistance_ohm": 0.004, "time_constant_s": 3.0}, ...],   (≤ 3)
//     "temperature":    {"reference_c": 25, "resistance_activation_k": 3000,
//                        "polarisation_activation_k": 4000, "capacity_ah_per_c": 0.004,
//                        "e0_v_per_c": 0.0002},
//     "thermal":        {"ambient_c": 7, "thermal_resistance_k_per_w": 2,
//                        "time_constant_s": 900},
//     "hysteresis":     {"magnitude_v": 0.01, "rate_per_ah": 20},
//     "ocv_correction": {"span_ah": 1.5, "delta_v": [0.0, -0.01, ...]},          (2..16)
//     "current_sensor": {"gain": 1.0, "offset_a": 0.0, "lead_s": 0.0}
//   }
//
// A missing member leaves that extension off; "temperature" and "thermal" are enabled by
// being present. Unknown keys are errors, as in the rest of the config.
//
// Until config_json.cpp parses this itself, load_extended_config*() take the extensions out
// of the JSON, hand the rest to config_from_json() and parse them here.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "core/model/extensions/extended_model.h"
#include "host/config_json.h"

namespace battsim {
namespace host {

struct ExtendedConfig {
    LoadedConfig config;
    core::ModelExtensions extensions;
};

// Parses the "extensions" object; `where` is its JSON path for messages. Throws ConfigError.
core::ModelExtensions extensions_from_json(const nlohmann::json& j, const std::string& origin,
                                           const std::string& where = "$.battery.extensions");
// Only the extensions that are on; an empty object when none is.
nlohmann::json extensions_to_json(const core::ModelExtensions& e);
// True if any extension changes the model voltage or the current.
bool extensions_active(const core::ModelExtensions& e);

ExtendedConfig extended_config_from_json(const nlohmann::json& j, const std::string& origin);
ExtendedConfig load_extended_config_file(const std::string& path);
// config_to_json() plus "battery.extensions" when any is on.
nlohmann::json extended_config_to_json(const ExtendedConfig& c);

}  // namespace host
}  // namespace battsim
