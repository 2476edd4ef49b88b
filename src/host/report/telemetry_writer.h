// The MAVLink stream the monitor's telemetry UART sends for a log (telemetry/mavlink.h),
// written beside a replay: raw, byte for byte what the device sends, and/or as a .tlog
// (each frame after its time as 8 big-endian bytes of µs), which ground stations open to
// replay. One encoder feeds both; the texts it sent are kept (`battsim replay --said`).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/monitor.h"
#include "core/sample.h"
#include "host/io/atomic_file.h"
#include "telemetry/mavlink.h"

namespace battsim {
namespace host {

// A STATUSTEXT the stream carried: what a ground station shows and speaks, and when.
struct SaidText {
    uint64_t time_us = 0;
    uint8_t severity = 0;  // MAV_SEVERITY
    std::string text;
};

// The texts as the summary's `said` entries: log time, time since take-off (null before it;
// `flight_start_s` NaN: no flight), severity name, text.
nlohmann::json said_json(const std::vector<SaidText>& said, double flight_start_s);

class TelemetryWriter {
public:
    // An empty path: that form is not written. Throws std::runtime_error if a file cannot be created.
    TelemetryWriter(const std::string& raw_path, const std::string& tlog_path, const telemetry::TelemetryConfig& config,
                    const core::MonitorConfig& monitor);
    // After each Monitor::update, in order.
    void add(const core::Sample& sample, const core::MonitorStatus& status);
    void commit();  // throws std::runtime_error on failure
    // Every STATUSTEXT sent so far, in order.
    const std::vector<SaidText>& said() const { return said_; }

private:
    std::vector<SaidText> said_;
    std::unique_ptr<AtomicFile> raw_;
    std::unique_ptr<AtomicFile> tlog_;
    telemetry::MavlinkTelemetry telemetry_;
};

}  // namespace host
}  // namespace battsim
