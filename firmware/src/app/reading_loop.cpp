#include "app/reading_loop.h"

namespace battsim {
namespace fw {

ReadingLoop::Result ReadingLoop::next(Reading& out, uint32_t poll_us) {
    const uint32_t start_us = clock_.micros();
    const uint32_t timeout_us = 3u * timer_.period_us();
    while (!sensors_.conversion_ready()) {
        if (clock_.micros() - start_us > timeout_us) {
            ++ready_timeouts_;
            return Result::Timeout;
        }
        clock_.sleep_us(poll_us);
    }
    // Stamp first: the time of the reading, not of the I²C traffic after it.
    const uint32_t now_us = clock_.micros();
    if (!sensors_.read_pack(out.pack)) {
        ++pack_errors_;
        return Result::PackError;
    }
    out.time_us = timer_.stamp(now_us);
    const bool taps_expected = sensors_.has_taps();  // before the call: a chip found by it has no reading yet
    out.taps_ok = sensors_.read_taps(out.taps);
    if (!out.taps_ok && taps_expected) ++tap_errors_;
    return Result::Reading;
}

ReadingCounters ReadingLoop::counters() const {
    ReadingCounters c;
    c.readings = timer_.readings();
    c.missed = timer_.missed();
    c.ready_timeouts = ready_timeouts_;
    c.pack_errors = pack_errors_;
    c.tap_errors = tap_errors_;
    return c;
}

}  // namespace fw
}  // namespace battsim
