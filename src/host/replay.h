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

// The samples a replay's config kept out by its sensor limits, in words (empty: none): the
// count per limit and the likely cause ("3547 current_high (sensor.max_current_a); a current in
// mA read as amperes (give --current-unit mA)?; does the config match this pack?").
std::string kept_out_text(const nlohmann::json& summary);

// Why a replay has nothing to report, in words; empty when at least one sample was valid.
// A log whose every sample the config's sensor limits kept out (a 4S config on a 6S log)
// replays without an error but reads null everywhere: batch makes its row
// "no_valid_samples" and replay exits 1, so no pipeline takes it for a replayed log.
// E.g. "the config's sensor limits kept out all 1339 samples: 1339 pack_voltage_high
// (sensor.max_pack_voltage_v); does the config match this pack?".
std::string no_valid_samples_text(const nlohmann::json& summary);

// What a replay's summary says of its log that the commands fitting along replays (fit,
// residual, fit-ocv, calibrate) must say too, as replay does: the input's notes (the reader's
// and the log's shape: a current of the other sign, a clock that jumps, a time unit that does
// not fit), the samples the sensor limits kept out and why, and the config's notes about
// this log (is_log_note: another pack, a temperature dependence the log cannot drive). A fit
// on a misread log runs without an error, and its numbers alone had not shown it.
std::vector<std::string> log_notes(const nlohmann::json& summary);

// Replays `path`; throws InputError (bad log) or std::runtime_error (outputs). Returns
// the summary JSON (schema battsim.summary).
nlohmann::json replay_log(const std::string& path, const ReplayOptions& options,
                          const SampleObserver& observer = nullptr);

}  // namespace host
}  // namespace battsim
