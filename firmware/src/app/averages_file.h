// Long-term averages of current and power kept on the SD card across flights. At boot
// they become the core's RollingAverage initial values, so a new flight's time estimate
// starts from the pack's usual demand instead of from nothing.
//
// File format (text, one key per line, floats with 9 significant digits so they read
// back as the same float):
//   battsim-averages 1
//   current_a=23.4567890
//   power_w=345.678901
//   flights=12
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "telemetry/text_buffer.h"

namespace battsim {
namespace fw {

struct StoredAverages {
    float current_a = 0.0f;
    float power_w = 0.0f;
    uint32_t flights = 0;
};

constexpr const char* kAveragesPath = "battsim/averages.txt";

void format_averages(const StoredAverages& a, telemetry::TextBuffer& out);
// False (and `out` untouched) for anything but a complete, well-formed file with finite,
// non-negative averages: a bad file means "no memory", never a wrong start value.
bool parse_averages(const char* text, size_t len, StoredAverages& out);

}  // namespace fw
}  // namespace battsim
