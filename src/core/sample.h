// One sensor reading as the monitor sees it: the unit every reader, the simulator
// and the firmware's sensor layer produce. Plain data, fixed size, no heap.
#pragma once
#include <stdint.h>

namespace battsim {
namespace core {

// 12S covers every multirotor pack we know of; PX4 logs carry up to 14 cells, the
// readers drop (and report) cells beyond this.
constexpr int kMaxCells = 12;

// Feeding it from your own sensors (docs/embedding.md): one Sample per reading, each the
// mean over its own conversion window, about 10–20 a second (the reference logger: one every
// 67.7 ms). The joint estimator's resistance pairs samples 0.05 s and 0.13 s apart among
// the last 16, so readings faster than about 115 Hz must be averaged down first (and
// windows much longer than 68 ms blur the current steps it measures); pairs over 0.35 s /
// 0.59 s apart are not taken, and a gap over 0.75 s (joint.max_sample_gap_s) is a sensor
// fault. The monitor reads no clock: dt comes from these time stamps alone.
struct Sample {
    // Monotonic time of the reading (µs, any origin): it must never go back (a device reset
    // or a pack swap: Monitor::configure again). A 32-bit micros() must be extended to 64
    // bits across its wrap (firmware/src/app/readings.h, ReadingTimer).
    uint64_t time_us = 0;
    float voltage_v = 0.0f;         // pack (bus) voltage, V
    float current_a = 0.0f;         // pack current, A: positive = discharge (negative = charge)
    // Each cell's own voltage (V), cell 1 (index 0) at the pack's negative end: not the
    // cumulative balance-tap voltages (cell k = tap k − tap k−1). 0 = no per-cell voltages
    // in this sample; fewer than 3 cells are not judged (the joint cell check compares each
    // cell with the others); normally MonitorConfig::cells_in_series, at most kMaxCells.
    uint8_t cell_count = 0;
    float cell_voltage_v[kMaxCells] = {};
    bool has_temperature = false;  // read only by the model extensions (temperature, thermal)
    float temperature_c = 0.0f;    // pack temperature, °C
};

}  // namespace core
}  // namespace battsim
