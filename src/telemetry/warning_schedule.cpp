#include "telemetry/warning_schedule.h"

namespace battsim {
namespace telemetry {
namespace {

uint64_t microseconds(float s) { return s > 0.0f ? static_cast<uint64_t>(s * 1.0e6f) : 0u; }

}  // namespace

void WarningSchedule::configure(float repeat_s, float clear_hold_s, const core::MonitorConfig& monitor) {
    repeat_us_ = microseconds(repeat_s);
    clear_hold_us_ = microseconds(clear_hold_s);
    short_flight_fraction_ = monitor.joint.short_flight_fraction;
    withdrawable_ = monitor.estimator == core::EstimatorKind::Joint ? kWithdrawableJoint : kWithdrawableReference;
    raised_ = told_ = withdrawn_ = withdrawn_now_ = 0;
    for (uint64_t& t : told_us_) t = 0;
    for (uint64_t& t : off_since_us_) t = 0;
}

uint8_t WarningSchedule::due(const core::MonitorStatus& status) {
    constexpr uint8_t kShort = 1u << core::kWarnShortFlight;
    constexpr uint8_t kCauses = (1u << core::kWarnLowCapacity) | (1u << core::kWarnHighResistance);
    // A withdrawn verdict that holds again is news again, whatever the repeat says.
    const uint8_t back = static_cast<uint8_t>(status.warnings & withdrawn_);
    withdrawn_ = static_cast<uint8_t>(withdrawn_ & ~back);
    uint8_t fresh = static_cast<uint8_t>((status.warnings_raised & ~raised_) | back);
    if (fresh & kShort) fresh = static_cast<uint8_t>(fresh & ~kCauses);
    uint8_t again = 0;
    // In the air only: on the ground the charge state (UNHEALTHY) keeps saying it.
    for (int w = 0; w < core::kWarnCount && repeat_us_ > 0 && status.flying; ++w) {
        const uint8_t bit = static_cast<uint8_t>(1u << w);
        if ((raised_ & bit) && !(back & bit) && (status.warnings & bit) && status.time_us >= told_us_[w] + repeat_us_)
            again |= bit;
    }
    if (status.warnings & kShort) again = static_cast<uint8_t>(again & ~kCauses);
    raised_ = status.warnings_raised;

    withdrawn_now_ = 0;
    const bool reads_short = status.expected_time_s > 0.0f && status.total_time_s > 0.0f &&
                             status.total_time_s < (short_flight_fraction_ + kClearMargin) * status.expected_time_s;
    for (int w = 0; w < core::kWarnCount && clear_hold_us_ > 0; ++w) {
        const uint8_t bit = static_cast<uint8_t>(1u << w);
        const bool on = (status.warnings & bit) || (w == core::kWarnShortFlight && reads_short);
        if (!(withdrawable_ & told_ & bit) || on || !status.flying) {
            off_since_us_[w] = 0;  // on, never told, or on the ground (the charge state says it there)
            continue;
        }
        if (off_since_us_[w] == 0) off_since_us_[w] = status.time_us > 0 ? status.time_us : 1;
        if (status.time_us >= off_since_us_[w] + clear_hold_us_) withdrawn_now_ |= bit;
    }
    // The short flight's withdrawal speaks for its causes.
    if (withdrawn_now_ & kShort) {
        withdrawn_ |= static_cast<uint8_t>(told_ & kCauses);
        told_ = static_cast<uint8_t>(told_ & ~kCauses);
        withdrawn_now_ = static_cast<uint8_t>(withdrawn_now_ & ~kCauses);
    }
    withdrawn_ |= withdrawn_now_;
    told_ = static_cast<uint8_t>(told_ & ~withdrawn_now_);
    return static_cast<uint8_t>(fresh | again);
}

}  // namespace telemetry
}  // namespace battsim
