#include "host/report/telemetry_writer.h"

namespace battsim {
namespace host {

TelemetryWriter::TelemetryWriter(const std::string& path, Format format, const telemetry::TelemetryConfig& config,
                                 const core::MonitorConfig& monitor)
    : file_(path), format_(format), telemetry_(std::make_unique<telemetry::MavlinkTelemetry>()) {
    telemetry_->configure(config, monitor);
}

void TelemetryWriter::add(const core::Sample& sample, const core::MonitorStatus& status) {
    uint8_t bytes[telemetry::MavlinkTelemetry::kMaxBytesPerUpdate];
    const size_t n = telemetry_->update(sample, status, bytes);
    size_t at = 0;
    while (at < n) {
        // Every frame is unsigned MAVLink 2: its length byte and 12 bytes around it.
        const size_t length = bytes[at + 1] + telemetry::kFrameOverheadBytes;
        if (format_ == Format::Tlog) {
            char stamp[8];
            for (int i = 0; i < 8; ++i) stamp[i] = static_cast<char>(status.time_us >> (8 * (7 - i)));
            file_.write(stamp, sizeof stamp);
        }
        file_.write(reinterpret_cast<const char*>(bytes + at), length);
        at += length;
    }
}

void TelemetryWriter::commit() { file_.commit(); }

}  // namespace host
}  // namespace battsim
