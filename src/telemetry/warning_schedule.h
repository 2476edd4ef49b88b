// When to tell the pilot about a warning, shared by the MAVLink texts and the buzzer: when it
// is first raised, and in flight again every repeat_s while it stays active (a link loses
// frames, a beep is missed). A short flight names its cause, so a cause raised with it, or
// active while it is, is never told on its own. Time is the samples' own.
#pragma once
#include <stdint.h>

#include "core/monitor.h"

namespace battsim {
namespace telemetry {

class WarningSchedule {
public:
    void configure(float repeat_s);  // 0: each warning once
    // The warnings to tell now (bit per core::Warning); call once per monitor update.
    uint8_t due(const core::MonitorStatus& status);
    // Warning `w` was told at `time_us`: its next repeat counts from here.
    void told(int w, uint64_t time_us) { told_us_[w] = time_us; }

private:
    uint64_t repeat_us_ = 0;
    uint8_t raised_ = 0;  // warnings raised so far
    uint64_t told_us_[core::kWarnCount] = {};
};

}  // namespace telemetry
}  // namespace battsim
