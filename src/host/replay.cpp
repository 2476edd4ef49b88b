#include "host/replay.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <thread>

#include "core/numeric.h"
#include "host/input_shape.h"
#include "host/pack_config.h"
#include "host/report/series_writer.h"
#include "host/report/summary.h"
#include "host/stats.h"

namespace battsim {
namespace host {

namespace {

// Mean |measured − the joint estimator's own model| per cell over a flight beyond which it has
// lost the pack: the simulated suites' flights sit at 0.5–13 mV per cell, the dissertation's
// racing flights at 6–28 mV, the Matrice 100's middle half at 7–38 mV.
constexpr double kLostModelVPerCell = 0.25;
// The same for the configured model (and the reference estimator's adapted one): a cell's
// whole curve spans about 1.2 V, so a model further off than this on average describes no pack.
// The dissertation's original parameters, the worst real fit shipped, sit at 0.25–0.35 V per
// cell on its flights; the reference's adaptation brings them to 0.02–0.06, and the Matrice 100
// fleet's to at most 0.17.
constexpr double kNoPackModelVPerCell = 1.0;
constexpr double kMaxRealtimeWaitS = 2.0;  // --realtime: the longest wait for one sample
// A flight that starts within the take-off confirmation and this much more of the log's first
// sample had no ground before it: the log opened loaded (a sample or two of a slow log included).
constexpr double kStartedLoadedSlackS = 1.0;

}  // namespace

std::vector<std::string> other_pack_notes(const nlohmann::json& summary) {
    std::vector<std::string> out;
    for (const nlohmann::json& note : summary.value("config_notes", nlohmann::json::array()))
        if (note.is_string() && is_other_pack_note(note.get<std::string>())) out.push_back(note.get<std::string>());
    return out;
}

std::string kept_out_text(const nlohmann::json& summary) {
    const nlohmann::json rejected = summary["samples"].value("rejected", nlohmann::json::object());
    if (rejected.empty()) return std::string();
    std::string out;
    for (int f = 1; f < core::kSampleFaultCount; ++f) {
        const char* key = sample_fault_key(static_cast<uint8_t>(f));
        if (rejected.contains(key))
            out += (out.empty() ? "" : " ") + rejected[key].dump() + " " + key + " (" +
                   sample_fault_limit(static_cast<uint8_t>(f)) + ")";
    }
    // Only cell readings kept out: a balance lead more likely than the wrong pack.
    bool pack_kept_out = false;
    for (int f = 1; f < core::kSampleCellVoltage; ++f)
        pack_kept_out = pack_kept_out || rejected.contains(sample_fault_key(static_cast<uint8_t>(f)));
    // The charge of a gap between valid samples is counted at the next one's current.
    const double span_s = summary["samples"].value("rejected_span_s", 0.0);
    if (pack_kept_out && span_s > 0.0)
        out += "; " + fixed_text(span_s, 1) + " s between valid samples, its charge counted at the current after it";
    // A current column in mA read as A reads a thousand times high: the unit before the pack.
    if (rejected.contains("current_high")) out += "; a current in mA read as amperes (give --current-unit mA)?";
    // Likewise a voltage in mV, every reading of it (a CSV column named plainly "voltage").
    // Not when the pack rests at volts of another cell count: a Matrice 100's 24.22 V on the
    // built-in 4S config had been asked whether it was in mV.
    const nlohmann::json high_v = rejected.value("pack_voltage_high", nlohmann::json());
    bool volts_of_another_pack = false;
    for (const std::string& note : other_pack_notes(summary)) volts_of_another_pack = volts_of_another_pack || !is_millivolts_note(note);
    if (high_v.is_number_unsigned() && high_v == summary["samples"].value("total", nlohmann::json()) &&
        summary["input"].value("format", std::string()) == "csv" && !volts_of_another_pack)
        out += "; a voltage in mV read as volts (name the column voltage_mv, or \"voltage (mV)\")?";
    out += pack_kept_out ? "; does the config match this pack?" : "; a loose balance lead, or a config for another cell count?";
    return out;
}

std::string no_valid_samples_text(const nlohmann::json& summary) {
    const nlohmann::json samples = summary.value("samples", nlohmann::json::object());
    const nlohmann::json valid = samples.value("valid", nlohmann::json()), total = samples.value("total", nlohmann::json());
    // A summary without the counts (another schema) is not judged here.
    if (!valid.is_number_unsigned() || !total.is_number_unsigned() || valid.get<uint64_t>() > 0) return std::string();
    if (total.get<uint64_t>() == 0) return "the log holds no sample";
    const std::string kept_out = kept_out_text(summary);
    return "the config's sensor limits kept out all " + total.dump() + " samples" +
           (kept_out.empty() ? std::string() : ": " + kept_out);
}

std::vector<std::string> log_notes(const nlohmann::json& summary) {
    std::vector<std::string> out;
    for (const nlohmann::json& note : summary["input"].value("notes", nlohmann::json::array()))
        if (note.is_string()) out.push_back(note.get<std::string>());
    const std::string kept_out = kept_out_text(summary);
    if (!kept_out.empty())
        out.push_back("the config's sensor limits kept out " +
                      std::to_string(summary["samples"]["total"].get<uint64_t>() - summary["samples"]["valid"].get<uint64_t>()) +
                      " of the " + summary["samples"]["total"].dump() + " samples: " + kept_out);
    for (const nlohmann::json& note : summary.value("config_notes", nlohmann::json::array()))
        if (note.is_string() && is_log_note(note.get<std::string>())) out.push_back(note.get<std::string>());
    return out;
}

nlohmann::json replay_log(const std::string& path, const ReplayOptions& options, const SampleObserver& observer) {
    ReaderOptions reader_options = options.reader;
    reader_options.shunt = options.config.monitor.shunt;  // the firmware's calibration, one source
    reader_options.clock_step_capacity_ah = options.config.monitor.battery.capacity_ah;
    std::unique_ptr<SampleReader> reader = open_reader(path, reader_options);

    // The monitor is large-ish (fixed arrays); keep it off the stack for deep call chains.
    auto monitor = std::make_unique<core::Monitor>();
    monitor->configure(options.config.monitor);
    SummaryAccumulator summary;
    summary.set_landed_below_a(options.config.monitor.flying.min_flying_current_a);
    summary.set_battery_state_times(options.config.telemetry.low_time_s, options.config.telemetry.critical_time_s);
    std::unique_ptr<SeriesWriter> series;
    int series_cells = 0;

    core::Sample sample;
    ShapePack pack;
    pack.empty_v = options.config.monitor.min_voltage_v;
    pack.full_v = options.config.monitor.max_voltage_v;
    pack.capacity_ah = options.config.monitor.battery.capacity_ah;
    InputShape shape(options.reader.columns.current_negative_is_discharge,
                     options.config.monitor.flying.min_flying_current_a, pack);
    LogFacts facts;  // for the config's notes
    facts.temperature_samples = 0;
    FirstRest rest(options.config.monitor.initial.max_resting_current_a);
    const double capacity_mah = 1000.0 * options.config.monitor.battery.capacity_ah;
    bool first = true;
    uint64_t t0_us = 0;
    const auto wall0 = std::chrono::steady_clock::now();
    double paced_us = 0.0;  // --realtime: the log's time paced so far (gaps shortened)
    uint64_t paced_last_us = 0;
    while (reader->next(sample)) {
        if (first) {
            t0_us = paced_last_us = sample.time_us;
            if (!options.series_path.empty()) {
                series_cells = sample.cell_count;
                series = std::make_unique<SeriesWriter>(options.series_path, series_cells);
            }
            first = false;
        }
        rest.add(sample);
        if (sample.has_temperature && std::isfinite(sample.temperature_c)) ++facts.temperature_samples;
        if (options.realtime_speed > 0) {
            // Pace only the output; the monitor still sees the log's time stamps. A gap in the
            // log is waited out for at most kMaxRealtimeWaitS (a clock that jumped by hours
            // had the replay sleep silently for as long).
            const double max_step_us = kMaxRealtimeWaitS * 1e6 * options.realtime_speed;
            if (sample.time_us > paced_last_us)
                paced_us += std::min(static_cast<double>(sample.time_us - paced_last_us), max_step_us);
            paced_last_us = std::max(paced_last_us, sample.time_us);
            const auto due = wall0 + std::chrono::microseconds(static_cast<int64_t>(paced_us / options.realtime_speed));
            std::this_thread::sleep_until(due);
        }
        const core::MonitorStatus& status = monitor->update(sample);
        shape.add(sample);
        if (std::isnan(facts.capacity_passed_s) && status.initialised && status.consumed_mah > capacity_mah)
            facts.capacity_passed_s = static_cast<double>(sample.time_us - t0_us) * 1e-6;
        if (std::isnan(facts.pole_runaway_s) && status.initialised && status.sample_valid &&
            status.consumed_mah > LogFacts::kPoleShare * capacity_mah &&
            std::fabs(static_cast<double>(status.model_voltage_v) - static_cast<double>(sample.voltage_v)) >
                kNoPackModelVPerCell * std::max(1, options.config.monitor.cells_in_series)) {
            facts.pole_runaway_s = static_cast<double>(sample.time_us - t0_us) * 1e-6;
            facts.pole_runaway_share = static_cast<double>(status.consumed_mah) / capacity_mah;
        }
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
    nlohmann::json body =
        summary.to_json(info.cell_count, options.config.monitor.estimator == core::EstimatorKind::Reference);
    std::vector<std::string> input_notes = info.notes;
    const bool flew = body["flight"].is_object();
    const core::JointEstimator::Config& jc = options.config.monitor.joint;
    InputShape::Lags lags;
    if (options.config.monitor.estimator == core::EstimatorKind::Joint) {
        lags.fastest_s = std::max(jc.resistance.lag_s, jc.hover_resistance.lag_s) /
                         (core::DifferenceResistanceEstimator::kHistory - 1);
        const auto span_s = [](float lag_s) {
            return static_cast<double>(core::max_pair_span_us(static_cast<uint64_t>(lag_s * 1.0e6f))) * 1e-6;
        };
        lags.slowest_s = std::max(span_s(jc.resistance.lag_s), span_s(jc.hover_resistance.lag_s));
        lags.prior_ohm = options.config.monitor.battery.internal_resistance_ohm;
        lags.hover_min_step_a = jc.hover_resistance.min_step_a;
    }
    const bool merged = info.averaged_in > info.averaged_out + info.averaged_out / 5;  // over 1.2 a window
    const bool flew_at_all = flew && body["flight"].value("duration_s", 0.0) >= InputShape::kShortestFlightS;
    for (const std::string& n : shape.notes(flew_at_all, options.config.monitor.flying.min_flying_current_a, lags,
                                              static_cast<double>(options.reader.average_us) * 1e-6,
                                              info.format == LogFormat::Csv, merged,
                                              info.format == LogFormat::Csv && info.current_scale_to_a > 0.0 &&
                                                  info.current_scale_to_a < 0.01,
                                              ColumnUnits{info.time_scale_to_s, info.time_column, info.current_scale_to_a}))
        input_notes.push_back(n);
    // A log whose flight starts with its first samples never showed the ground: opened in the air
    // or armed, or a craft that draws the take-off current disarmed, which then reads as one
    // flight that never lands (a 1S whoop idling at 1.2 A against a 0.81 A bar: "flight 291.8 s,
    // still flying" for a 240 s hop), with the starting charge read off a loaded sample.
    if (flew && body["flight"]["start_s"].is_number()) {
        const double from_first_s = body["flight"]["start_s"].get<double>() - static_cast<double>(t0_us) * 1e-6;
        const double bar_a = options.config.monitor.flying.min_flying_current_a;
        if (from_first_s <= options.config.monitor.flying.takeoff_confirm_s + kStartedLoadedSlackS) {
            char buf[320];
            std::snprintf(buf, sizeof buf,
                          "the flight starts %.2f s into the log, with no ground before it (take-off current "
                          "monitor.min_flying_current_a %.3g A): the log opened in the air or armed, or the craft draws "
                          "that much on the ground",
                          from_first_s, bar_a);
            input_notes.push_back(std::string(buf) +
                                  ", so the charge at the start is read off a loaded sample and a ground at that draw "
                                  "counts as flight. If it was on the ground, give the config a take-off current above "
                                  "its ground draw");
        }
    }
    j["input"] = {{"path", path}, {"format", to_string(info.format)}, {"cells", info.cell_count},
                  {"has_temperature", info.has_temperature}, {"notes", input_notes}};
    j["config"] = options.config.name;
    j["estimator"] = options.config.monitor.estimator == core::EstimatorKind::Joint ? "joint" : "reference";
    // Only when one applies: summaries of configs without notes keep their keys.
    facts.cells = info.cell_count;
    facts.resting_voltage_v = rest.voltage_v();
    facts.path = path;
    const LogPack declared = log_pack(info, facts.resting_voltage_v);
    if (declared.cells_declared) {
        facts.declared_cells = declared.cells;
        facts.declared_cells_from = declared.cells_from;
    }
    facts.declared_capacity_ah = declared.capacity_ah;
    facts.declared_capacity_from = declared.capacity_from;
    if (!info.parameters.empty()) {
        // The battery parameters the log's autopilot flew with, as make-config reads them.
        nlohmann::json a = nlohmann::json::object();
        if (facts.declared_cells > 0) a["cells"] = facts.declared_cells;
        if (std::isfinite(declared.capacity_ah)) a["capacity_ah"] = declared.capacity_ah;
        if (std::isfinite(declared.cutoff_voltage_v)) a["cutoff_voltage_v"] = declared.cutoff_voltage_v;
        if (std::isfinite(declared.cutoff_delay_s)) a["cutoff_delay_s"] = declared.cutoff_delay_s;
        if (std::isfinite(declared.resistance_ohm)) a["resistance_ohm"] = declared.resistance_ohm;
        j["input"]["autopilot_battery"] = a;
    }
    std::vector<std::string> notes = config_notes(options.config.monitor, facts);
    // The joint estimator's own model (its tracking filter one step ahead) follows a pack it
    // has within tens of mV per cell; volts off means it lost it and rejects every reading as
    // a glitch (Matrice 100 flight 19 without an OCV table: the state of charge ran below the
    // curve's empty and stayed there, 21 V off, while the capacity climbed to its bound).
    if (options.config.monitor.estimator == core::EstimatorKind::Joint && body["flight"].is_object()) {
        const nlohmann::json& e = body["flight"]["voltage_error_v"]["adapted"]["mean_abs"];
        const int cells = std::max(1, options.config.monitor.cells_in_series);
        if (e.is_number() && e.get<double>() / cells > kLostModelVPerCell) {
            char buf[160];
            std::snprintf(buf, sizeof buf, "the joint estimator's own model is %.2f V per cell off the measurement over the flight",
                          e.get<double>() / cells);
            notes.push_back(std::string(buf) +
                            " (mean; tens of mV when it follows the pack): its filter lost the pack, and its capacity, "
                            "state of charge and remaining time are not to be trusted. Does the config's curve fit this "
                            "pack? (battsim fit-ocv)");
        }
    }
    // Said only when no note above explains it already (a config for another pack, a count
    // past the capacity: both put the model volts off).
    // (... or a measured temperature driving terms fitted to a self-heating state.)
    const bool explained =
        std::isfinite(facts.capacity_passed_s) || std::isfinite(facts.pole_runaway_s) ||
        std::any_of(notes.begin(), notes.end(), [](const std::string& n) { return is_other_pack_note(n); }) ||
        (facts.temperature_samples > 0 && !measured_temperature_note(options.config.monitor, true).empty());
    // A capacity held at the estimator's bound is the bound, not the pack's, and its σ (the
    // filter's, computed as if the bound were an estimate) claims a precision it does not
    // have: Matrice 100 flight 51 read 13.950 Ah (3 × the config's 4.65) with the reference
    // estimator and flight 22 9.300 ± 0.273 Ah with the joint one, both without a word.
    // With the reference estimator, not when a note already gives the cause (another pack, a
    // count past the capacity, a measured temperature driving terms fitted to a self-heating
    // state): its capacity rests on that model. The joint estimator's rests on its OCV table.
    const core::MonitorConfig& m = options.config.monitor;
    const bool joint = m.estimator == core::EstimatorKind::Joint;
    if (body["flight"].is_object() && (joint || !explained) && body["flight"]["capacity_ah"]["final"].is_number()) {
        const core::CapacityEkf::Config& ekf = m.joint.health.enabled ? m.joint.health.ekf : m.joint.ekf;
        const double rated_ah = m.battery.capacity_ah;
        const double lo = rated_ah * (joint ? ekf.min_capacity_fraction : m.capacity.min_capacity_fraction);
        const double hi = rated_ah * (joint ? ekf.max_capacity_fraction : m.capacity.max_capacity_fraction);
        const double final_ah = body["flight"]["capacity_ah"]["final"].get<double>();
        // The joint estimator reports the weakest cell's share of its filter's capacity: with a
        // weak cell counted, a figure under the lower bound is that share, not the bound.
        const nlohmann::json deficit = body["flight"].value("pack_capacity_deficit", nlohmann::json::object());
        const bool weak_cell_counted = deficit.is_object() && deficit.value("final", 0.0) > 0.0;
        const bool high = final_ah >= 0.995 * hi, low = final_ah <= 1.005 * lo && !(joint && weak_cell_counted);
        if (rated_ah > 0.0 && (high || low)) {
            char buf[512];
            std::snprintf(buf, sizeof buf,
                          "the capacity ended at the estimator's %s bound, %.3f Ah (%.1f x the config's %.3f Ah): the "
                          "flight did not tell the pack's capacity, so its figure%s, the remaining time and the "
                          "warnings that rest on it are not to be trusted. Does the config's curve fit this pack? (%s)",
                          high ? "upper" : "lower", high ? hi : lo, (high ? hi : lo) / rated_ah, rated_ah,
                          joint ? " and its standard error" : "",
                          joint ? "battsim fit-ocv" : "battsim residual LOG -c CONFIG -o FITTED.json");
            notes.push_back(buf);
        }
    }
    if (body["flight"].is_object() && !explained) {
        // A config whose model is volts off every reading (a typed extension setting an order of
        // magnitude out: resistance_activation_k −1e5 put flight 29's model 78 V off) had
        // replayed with no word; the reference estimator's figures rest on that model.
        const nlohmann::json& err = body["flight"]["voltage_error_v"];
        const int cells = std::max(1, options.config.monitor.cells_in_series);
        const bool reference = options.config.monitor.estimator == core::EstimatorKind::Reference;
        for (const char* which : {"model", "adapted"}) {
            if (!reference && std::string(which) == "adapted") continue;  // the joint note above
            const nlohmann::json& e = err[which]["mean_abs"];
            if (!e.is_number() || !(e.get<double>() / cells > kNoPackModelVPerCell)) continue;
            char buf[200];
            std::snprintf(buf, sizeof buf, "the %s is %.2f V per cell off the measurement over the flight",
                          std::string(which) == "model" ? "config's battery model"
                                                         : "reference estimator's adapted model",
                          e.get<double>() / cells);
            notes.push_back(std::string(buf) +
                            " (mean; a cell's whole curve spans about 1.2 V): it describes no pack, so " +
                            (reference ? "the capacity, resistance and remaining time are not to be trusted"
                                       : "its model-error figures mean nothing") +
                            ". Check the config's battery settings and its battery.extensions (a value an order of "
                            "magnitude out), or fit them to this log (battsim residual LOG -c CONFIG -o FITTED.json)");
            break;  // the adapted model starts from the configured one: one note says it
        }
    }
    if (!notes.empty()) j["config_notes"] = notes;
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
