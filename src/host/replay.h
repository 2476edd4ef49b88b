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

// The notes of a replay's summary that say its config is for another pack than the log's
// (is_other_pack_note). The tools that replay many logs say these per log, where a fleet's
// rows or a fit's numbers would hide them.
std::vector<std::string> other_pack_notes(const nlohmann::json& summary);

// Replays `path`; throws InputError (bad log) or std::runtime_error (outputs). Returns
// the summary JSON (schema battsim.summary).
nlohmann::json replay_log(const std::string& path, const ReplayOptions& options,
                          const SampleObserver& observer = nullptr);

}  // namespace host
}  // namespace battsim
