// From sensor readings to the core's Sample. Each integer reading becomes a float by one
// correctly rounded division, so the float is the one nearest the reading's decimal
// value: exactly what the host gets when it parses that decimal from a log. That is what
// lets a device log replay to the device's own numbers, bit for bit.
#pragma once
#include <stdint.h>

#include "app/hardware.h"
#include "core/sample.h"
#include "core/sensor.h"

namespace battsim {
namespace fw {

constexpr int32_t kBusUnitsPerVolt = 100000;        // 10 µV
constexpr int32_t kShuntUnitsPerMillivolt = 10000;  // 0.1 µV
constexpr int kBusDecimals = 5;                     // digits that write a reading exactly
constexpr int kShuntDecimals = 4;

inline float bus_voltage_v(const PackReading& r) {
    return static_cast<float>(r.bus_10uv) / static_cast<float>(kBusUnitsPerVolt);
}
inline float shunt_voltage_mv(const PackReading& r) {
    return static_cast<float>(r.shunt_100nv) / static_cast<float>(kShuntUnitsPerMillivolt);
}
// The same conversion as the host readers (core::current_ma_from_shunt_mv, then mA → A).
inline float pack_current_a(const PackReading& r, const core::ShuntCalibration& cal) {
    return core::current_ma_from_shunt_mv(shunt_voltage_mv(r), cal) / 1000.0f;
}

// Cell voltages in 10 µV units from the cumulative taps: cell k = tap k − tap k−1, and the
// top cell = pack bus − the highest tap used (as the reference hardware did). Returns the
// cell count: `cells_in_series` when 2…kTapChannels+1 cells can be measured, else 0.
int cell_voltages_10uv(const PackReading& pack, const TapReading& taps, int cells_in_series,
                       int32_t out_10uv[kTapChannels + 1]);

// Builds the sample the monitor sees. `taps` may be null (no INA3221): no cell data.
void make_sample(uint64_t time_us, const PackReading& pack, const TapReading* taps, int cells_in_series,
                 const core::ShuntCalibration& cal, core::Sample& out);

// 32-bit microsecond clock → 64-bit time stamps, and readings the loop did not collect in
// time (a gap of more than 1.5 conversion periods counts the conversions it skipped).
class ReadingTimer {
public:
    explicit ReadingTimer(uint32_t period_us) : period_us_(period_us) {}
    // Call once per reading with the clock's micros(); returns the extended time stamp.
    uint64_t stamp(uint32_t micros_now);
    uint32_t missed() const { return missed_; }
    uint32_t readings() const { return readings_; }
    uint32_t period_us() const { return period_us_; }

private:
    uint32_t period_us_;
    bool started_ = false;
    uint32_t last_micros_ = 0;
    uint64_t now_us_ = 0;
    uint32_t missed_ = 0;
    uint32_t readings_ = 0;
};

// INA226: shunt and bus conversions of 2116 µs each, averaged over 16: one reading every
// 2 × 2116 × 16 µs ≈ 67.7 ms.
constexpr uint32_t kIna226ConversionUs = 2116;
constexpr uint32_t kIna226Averages = 16;
constexpr uint32_t kIna226PeriodUs = 2u * kIna226ConversionUs * kIna226Averages;
// INA3221: bus channels only (shunt conversions off), 1100 µs × 16 averages × 3 channels.
constexpr uint32_t kIna3221ConversionUs = 1100;
constexpr uint32_t kIna3221Averages = 16;

}  // namespace fw
}  // namespace battsim
