// libFuzzer harness for the monitor's per-sample update: bytes become samples (time
// steps, voltages, currents, cells — NaN, inf and absurd values included). Whatever comes
// in, the status must stay finite and within physical bounds, and the MAVLink telemetry
// built from it must fit its buffer as whole, well-formed frames.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "core/monitor.h"
#include "telemetry/mavlink.h"

namespace {
bool finite_status(const battsim::core::MonitorStatus& s) {
    const float v[] = {s.consumed_mah, s.consumed_mwh, s.model_voltage_v, s.adapted_model_voltage_v, s.soc,
                       s.capacity_ah, s.resistance_ohm, s.usable_capacity_ah, s.remaining_time_s, s.total_time_s,
                       s.avg_power_w, s.filtered_current_a};
    for (float x : v)
        if (!std::isfinite(x)) return false;
    for (int c = 0; c < battsim::core::kMaxCells; ++c)
        if (!std::isfinite(s.cell_score[c]) || std::fabs(s.cell_score[c]) > 1.0001f) return false;
    return s.soc >= 0.0f && s.soc <= 1.0f && s.capacity_ah > 0.0f && s.resistance_ohm >= 0.0f &&
           s.remaining_time_s >= 0.0f;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static battsim::core::Monitor monitor;
    battsim::core::MonitorConfig cfg;
    if (size && (data[0] & 1)) cfg.estimator = battsim::core::EstimatorKind::Joint;
    monitor.configure(cfg);
    static battsim::telemetry::MavlinkTelemetry telemetry;
    telemetry.configure(battsim::telemetry::TelemetryConfig{}, cfg);
    uint8_t frames[battsim::telemetry::MavlinkTelemetry::kMaxBytesPerUpdate];
    battsim::core::Sample s;
    uint64_t t = 0;
    // 16 bytes a sample: dt (2), voltage (4), current (4), 6 bytes picking cell values.
    for (size_t off = 1; off + 16 <= size; off += 16) {
        uint16_t dt_ms;
        float v, i;
        std::memcpy(&dt_ms, data + off, 2);
        std::memcpy(&v, data + off + 2, 4);
        std::memcpy(&i, data + off + 6, 4);
        t += dt_ms * 1000u;
        s.time_us = t;
        s.voltage_v = v;
        s.current_a = i;
        s.cell_count = data[off + 10] % 7;
        for (int c = 0; c < s.cell_count; ++c)
            s.cell_voltage_v[c] = std::isfinite(v) ? v / s.cell_count + (static_cast<int8_t>(data[off + 11 + c % 5]) * 0.01f) : v;
        const battsim::core::MonitorStatus& st = monitor.update(s);
        if (!finite_status(st)) std::abort();
        const size_t n = telemetry.update(s, st, frames);
        if (n > sizeof frames) std::abort();
        for (size_t at = 0; at < n; at += frames[at + 1] + battsim::telemetry::kFrameOverheadBytes) {
            if (frames[at] != 0xFD || at + frames[at + 1] + battsim::telemetry::kFrameOverheadBytes > n) std::abort();
        }
    }
    return 0;
}
