#include "host/replay.h"
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <thread>

#include "core/numeric.h"
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
constexpr double kMaxRealtimeWaitS = 2.0;  // --realtime: the longest wait for one sample

// Two misreadings no reader can tell from the data alone, and no number shows: a log that
// counts discharge as negative flies nothing, and a time column in milliseconds read as
// seconds spreads a flight over days. Both read on without complaint, so say so. Two more
// shapes make every estimate rougher without any error: a pack voltage in 0.1 V steps (a
// radio's telemetry log) and samples too close together for the resistance's lag.
class InputShape {
public:
    InputShape(bool negated, double ground_a) : negated_(negated), ground_a_(ground_a) {}
    void add(const core::Sample& s) {
        if (std::isfinite(s.voltage_v) && s.voltage_v != 0.0f) {
            const double tenths = 10.0 * static_cast<double>(s.voltage_v);
            coarse_ = coarse_ && std::fabs(tenths - std::round(tenths)) < 2e-3;
            if (voltages_ == 0) first_v_ = s.voltage_v;
            last_v_ = s.voltage_v;
            varied_ = varied_ || s.voltage_v != first_v_;
            ++voltages_;
        }
        if (have_ && s.time_us > last_us_) {
            const double step_s = static_cast<double>(s.time_us - last_us_) * 1e-6;
            // The first kMaxIntervals: their median is the log's usual interval, and a replay's
            // memory stays flat however long the log (every interval had been kept).
            if (intervals_s_.size() < kMaxIntervals) intervals_s_.push_back(step_s);
            // The log's own count at loaded currents, whether or not the monitor counted (it
            // starts at a rest).
            if (std::isfinite(s.current_a) && std::fabs(s.current_a) >= ground_a_)
                loaded_mah_ += static_cast<double>(s.current_a) * step_s / 3.6;
            if (step_s > longest_s_) {
                longest_s_ = step_s;
                longest_at_s_ = static_cast<double>(last_us_ - first_us_) * 1e-6;
                // At the log's current after the gap: the monitor's own count over the step
                // had also taken its first charge estimate when that came at the same sample
                // (a ULog's 3600 s jump at 0 A read "4953 mAh counted over the gap").
                longest_mah_ = std::isfinite(s.current_a) ? static_cast<double>(s.current_a) * step_s / 3.6 : 0.0;
            }
        }
        if (!have_) first_us_ = s.time_us;
        last_us_ = s.time_us;
        have_ = true;
        if (std::isfinite(s.current_a)) {
            const double current_a = static_cast<double>(s.current_a);
            min_a_ = std::min(min_a_, current_a);
            max_a_ = std::max(max_a_, current_a);
            // On the ground (both readings under the take-off current) a step is the sensor's
            // scatter, not the load's: the first kMaxIntervals, for the scatter note below.
            if (have_current_ && std::fabs(current_a) < ground_a_ && std::fabs(last_a_) < ground_a_ &&
                ground_steps_a_.size() < kMaxIntervals)
                ground_steps_a_.push_back(std::fabs(current_a - last_a_));
            last_a_ = current_a;
            have_current_ = true;
        }
    }
    // Whether the joint estimator's resistance can pair this log's samples:
    struct Lags {
        double fastest_s = 0.0;  // the shortest median interval at which its lags are reached (0: no limit)
        double slowest_s = 0.0;  // the longest pair it takes (0: no limit)
        double prior_ohm = 0.0;  // what it uses when it measures none
        double hover_min_step_a = 0.0;  // the smallest step its hover estimate pairs (0: not the joint estimator)
    };
    // `csv`: the log is a headered CSV (the only format --negative-discharge flips); `merged`:
    // the --average-ms windows held more than one sample on average.
    // `milliamperes`: the log's current column was read in mA (a CSV log's name or --current-unit).
    std::vector<std::string> notes(bool flew, double takeoff_a, const Lags& lags, double window_s, bool csv,
                                   bool merged, bool milliamperes) const {
        const double fastest_s = lags.fastest_s;
        std::vector<std::string> out;
        char buf[512];
        // What to do about the other sign: the option flips headered CSV logs only; the
        // readers of the other formats take the sign as the autopilot or logger wrote it.
        const std::string remedy =
            !csv ? std::string(": this log's current sensor counts discharge as negative (--negative-discharge flips "
                               "headered CSV logs only: set the sensor's sign where it is logged, or export the log to CSV)")
            : negated_ ? std::string(" with --negative-discharge: if this log counts discharge as positive, replay it "
                                     "without (manifest: \"negative_is_discharge\": false)")
                       : std::string(": if this log counts discharge as negative, replay it with --negative-discharge "
                                     "(manifest: \"negative_is_discharge\": true)");
        if (!flew && max_a_ < takeoff_a && min_a_ <= -takeoff_a) {
            std::snprintf(buf, sizeof buf, "the current never reaches the take-off threshold (%.3g A) but falls to %.3g A",
                          takeoff_a, min_a_);
            out.push_back(buf + remedy);
        } else if (loaded_mah_ < -kSignMinMah && last_v_ < kSignMinFall * first_v_) {
            // A log that does reach the take-off current the wrong way round (regeneration,
            // a brief reverse reading) but whose loaded count runs backwards while the pack
            // empties. Counted only at take-off currents: a charger's taper and the rest after
            // it (a correctly signed log) count little and the voltage falls a few tenths.
            std::snprintf(buf, sizeof buf,
                          "the charge counted at currents beyond the take-off threshold is %.0f mAh (negative) while "
                          "the pack voltage fell from %.3g to %.3g V",
                          loaded_mah_, static_cast<double>(first_v_), static_cast<double>(last_v_));
            out.push_back(buf + remedy);
        }
        // The other unit: a current in amperes read as milliamperes is a thousand times low and
        // never takes off (a CMU Matrice 100 flight with --current-unit mA: 33.5 A read as
        // 0.0335 A), while the pack's voltage falls as in any flight. The reverse, milliamperes
        // read as amperes, breaks the sensor's current limit and the brief says so.
        if (!flew && milliamperes && max_a_ < takeoff_a && max_a_ * 1000.0 >= takeoff_a && last_v_ < kSignMinFall * first_v_) {
            std::snprintf(buf, sizeof buf,
                          "the current never reaches the take-off threshold (%.3g A), peaking at %.3g A read in mA, "
                          "while the pack voltage fell from %.3g to %.3g V: if the current column counts amperes, give "
                          "--current-unit A (manifest: columns.current_unit or current_unit)",
                          takeoff_a, max_a_, static_cast<double>(first_v_), static_cast<double>(last_v_));
            out.push_back(buf);
        }
        // Battery logs are written a few times a second to once every few seconds.
        const double dt_s = median(intervals_s_);
        // Unless the user's own --average-ms windows spaced them so.
        if (dt_s > kSlowestIntervalS && !(dt_s <= 1.5 * window_s)) {
            std::snprintf(buf, sizeof buf,
                          "the samples are %.4g s apart (median): if the time column counts milliseconds, give "
                          "--time-unit ms (or --time-col with a column in seconds)",
                          dt_s);
            out.push_back(buf);
        }
        // The other way round: seconds read as milliseconds squeeze a flight into a fraction
        // of a second, too short for any take-off (a CMU flight as time_ms: 200 s in 0.2 s).
        const double span_s = static_cast<double>(last_us_ - first_us_) * 1e-6;
        const bool seconds_as_ms = dt_s > 0.0 && dt_s < kFastestIntervalS && span_s < kShortestSpanS && !flew &&
                                   intervals_s_.size() >= static_cast<size_t>(kCoarseMinSamples);
        if (seconds_as_ms) {
            std::snprintf(buf, sizeof buf,
                          "the samples are %.3g ms apart (median) and the log spans %.3g s: if the time column "
                          "counts seconds, give --time-unit s (or --time-col with a column in seconds)",
                          dt_s * 1e3, span_s);
            out.push_back(buf);
        }
        if (coarse_ && varied_ && voltages_ >= kCoarseMinSamples) {
            out.push_back("the pack voltage moves in 0.1 V steps, as a radio's telemetry carries it: the capacity, "
                          "resistance and short-flight warnings read from it are rougher than from the monitor's own "
                          "sensors (README, \"Radio telemetry logs\")");
        }
        if (dt_s > 0.0 && dt_s < fastest_s && !seconds_as_ms) {
            std::snprintf(buf, sizeof buf,
                          "the samples are %.3g ms apart (median): the joint estimator's resistance compares samples "
                          "up to %.3g s apart among its last %d, so below %.3g ms it is measured late or never; "
                          "give --average-ms %.0f (manifest: average_ms)",
                          dt_s * 1e3, fastest_s * (core::DifferenceResistanceEstimator::kHistory - 1),
                          core::DifferenceResistanceEstimator::kHistory, fastest_s * 1e3, std::ceil(fastest_s * 1e3));
            out.push_back(buf);
        }
        // Windows that merge samples into intervals longer than the reference logger's own
        // join the readings either side of a current step, so each pair the resistance takes
        // straddles part of the polarisation: on the dissertation's flights 200 ms windows
        // read R0 6-9 % high and the capacity up to 14 % low (README, "Input formats"). A
        // window no longer than the log's own interval merges nothing and is not said.
        if (lags.hover_min_step_a > 0.0 && merged && dt_s > kLongestMergedIntervalS) {
            std::snprintf(buf, sizeof buf,
                          "--average-ms %.0f merges the samples into %.0f ms intervals (median), longer than the "
                          "reference logger's 68 ms: readings either side of a current step are averaged together, and "
                          "the joint estimator's resistance reads high and its capacity low (README, \"Input formats\"); "
                          "averaging is for fast logs: %.0f ms suffices",
                          window_s * 1e3, dt_s * 1e3, std::ceil(std::max(fastest_s, 1e-3) * 1e3));
            out.push_back(buf);
        }
        // A clock that jumps (a logging gap, or two sessions in one file): the monitor counts
        // the charge over it at the currents either side, and a flight's time spans it.
        if (dt_s > 0.0 && longest_s_ > kLongestGapS && longest_s_ > kGapMedians * dt_s) {
            std::snprintf(buf, sizeof buf,
                          "the log's clock jumps %.4g s at %.4g s into the log (a logging gap, or two sessions in one "
                          "file): the monitor counts the charge over the gap at the currents either side (%.4g mAh at the "
                          "current after it) and a flight's time spans it; replay two sessions apart",
                          longest_s_, longest_at_s_, std::isfinite(longest_mah_) ? longest_mah_ : 0.0);
            out.push_back(buf);
        }
        // A log written once a second (ArduCopter 3.0's CURR rows): no pair is close enough,
        // so R0 is never measured and a resistive pack hides (underpowered.log, README).
        if (flew && lags.slowest_s > 0.0 && dt_s > lags.slowest_s) {
            std::snprintf(buf, sizeof buf,
                          "the samples are %.3g s apart (median): the joint estimator's resistance pairs samples at "
                          "most %.3g s apart, so it measures few or none and keeps the config's %.3g mOhm: a pack of "
                          "higher resistance is not seen as one (no high-resistance warning; its short flight is "
                          "missed or put down to capacity)",
                          dt_s, lags.slowest_s, lags.prior_ohm * 1e3);
            out.push_back(buf);
        }
        // A noisy current sensor: the hover resistance takes its scatter for current steps the
        // voltage did not follow, and reads low (README, "A noisy current sensor"). σ from the
        // mean of the smallest 90 % of the ground steps (a difference of two readings has σ√2;
        // the mean of the smallest 90 % of |N(0, 1)| is 0.6573), not their median: in a log
        // of 0.1 A steps the median is 0 or a whole step, whatever the noise.
        if (lags.hover_min_step_a > 0.0 && ground_steps_a_.size() >= static_cast<size_t>(kCoarseMinSamples)) {
            std::vector<double> steps = ground_steps_a_;
            std::sort(steps.begin(), steps.end());
            const size_t kept = std::max<size_t>(1, steps.size() * 9 / 10);
            double sum = 0.0;
            for (size_t k = 0; k < kept; ++k) sum += steps[k];
            const double sigma_a = sum / static_cast<double>(kept) / (0.6573 * std::sqrt(2.0));
            if (sigma_a > kNoiseShareOfStep * lags.hover_min_step_a) {
                std::snprintf(buf, sizeof buf,
                              "the current scatters by about %.2g A (one standard deviation, from %zu steps on the "
                              "ground): the joint estimator's hover resistance, paired from %.3g A steps, takes that "
                              "for steps the voltage did not follow and reads low in a steady hover, and the capacity "
                              "with it; for a sensor this noisy set \"joint\": {\"hover_resistance_min_step_a\": %.2g} "
                              "(README, \"A noisy current sensor\")",
                              sigma_a, ground_steps_a_.size(), lags.hover_min_step_a,
                              std::max(1.0, std::ceil(sigma_a / kNoiseShareOfStep * 10.0) / 10.0));
                out.push_back(buf);
            }
        }
        return out;
    }

private:
    static constexpr double kSlowestIntervalS = 10.0;
    static constexpr double kLongestMergedIntervalS = 0.075;  // the reference logger's 67.7 ms and its jitter
    // A loaded count this far below zero while the voltage fell by over 3 % (the fall also
    // tells a flight in amperes read as mA from a log that stayed on the ground).
    static constexpr double kSignMinMah = 10.0;
    static constexpr float kSignMinFall = 0.97f;
    static constexpr double kFastestIntervalS = 1e-3;  // a flight controller's blackbox at most
    static constexpr double kShortestSpanS = 10.0;
    static constexpr long kCoarseMinSamples = 20;
    static constexpr size_t kMaxIntervals = 65536;
    static constexpr double kLongestGapS = 60.0;  // and kGapMedians of the usual interval
    static constexpr double kGapMedians = 100.0;
    // The scatter (σ) at which a step of hover_min_step_a is a quarter noise: at ±100 mA
    // (σ 0.058 A) on 0.2 A steps a simulated hover's capacity already read 7–10 % low.
    static constexpr double kNoiseShareOfStep = 0.25;
    bool negated_;  // --negative-discharge given
    bool coarse_ = true, varied_ = false;
    float first_v_ = 0.0f, last_v_ = 0.0f;
    long voltages_ = 0;
    std::vector<double> intervals_s_;
    uint64_t first_us_ = 0, last_us_ = 0;
    double loaded_mah_ = 0.0;  // current × interval at currents beyond the take-off threshold, as read
    double longest_s_ = 0.0, longest_at_s_ = 0.0, longest_mah_ = 0.0;  // the longest interval, where, its charge
    double ground_a_;
    bool have_current_ = false;
    double last_a_ = 0.0;
    std::vector<double> ground_steps_a_;  // |ΔI| between ground readings
    bool have_ = false;
    double min_a_ = INFINITY, max_a_ = -INFINITY;
};

}  // namespace

std::vector<std::string> other_pack_notes(const nlohmann::json& summary) {
    std::vector<std::string> out;
    for (const nlohmann::json& note : summary.value("config_notes", nlohmann::json::array()))
        if (note.is_string() && is_other_pack_note(note.get<std::string>())) out.push_back(note.get<std::string>());
    return out;
}

nlohmann::json replay_log(const std::string& path, const ReplayOptions& options, const SampleObserver& observer) {
    ReaderOptions reader_options = options.reader;
    reader_options.shunt = options.config.monitor.shunt;  // the firmware's calibration, one source
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
    InputShape shape(options.reader.columns.current_negative_is_discharge,
                     options.config.monitor.flying.min_flying_current_a);
    LogFacts facts;  // for the config's notes
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
    for (const std::string& n : shape.notes(flew, options.config.monitor.flying.min_flying_current_a, lags,
                                              static_cast<double>(options.reader.average_us) * 1e-6,
                                              info.format == LogFormat::Csv, merged,
                                              info.format == LogFormat::Csv && info.current_scale_to_a > 0.0 && info.current_scale_to_a < 0.01))
        input_notes.push_back(n);
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
