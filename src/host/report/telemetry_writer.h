// The MAVLink stream the monitor's telemetry UART sends for a log (telemetry/mavlink.h),
// written beside a replay: raw, byte for byte what the device sends, or as a .tlog (each
// frame after its time as 8 big-endian bytes of µs), which ground stations open to replay.
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
    enum class Format { Raw, Tlog };
    // Throws std::runtime_error if the file cannot be created.
    TelemetryWriter(const std::string& path, Format format, const telemetry::TelemetryConfig& config,
                    const core::MonitorConfig& monitor);
    // After each Monitor::update, in order.
    void add(const core::Sample& sample, const core::MonitorStatus& status);
    void commit();  // throws std::runtime_error on failure

private:
    AtomicFile file_;
    Format format_;
    std::unique_ptr<telemetry::MavlinkTelemetry> telemetry_;
};

}  // namespace host
}  // namespace battsim
