// What the 128×64 OLED shows: 6 rows of 21 characters, laid out here so the page is the
// same on the panel and in the host's text dump.
#pragma once
#include <stdint.h>

#include "app/hardware.h"
#include "app/reading_loop.h"
#include "core/monitor.h"
#include "core/sample.h"

namespace battsim {
namespace fw {

struct MonitorPage {
    const core::Sample* sample = nullptr;
    const core::MonitorStatus* status = nullptr;
    ReadingCounters counters;
    bool sd_ok = true;
    bool current_reversed = false;  // MonitorAppState::current_reversed
};

// 16.42V  23.5A FLY
// SoC  78%  1234mAh
// Cap 1.48Ah R 21mOhm
// Left  3:12 of  5:40
// 4.11 4.10 4.12 4.09
// ok miss3
void draw_monitor_page(Display& d, const MonitorPage& page);

struct LoggerPage {
    float voltage_v = 0.0f;
    float current_a = 0.0f;
    float consumed_mah = 0.0f;
    uint32_t lines_sent = 0;
    bool connected = false;
    ReadingCounters counters;
    bool taps_missing = false;  // the config wants cells but no INA3221 answers
};
void draw_logger_page(Display& d, const LoggerPage& page);

}  // namespace fw
}  // namespace battsim
