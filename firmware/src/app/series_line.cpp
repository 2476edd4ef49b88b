#include "app/series_line.h"

namespace battsim {
namespace fw {

void format_series_header(int cells, telemetry::TextBuffer& out) {
    out.clear();
    out.append(
        "time_s,voltage_v,current_a,filtered_current_a,model_voltage_v,adapted_model_voltage_v,consumed_mah,"
        "consumed_mwh,soc,capacity_ah,resistance_ohm,usable_capacity_ah,remaining_time_s,total_time_s,"
        "avg_power_w,flying,sample_valid,warnings");
    for (int c = 1; c <= cells; ++c) out.appendf(",cell%d_v", c);
    for (int c = 1; c <= cells; ++c) out.appendf(",cell%d_score", c);
    out.append(",capacity_sigma_ah,expected_time_s,remaining_energy_wh,rest_capacity_ah,outlier_cell,pack_capacity_deficit");
    for (int c = 1; c <= cells; ++c) out.appendf(",cell%d_resistance_ohm", c);
    for (int c = 1; c <= cells; ++c) out.appendf(",cell%d_capacity_deficit", c);
    for (int c = 1; c <= cells; ++c) out.appendf(",cell%d_capacity_deficit_sigma", c);
    out.append_char('\n');
}

namespace {

float cell_value(const float* values, int c) { return c < core::kMaxCells ? values[c] : 0.0f; }

void put(telemetry::TextBuffer& out, const char* fmt, float v, bool known = true) {
    if (known) out.appendf(fmt, static_cast<double>(v));
    out.append_char(',');
}

}  // namespace

void format_series_line(const core::Sample& sample, const core::MonitorStatus& s, int cells, telemetry::TextBuffer& out) {
    out.clear();
    // Seconds with 6 decimals straight from the integer microseconds: the same digits as
    // printing time_us·1e-6 with %.6f, without double arithmetic on the device.
    out.append_fixed(static_cast<int64_t>(sample.time_us), 6);
    out.append_char(',');
    put(out, "%.4f", sample.voltage_v);
    put(out, "%.4f", sample.current_a);
    put(out, "%.4f", s.filtered_current_a);
    // Empty until the monitor has its initial state (models, state of charge) or a resistance:
    // a 0 V model had read as a 16.8 V error.
    put(out, "%.4f", s.model_voltage_v, s.initialised);
    put(out, "%.4f", s.adapted_model_voltage_v, s.initialised);
    put(out, "%.3f", s.consumed_mah);
    put(out, "%.2f", s.consumed_mwh);
    put(out, "%.5f", s.soc, s.initialised);
    put(out, "%.5f", s.capacity_ah);
    put(out, "%.6f", s.resistance_ohm, s.resistance_ohm > 0.0f);
    put(out, "%.5f", s.usable_capacity_ah);
    if (s.time_valid) {
        put(out, "%.2f", s.remaining_time_s);
        put(out, "%.2f", s.total_time_s);
    } else {
        out.append(",,");
    }
    put(out, "%.3f", s.avg_power_w);
    out.append(s.flying ? "1," : "0,");
    out.append(s.sample_valid ? "1," : "0,");
    out.append_uint(s.warnings);
    for (int c = 0; c < cells; ++c) {
        out.append_char(',');
        if (c < sample.cell_count) out.appendf("%.4f", static_cast<double>(sample.cell_voltage_v[c]));
    }
    for (int c = 0; c < cells; ++c) {
        out.appendf(",%.4f", static_cast<double>(c < s.cell_count ? s.cell_score[c] : 0.0f));
    }
    // The joint estimator's own outputs (zero with the reference estimator).
    out.appendf(",%.5f,", static_cast<double>(s.capacity_sigma_ah));
    if (s.time_valid) out.appendf("%.2f", static_cast<double>(s.expected_time_s));
    out.appendf(",%.3f", static_cast<double>(s.remaining_energy_wh));
    out.appendf(",%.5f", static_cast<double>(s.rest_capacity_ah));
    out.appendf(",%d", s.outlier_cell + 1);
    out.appendf(",%.4f", static_cast<double>(s.pack_capacity_deficit));
    for (int c = 0; c < cells; ++c) out.appendf(",%.6f", static_cast<double>(cell_value(s.cell_resistance_ohm, c)));
    for (int c = 0; c < cells; ++c) out.appendf(",%.4f", static_cast<double>(cell_value(s.cell_capacity_deficit, c)));
    for (int c = 0; c < cells; ++c)
        out.appendf(",%.4f", static_cast<double>(cell_value(s.cell_capacity_deficit_sigma, c)));
    out.append_char('\n');
}

}  // namespace fw
}  // namespace battsim
