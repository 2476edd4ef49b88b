// The measuring heart of both programs: wait for the INA226's conversion-ready flag,
// stamp the time, read the pack and the taps. Counts what went wrong instead of stopping.
#pragma once
#include <stdint.h>

#include "app/hardware.h"
#include "app/readings.h"

namespace battsim {
namespace fw {

struct Reading {
    uint64_t time_us = 0;
    PackReading pack;
    TapReading taps;
    bool taps_ok = false;
};

struct ReadingCounters {
    uint32_t readings = 0;
    uint32_t missed = 0;          // conversions skipped (the loop was late)
    uint32_t ready_timeouts = 0;  // no conversion for several periods: INA226 gone?
    uint32_t pack_errors = 0;     // I²C read of the INA226 failed
    uint32_t tap_errors = 0;      // INA3221 present, its reading failed or was not ready (sample without cells)
};

class ReadingLoop {
public:
    enum class Result { Reading, Timeout, PackError };

    ReadingLoop(Sensors& sensors, Clock& clock, uint32_t period_us = kIna226PeriodUs)
        : sensors_(sensors), clock_(clock), timer_(period_us) {}

    // Polls the flag every `poll_us` for up to three conversion periods.
    Result next(Reading& out, uint32_t poll_us = 1000);
    ReadingCounters counters() const;

private:
    Sensors& sensors_;
    Clock& clock_;
    ReadingTimer timer_;
    uint32_t ready_timeouts_ = 0;
    uint32_t pack_errors_ = 0;
    uint32_t tap_errors_ = 0;
};

}  // namespace fw
}  // namespace battsim
