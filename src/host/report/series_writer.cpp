#include "host/report/series_writer.h"

#include <cstdio>

namespace battsim {
namespace host {

std::string series_header(int cells) {
    std::string h =
        "time_s,voltage_v,current_a,filtered_current_a,model_voltage_v,adapted_model_voltage_v,consumed_mah,"
        "consumed_mwh,soc,capacity_ah,resistance_ohm,usable_capacity_ah,remaining_time_s,total_time_s,"
        "avg_power_w,flying,sample_valid,warnings";
    for (int c = 1; c <= cells; ++c) h += ",cell" + std::to_string(c) + "_v";
    for (int c = 1; c <= cells; ++c) h += ",cell" + std::to_string(c) + "_score";
    h += ",capacity_sigma_ah,expected_time_s,remaining_energy_wh,rest_capacity_ah,outlier_cell,pack_capacity_deficit";
    for (int c = 1; c <= cells; ++c) h += ",cell" + std::to_string(c) + "_resistance_ohm";
    for (int c = 1; c <= cells; ++c) h += ",cell" + std::to_string(c) + "_capacity_deficit";
    for (int c = 1; c <= cells; ++c) h += ",cell" + std::to_string(c) + "_capacity_deficit_sigma";
    return h;
}

SeriesWriter::SeriesWriter(const std::string& path, int cells)
    : file_(std::make_unique<AtomicFile>(path)), cells_(cells) {
    file_->write(series_header(cells) + "\n");
    line_.reserve(512);
}

void SeriesWriter::add(const core::Sample& sample, const core::MonitorStatus& s) {
    char buf[64];
    line_.clear();
    auto put = [&](const char* fmt, double v, bool known = true) {
        if (known) {
            std::snprintf(buf, sizeof buf, fmt, v);
            line_ += buf;
        }
        line_ += ',';
    };
    put("%.6f", sample.time_us * 1e-6);
    put("%.4f", sample.voltage_v);
    put("%.4f", sample.current_a);
    put("%.4f", s.filtered_current_a);
    // Empty until the monitor has its initial state (models, state of charge) or a resistance,
    // as the firmware writes them: a 0 V model had read as a 16.8 V error.
    put("%.4f", s.model_voltage_v, s.initialised);
    put("%.4f", s.adapted_model_voltage_v, s.initialised);
    put("%.3f", s.consumed_mah);
    put("%.2f", s.consumed_mwh);
    put("%.5f", s.soc, s.initialised);
    put("%.5f", s.capacity_ah);
    put("%.6f", s.resistance_ohm, s.resistance_ohm > 0.0f);
    put("%.5f", s.usable_capacity_ah);
    if (s.time_valid) {
        put("%.2f", s.remaining_time_s);
        put("%.2f", s.total_time_s);
    } else {
        line_ += ",,";
    }
    put("%.3f", s.avg_power_w);
    line_ += s.flying ? "1," : "0,";
    line_ += s.sample_valid ? "1," : "0,";
    std::snprintf(buf, sizeof buf, "%u", static_cast<unsigned>(s.warnings));
    line_ += buf;
    for (int c = 0; c < cells_; ++c) {
        line_ += ',';
        if (c < sample.cell_count) {
            std::snprintf(buf, sizeof buf, "%.4f", sample.cell_voltage_v[c]);
            line_ += buf;
        }
    }
    for (int c = 0; c < cells_; ++c) {
        std::snprintf(buf, sizeof buf, ",%.4f", c < s.cell_count ? s.cell_score[c] : 0.0f);
        line_ += buf;
    }
    // The joint estimator's own outputs (zero with the reference estimator).
    std::snprintf(buf, sizeof buf, ",%.5f,", s.capacity_sigma_ah);
    line_ += buf;
    if (s.time_valid) {
        std::snprintf(buf, sizeof buf, "%.2f", s.expected_time_s);
        line_ += buf;
    }
    // One value per call, as put() does: a buffer of 64 holds any one float's digits.
    std::snprintf(buf, sizeof buf, ",%.3f", s.remaining_energy_wh);
    line_ += buf;
    std::snprintf(buf, sizeof buf, ",%.5f", s.rest_capacity_ah);
    line_ += buf;
    std::snprintf(buf, sizeof buf, ",%d", s.outlier_cell + 1);
    line_ += buf;
    std::snprintf(buf, sizeof buf, ",%.4f", s.pack_capacity_deficit);
    line_ += buf;
    const auto cell_column = [&](const char* fmt, const float* values) {
        for (int c = 0; c < cells_; ++c) {
            std::snprintf(buf, sizeof buf, fmt, c < core::kMaxCells ? values[c] : 0.0f);
            line_ += buf;
        }
    };
    cell_column(",%.6f", s.cell_resistance_ohm);
    cell_column(",%.4f", s.cell_capacity_deficit);
    cell_column(",%.4f", s.cell_capacity_deficit_sigma);
    line_ += '\n';
    file_->write(line_);
}

void SeriesWriter::commit() { file_->commit(); }

}  // namespace host
}  // namespace battsim
