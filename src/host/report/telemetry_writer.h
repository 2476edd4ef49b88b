// The MAVLink stream the monitor's telemetry UART sends for a log (telemetry/mavlink.h),
// written beside a replay: raw, byte for byte what the device sends, and/or as a .tlog
// (each frame after its time as 8 big-endian bytes of µs), which ground stations open to
// replay. One encoder feeds both.
#pragma once
#include <memory>
#include <string>

#include "core/monitor.h"
#include "core/sample.h"
#include "host/io/atomic_file.h"
#include "telemetry/mavlink.h"

namespace battsim {
namespace host {

class TelemetryWriter {
public:
    // An empty path: that form is not written. Throws std::runtime_error if a file cannot be created.
    TelemetryWriter(const std::string& raw_path, const std::string& tlog_path, const telemetry::TelemetryConfig& config,
                    const core::MonitorConfig& monitor);
    // After each Monitor::update, in order.
    void add(const core::Sample& sample, const core::MonitorStatus& status);
    void commit();  // throws std::runtime_error on failure

private:
    std::unique_ptr<AtomicFile> raw_;
    std::unique_ptr<AtomicFile> tlog_;
    telemetry::MavlinkTelemetry telemetry_;
};

}  // namespace host
}  // namespace battsim
