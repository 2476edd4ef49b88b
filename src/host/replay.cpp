#include "host/replay.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "host/report/series_writer.h"
#include "host/report/summary.h"

namespace battsim {
namespace host {

nlohmann::json replay_log(const std::string& path, const ReplayOptions& options, const SampleObserver& observer) {
    ReaderOptions reader_options = options.reader;
    reader_options.shunt = options.config.monitor.shunt;  // the firmware's calibration, one source
    std::unique_ptr<SampleReader> reader = open_reader(path, reader_options);

    // The monitor is large-ish (fixed arrays); keep it off the stack for deep call chains.
    auto monitor = std::make_unique<core::Monitor>();
    monitor->configure(options.config.monitor);
    SummaryAccumulator summary;
    std::unique_ptr<SeriesWriter> series;
    int series_cells = 0;

    core::Sample sample;
    LogFacts facts;  // for the config's notes: its first voltage, when the pack was at rest
    bool first = true;
    uint64_t t0_us = 0;
    const auto wall0 = std::chrono::steady_clock::now();
    while (reader->next(sample)) {
        if (first) {
            t0_us = sample.time_us;
            if (!options.series_path.empty()) {
                series_cells = sample.cell_count;
                series = std::make_unique<SeriesWriter>(options.series_path, series_cells);
            }
            first = false;
            if (std::isfinite(sample.voltage_v) && sample.voltage_v > 0.0f &&
                std::fabs(sample.current_a) <= options.config.monitor.initial.max_resting_current_a)
                facts.resting_voltage_v = sample.voltage_v;
        }
        if (options.realtime_speed > 0) {
            // Pace only the output; the monitor still sees the log's time stamps.
            const auto due = wall0 + std::chrono::microseconds(static_cast<int64_t>(
                                         (sample.time_us - t0_us) / options.realtime_speed));
            std::this_thread::sleep_until(due);
        }
        const core::MonitorStatus& status = monitor->update(sample);
        summary.add(status);
        if (series) series->add(sample, status);
        if (observer) observer(sample, status);
    }
    if (first) throw InputError(path, 0, 0, "the log holds no samples");

    const SourceInfo& info = reader->info();
    nlohmann::json j;
    j["schema"] = kSummarySchema;
    j["schema_version"] = kSummaryVersion;
    j["battsim_version"] = BATTSIM_VERSION;
    j["input"] = {{"path", path}, {"format", to_string(info.format)}, {"cells", info.cell_count},
                  {"has_temperature", info.has_temperature}, {"notes", info.notes}};
    j["config"] = options.config.name;
    j["estimator"] = options.config.monitor.estimator == core::EstimatorKind::Joint ? "joint" : "reference";
    // Only when one applies: summaries of configs without notes keep their keys.
    facts.cells = info.cell_count;
    const std::vector<std::string> notes = config_notes(options.config.monitor, facts);
    if (!notes.empty()) j["config_notes"] = notes;
    nlohmann::json body = summary.to_json(info.cell_count);
    for (auto it = body.begin(); it != body.end(); ++it) j[it.key()] = it.value();
    // The joint cell check's step measurements at the end of the log (take-off, landing, the
    // bursts' clean edges): how many, and each cell's ΔV/ΔI with its standard error.
    if (options.config.monitor.estimator == core::EstimatorKind::Joint && info.cell_count > 0 && j["flight"].is_object()) {
        const core::CellStepResistance::Status& st = monitor->cell_analyzer().step_status();
        nlohmann::json r = nlohmann::json::array(), s = nlohmann::json::array();
        for (int c = 0; c < info.cell_count && c < core::kMaxCells; ++c) {
            r.push_back(st.steps > 0 ? nlohmann::json(round_sig(st.resistance_ohm[c], 4)) : nlohmann::json(nullptr));
            s.push_back(st.steps > 0 ? nlohmann::json(round_sig(st.sigma_ohm[c], 2)) : nlohmann::json(nullptr));
        }
        j["flight"]["cell_steps"] = {{"count", st.steps}, {"resistance_ohm", r}, {"sigma_ohm", s}};
    }
    if (series) series->commit();
    return j;
}

}  // namespace host
}  // namespace battsim
