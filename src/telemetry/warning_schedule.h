// When to tell the pilot about a warning, shared by the MAVLink texts and the buzzer: when it
// is first raised, and in flight again every repeat_s while it stays active (a link loses
// frames, a beep is missed). A short flight names its cause, so a cause raised with it, or
// active while it is, is never told on its own. Time is the samples' own.
//
// A health verdict can clear in flight (a cold pack's resistance falls as it warms): one that
// was told and has stayed off for clear_hold_s in the air is withdrawn, so the pilot does not
// land early on a verdict the monitor no longer holds, and told afresh if it comes back.
#pragma once
#include <stdint.h>

#include "core/monitor.h"

namespace battsim {
namespace telemetry {

class WarningSchedule {
public:
    // The verdicts that can be withdrawn: the joint estimator's short flight, or the
    // reference estimator's low capacity and high resistance. Not the joint estimator's
    // causes (a cause giving way to another is no withdrawal of the verdict), nor the sensor
    // and cell warnings (a gap is over at the next sample; a named cell is worth measuring).
    static constexpr uint8_t kWithdrawableJoint = 1u << core::kWarnShortFlight;
    static constexpr uint8_t kWithdrawableReference = (1u << core::kWarnLowCapacity) | (1u << core::kWarnHighResistance);

    // repeat_s 0: each warning once; clear_hold_s 0: never withdrawn. A short flight is off
    // only while its verdict's reading is clear of the bar too (total ≥ short_flight_fraction
    // + kClearMargin of a healthy pack's): the verdict clears on one round but takes three to
    // hold again, and a flight reading 19–21 % short would be withdrawn and warned in turn.
    static constexpr float kClearMargin = 0.05f;
    void configure(float repeat_s, float clear_hold_s, const core::MonitorConfig& monitor);
    // The warnings to tell now (bit per core::Warning); call once per monitor update.
    uint8_t due(const core::MonitorStatus& status);
    // The warnings withdrawn by the last due(): told, then off in flight for clear_hold_s.
    // Never a warning due in the same update.
    uint8_t withdrawn() const { return withdrawn_now_; }
    // The repeat (µs; 0: once), for a message of the caller's own that follows the same rule.
    uint64_t repeat_us() const { return repeat_us_; }
    // Warning `w` was told at `time_us`: its next repeat counts from here.
    void told(int w, uint64_t time_us) {
        told_us_[w] = time_us;
        told_ |= static_cast<uint8_t>(1u << w);
    }

private:
    uint64_t repeat_us_ = 0;
    uint64_t clear_hold_us_ = 0;
    float short_flight_fraction_ = 0.8f;
    uint8_t withdrawable_ = 0;
    uint8_t raised_ = 0;         // warnings raised so far
    uint8_t told_ = 0;           // told and not withdrawn since
    uint8_t withdrawn_ = 0;      // withdrawn and not active since
    uint8_t withdrawn_now_ = 0;  // withdrawn by the last due()
    uint64_t told_us_[core::kWarnCount] = {};
    uint64_t off_since_us_[core::kWarnCount] = {};  // when a told warning went off in flight (0: on)
};

}  // namespace telemetry
}  // namespace battsim
