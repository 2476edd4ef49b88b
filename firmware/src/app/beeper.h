// The buzzer: a LiPo alarm that knows what the monitor knows. FPV pilots fly with a
// balance-lead voltage alarm; this one also beeps a verdict the voltage cannot give yet.
//
// In flight, below the remaining-flight-time thresholds: a chirp every 2 s (LOW), fast
// beeping (CRITICAL). When a warning is raised, long beeps: three for a short flight (or,
// with the reference estimator, low capacity or high resistance), two for a weak cell, one
// for a sensor fault; again every repeat_s while it stays active in flight. Swapped shunt
// sense wires (telemetry::ReversedCurrentCheck) beep as a sensor fault does, on the ground
// too (the monitor sees no take-off through them), again every repeat_s. Time is the
// samples' own, so the pattern is the same on the device and on the host. The thresholds
// and the repeat are the config's `telemetry` section's, which the ground station's
// charge state and texts use too.
#pragma once
#include <stdint.h>

#include "core/monitor.h"
#include "telemetry/mavlink.h"
#include "telemetry/warning_schedule.h"

namespace battsim {
namespace fw {

class Beeper {
public:
    static constexpr uint32_t kLongOnMs = 400;   // a long beep
    static constexpr uint32_t kLongGapMs = 500;  // between long beeps (and after the last): longer than the logger's 0.35 s gaps
    static constexpr uint32_t kChirpOnMs = 100, kChirpPeriodMs = 2000;  // LOW
    static constexpr uint32_t kFastOnMs = 200, kFastPeriodMs = 400;     // CRITICAL

    void configure(const telemetry::TelemetryConfig& config, const core::MonitorConfig& monitor);
    // After each monitor update: whether the buzzer sounds until the next sample.
    // current_reversed: the firmware's ReversedCurrentCheck (latched for the boot).
    bool update(const core::MonitorStatus& status, bool current_reversed = false);
    // Long beeps announcing warning `w`.
    static int long_beeps(core::Warning w);

private:
    float low_time_s_ = 0.0f;
    float critical_time_s_ = 0.0f;
    telemetry::WarningSchedule schedule_;  // the same rule as the ground station's texts
    uint8_t pending_ = 0;                  // warnings waiting for their pattern
    uint64_t pattern_start_us_ = 0;
    int pattern_beeps_ = 0;  // long beeps of the pattern under way (0: none)
    bool reversed_told_ = false;
    uint64_t reversed_told_us_ = 0;
};

}  // namespace fw
}  // namespace battsim
