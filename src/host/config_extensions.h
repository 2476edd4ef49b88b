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
// being present. Unknown keys are errors, as in the rest of the config. config_json.cpp
// reads and writes this block as part of the battery section (core::MonitorConfig::extensions).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "core/model/extensions/extended_model.h"

namespace battsim {
namespace host {

// Parses the "extensions" object; `where` is its JSON path for messages. Throws ConfigError.
core::ModelExtensions extensions_from_json(const nlohmann::json& j, const std::string& origin,
                                           const std::string& where = "$.battery.extensions");
// Only the extensions that are on; an empty object when none is.
nlohmann::json extensions_to_json(const core::ModelExtensions& e);

}  // namespace host
}  // namespace battsim
