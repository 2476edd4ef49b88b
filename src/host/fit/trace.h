// A log replayed once through the core monitor and kept in memory, sample by sample, with
// what the monitor decided (valid, flying, initialised, dt) and what it computed (model
// voltage, charge drawn, filtered current). Fitting and residual analysis re-simulate the
// model along it many times; the monitor's own decisions do not depend on the model
// parameters, so they are taken once from this replay.
#pragma once
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "host/config_json.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {
namespace fit {

// Too little data to fit: a log with no sample in the objective, or no more samples than
// parameters. The data's fault, not the command line's: an InputError (exit 3). `advice` names
// the remedy in the caller's own options; finding() is the message without it.
class TooLittleData : public InputError {
public:
    TooLittleData(const std::string& file, const std::string& finding, const std::string& advice = "")
        : InputError(file, 0, 0, advice.empty() ? finding : finding + " (" + advice + ")"), finding_(finding) {}
    const std::string& finding() const { return finding_; }

private:
    std::string finding_;
};

struct TracePoint {
    double time_s = 0;  // since the log's first sample
    float dt_s = 0;     // the monitor's dt (since the previous valid sample)
    float voltage_v = 0;
    float current_a = 0;
    bool has_temperature = false;
    float temperature_c = 0;
    bool valid = false;        // accepted by the monitor's plausibility check
    bool flying = false;
    bool initialised = false;  // initial state of charge known at this sample
    bool in_flight = false;    // inside the summary's flight window (first to last flying sample)
    float monitor_model_v = 0;
    float monitor_consumed_mah = 0;
    float monitor_filtered_a = 0;
};

struct Trace {
    std::string path;
    std::string label;  // file name without directory and extension
    SourceInfo info;
    std::vector<TracePoint> points;
    long settle_index = -1;  // first initialised sample; -1 = never initialised
    float monitor_initial_ah = 0;
    bool has_temperature = false;  // any valid sample carries one
    float flying_current_a = 0;    // the config's take-off current (monitor.min_flying_current_a)
    std::vector<std::string> notes;  // what the replay says of the log with this config (log_notes)
};

// A trace's label: the file name of `path` without directory and extension.
std::string trace_label(const std::string& path);

// Replays `path` with `config` (the base model; extensions play no part in the monitor's
// decisions) and keeps every sample. Throws InputError like replay_log().
Trace load_trace(const std::string& path, const ReaderOptions& reader, const LoadedConfig& config);

// Writes the trace's notes to `out` (if not null) as replay says them, one a line, prefixed
// with `command` and the log: "battsim fit: note: LOG: ...".
void say_notes(const std::string& command, const Trace& trace, std::ostream* out);

}  // namespace fit
}  // namespace host
}  // namespace battsim
