#include "telemetry/warning_schedule.h"

namespace battsim {
namespace telemetry {

void WarningSchedule::configure(float repeat_s) {
    repeat_us_ = repeat_s > 0.0f ? static_cast<uint64_t>(repeat_s * 1.0e6f) : 0u;
    raised_ = 0;
    for (uint64_t& t : told_us_) t = 0;
}

uint8_t WarningSchedule::due(const core::MonitorStatus& status) {
    constexpr uint8_t kShort = 1u << core::kWarnShortFlight;
    constexpr uint8_t kCauses = (1u << core::kWarnLowCapacity) | (1u << core::kWarnHighResistance);
    uint8_t fresh = static_cast<uint8_t>(status.warnings_raised & ~raised_);
    if (fresh & kShort) fresh = static_cast<uint8_t>(fresh & ~kCauses);
    uint8_t again = 0;
    // In the air only: on the ground the charge state (UNHEALTHY) keeps saying it.
    for (int w = 0; w < core::kWarnCount && repeat_us_ > 0 && status.flying; ++w) {
        const uint8_t bit = static_cast<uint8_t>(1u << w);
        if ((raised_ & bit) && (status.warnings & bit) && status.time_us >= told_us_[w] + repeat_us_) again |= bit;
    }
    if (status.warnings & kShort) again = static_cast<uint8_t>(again & ~kCauses);
    raised_ = status.warnings_raised;
    return static_cast<uint8_t>(fresh | again);
}

}  // namespace telemetry
}  // namespace battsim
