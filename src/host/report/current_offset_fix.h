// The current-sensor offset a replay learnt on the ground, turned into a config correction.
// The joint estimator learns it from the resting pack's state of charge before the take-off
// and calls it a sensor fault beyond joint.offset_fault_a; the config's
// extensions.current_sensor.offset_a takes it out of every later flight (and, through
// export-config, out of the firmware's).
#pragma once
#include <nlohmann/json.hpp>

#include "core/config.h"

namespace battsim {
namespace host {

// When the summary's sensor_fault names a current offset, moves the config's offset by it
// (the estimator learns the offset of the already corrected current, so the two add) and
// returns the offset taken out, in A; otherwise leaves the config alone and returns 0.
double correct_current_offset(const nlohmann::json& summary, core::MonitorConfig& config);

}  // namespace host
}  // namespace battsim
