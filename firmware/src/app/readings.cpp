#include "app/readings.h"

namespace battsim {
namespace fw {

int cell_voltages_10uv(const PackReading& pack, const TapReading& taps, int cells_in_series,
                       int32_t out_10uv[kTapChannels + 1]) {
    if (cells_in_series < 2 || cells_in_series > kTapChannels + 1) return 0;
    const int used_taps = cells_in_series - 1;
    int32_t below_10uv = 0;
    for (int k = 0; k < used_taps; ++k) {
        const int32_t tap_10uv = taps.tap_mv[k] * 100;
        out_10uv[k] = tap_10uv - below_10uv;
        below_10uv = tap_10uv;
    }
    out_10uv[used_taps] = pack.bus_10uv - below_10uv;
    return cells_in_series;
}

void make_sample(uint64_t time_us, const PackReading& pack, const TapReading* taps, int cells_in_series,
                 const core::ShuntCalibration& cal, core::Sample& out) {
    out = core::Sample{};
    out.time_us = time_us;
    out.voltage_v = bus_voltage_v(pack);
    out.current_a = pack_current_a(pack, cal);
    if (taps == nullptr) return;
    int32_t cells_10uv[kTapChannels + 1];
    const int n = cell_voltages_10uv(pack, *taps, cells_in_series, cells_10uv);
    out.cell_count = static_cast<uint8_t>(n);
    for (int c = 0; c < n; ++c) {
        out.cell_voltage_v[c] = static_cast<float>(cells_10uv[c]) / static_cast<float>(kBusUnitsPerVolt);
    }
}

uint64_t ReadingTimer::stamp(uint32_t micros_now) {
    if (!started_) {
        started_ = true;
        now_us_ = micros_now;
    } else {
        // Unsigned difference: right across the 32-bit wrap.
        const uint32_t gap_us = micros_now - last_micros_;
        now_us_ += gap_us;
        if (gap_us > period_us_ + period_us_ / 2u) missed_ += (gap_us + period_us_ / 2u) / period_us_ - 1u;
    }
    last_micros_ = micros_now;
    ++readings_;
    return now_us_;
}

}  // namespace fw
}  // namespace battsim
