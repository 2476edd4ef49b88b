#include "app/beeper.h"

namespace battsim {
namespace fw {
namespace {

uint64_t us(uint32_t ms) { return static_cast<uint64_t>(ms) * 1000u; }

}  // namespace

void Beeper::configure(const telemetry::TelemetryConfig& config, const core::MonitorConfig& monitor) {
    low_time_s_ = config.low_time_s;
    critical_time_s_ = config.critical_time_s;
    // As the texts: a verdict back after its withdrawal beeps at once.
    schedule_.configure(config.text_repeat_s, config.clear_hold_s, monitor);
    pending_ = 0;
    pattern_start_us_ = 0;
    pattern_beeps_ = 0;
    reversed_told_ = false;
    reversed_told_us_ = 0;
}

int Beeper::long_beeps(core::Warning w) {
    switch (w) {
        case core::kWarnShortFlight:
        case core::kWarnLowCapacity:
        case core::kWarnHighResistance:
            return 3;
        case core::kWarnCellOutlier:
            return 2;
        case core::kWarnSensorFault:
            return 1;
        default:
            return 0;
    }
}

bool Beeper::update(const core::MonitorStatus& status, bool current_reversed) {
    const uint64_t t = status.time_us;
    pending_ |= schedule_.due(status);
    const uint64_t long_us = us(kLongOnMs + kLongGapMs);
    if (pattern_beeps_ > 0 && t >= pattern_start_us_ + static_cast<uint64_t>(pattern_beeps_) * long_us) pattern_beeps_ = 0;
    if (pattern_beeps_ == 0 && pending_ != 0) {
        // The most beeps first: a short flight before a weak cell before a sensor fault.
        int best = -1;
        for (int w = 0; w < core::kWarnCount; ++w) {
            if ((pending_ & (1u << w)) && (best < 0 || long_beeps(static_cast<core::Warning>(w)) >
                                                           long_beeps(static_cast<core::Warning>(best))))
                best = w;
        }
        if (best < 0) {
            pending_ = 0;  // no warning of ours: nothing to beep (the schedule gives none)
        } else {
            pending_ = static_cast<uint8_t>(pending_ & ~(1u << best));
            schedule_.told(best, t);
            pattern_start_us_ = t;
            pattern_beeps_ = long_beeps(static_cast<core::Warning>(best));
        }
    }
    if (pattern_beeps_ == 0 && current_reversed &&
        (!reversed_told_ || (schedule_.repeat_us() > 0 && t >= reversed_told_us_ + schedule_.repeat_us()))) {
        // A craft without an OLED or a ground station heard nothing of its wiring, and flew
        // with a monitor that never sees it take off.
        reversed_told_ = true;
        reversed_told_us_ = t;
        pattern_start_us_ = t;
        pattern_beeps_ = long_beeps(core::kWarnSensorFault);
    }
    if (pattern_beeps_ > 0) return (t - pattern_start_us_) % long_us < us(kLongOnMs);

    if (!status.flying || !status.time_valid) return false;
    if (status.remaining_time_s < critical_time_s_) return t % us(kFastPeriodMs) < us(kFastOnMs);
    if (status.remaining_time_s < low_time_s_) return t % us(kChirpPeriodMs) < us(kChirpOnMs);
    return false;
}

}  // namespace fw
}  // namespace battsim
