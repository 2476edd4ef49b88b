#include "host/report/telemetry_writer.h"

#include <algorithm>
#include <cmath>

#include "host/report/summary.h"

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
    for (size_t at = 0; at < n; at += bytes[at + 1] + telemetry::kFrameOverheadBytes) {
        const uint8_t* frame = bytes + at;
        const uint32_t id = frame[7] | (frame[8] << 8) | (static_cast<uint32_t>(frame[9]) << 16);
        if (id != telemetry::kStatusTextId) continue;
        // Payload: severity, then up to 50 characters (trailing zeros dropped on the wire).
        const uint8_t* payload = frame + 10;
        const size_t length = frame[1];
        std::string text(reinterpret_cast<const char*>(payload + 1), length > 1 ? length - 1 : 0);
        text = text.substr(0, std::min(text.find('\0'), telemetry::kStatusTextChars));
        said_.push_back(SaidText{status.time_us, payload[0], text});
    }
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

nlohmann::json said_json(const std::vector<SaidText>& said, double flight_start_s) {
    nlohmann::json out = nlohmann::json::array();
    for (const SaidText& t : said) {
        const double time_s = t.time_us * 1e-6;
        const bool in_flight = std::isfinite(flight_start_s) && time_s >= flight_start_s;
        out.push_back({{"time_s", time_s_of_us(t.time_us)},
                       {"flight_time_s", in_flight ? nlohmann::json(round_sig(time_s - flight_start_s, 7)) : nlohmann::json(nullptr)},
                       {"severity", t.severity == telemetry::kMavSeverityWarning  ? "warning"
                                    : t.severity == telemetry::kMavSeverityNotice ? "notice"
                                                                                 : "other"},
                       {"text", t.text}});
    }
    return out;
}

void TelemetryWriter::commit() {
    if (raw_) raw_->commit();
    if (tlog_) tlog_->commit();
}

}  // namespace host
}  // namespace battsim
