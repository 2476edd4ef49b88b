// The current sensor against the charger's count. A current-sensor gain error reads to the
// voltage as a capacity and resistance error of the same size, so no monitor can flag it in
// flight (docs/estimator.md, twenty-fourth session); the charge a charger puts back after the
// flight is a second, independent count of the same charge. The monitor's count over the log
// (the summary's `consumed`, less the charge it read as missing at start) over the charger's
// is the sensor's gain, an offset's charge included.
#pragma once
#include <nlohmann/json.hpp>

#include "core/config.h"

namespace battsim {
namespace host {

struct ChargerCheckOptions {
    double charged_ah = 0;      // what the charger put back, the pack charged full before the log
    double tolerance = 0.03;    // |counted / charged − 1| beyond this is a sensor fault
    double current_gain = 1.0;  // the config's current-sensor gain (battery.extensions.current_sensor.gain)
};

// The check as JSON (`charger_check` in the summary): charged_ah, counted_ah, ratio,
// tolerance, current_gain, suggested_current_gain (current_gain × charged / counted), fault,
// notes. No verdict (fault null, no suggestion) when the pack was not full at the start; no
// suggestion after an in-flight sensor fault. Throws std::invalid_argument when there is
// nothing to compare (no charge, none counted) or the options are out of range.
nlohmann::json charger_check(const nlohmann::json& summary, const ChargerCheckOptions& options);

// What `replay --charged-mah` and a manifest's `charged_mah` both do: the check with the
// config's current-sensor gain, added to the summary as `charger_check`. Throws as above.
void add_charger_check(nlohmann::json& summary, double charged_mah, double tolerance, const core::MonitorConfig& config);

}  // namespace host
}  // namespace battsim
