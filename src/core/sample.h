// One sensor reading as the monitor sees it: the unit every reader, the simulator
// and the firmware's sensor layer produce. Plain data, fixed size, no heap.
#pragma once
#include <stdint.h>

namespace battsim {
namespace core {

// 12S covers every multirotor pack we know of; PX4 logs carry up to 14 cells, the
// readers drop (and report) cells beyond this.
constexpr int kMaxCells = 12;

struct Sample {
    uint64_t time_us = 0;           // monotonic time stamp of the reading
    float voltage_v = 0.0f;         // pack (bus) voltage
    float current_a = 0.0f;         // positive = discharge
    uint8_t cell_count = 0;         // 0 = no per-cell voltages in this sample
    float cell_voltage_v[kMaxCells] = {};
    bool has_temperature = false;
    float temperature_c = 0.0f;
};

}  // namespace core
}  // namespace battsim
