#include "host/report/telemetry_writer.h"

namespace battsim {
namespace host {

TelemetryWriter::TelemetryWriter(const std::string& raw_path, const std::string& tlog_path,
                                 const telemetry::TelemetryConfig& config, const core::MonitorConfig& monitor) {
    if (!raw_path.empty()) raw_ = std::make_unique<AtomicFile>(raw_path);
    if (!tlog_path.empty()) tlog_ = std::make_unique<AtomicFile>(tlog_path);
    telemetry_.configure(config, monitor);
}

void TelemetryWriter::add(const core::Sample& sample, const core::MonitorStatus& status) {
    uint8_t bytes[telemetry::MavlinkTelemetry::kMaxBytesPerUpdate];
    const size_t n = telemetry_.update(sample, status, bytes);
    if (n == 0) return;
    if (raw_) raw_->write(reinterpret_cast<const char*>(bytes), n);
    if (!tlog_) return;
    char stamp[8];
    for (int i = 0; i < 8; ++i) stamp[i] = static_cast<char>(status.time_us >> (8 * (7 - i)));
    for (size_t at = 0; at < n;) {
        // Every frame is unsigned MAVLink 2: its length byte and 12 bytes around it.
        const size_t length = bytes[at + 1] + telemetry::kFrameOverheadBytes;
        tlog_->write(stamp, sizeof stamp);
        tlog_->write(reinterpret_cast<const char*>(bytes + at), length);
        at += length;
    }
}

void TelemetryWriter::commit() {
    if (raw_) raw_->commit();
    if (tlog_) tlog_->commit();
}

}  // namespace host
}  // namespace battsim
