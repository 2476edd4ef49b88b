// Replay: stream a log through the core monitor at the log's own timing and collect
// the summary (and optionally the per-sample series). The one function that replay,
// batch, residual and score all call.
#pragma once
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/monitor.h"
#include "core/sample.h"
#include "host/config_json.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

struct ReplayOptions {
    ReaderOptions reader;
    LoadedConfig config;
    std::string series_path;   // empty = no series
    double realtime_speed = 0; // > 0: pace to wall time at this speed-up (1 = real time)
};

// Called for each sample after the monitor's update.
using SampleObserver = std::function<void(const core::Sample&, const core::MonitorStatus&)>;

// Replays `path`; throws InputError (bad log) or std::runtime_error (outputs). Returns
// the summary JSON (schema battsim.summary).
nlohmann::json replay_log(const std::string& path, const ReplayOptions& options,
                          const SampleObserver& observer = nullptr);

}  // namespace host
}  // namespace battsim
