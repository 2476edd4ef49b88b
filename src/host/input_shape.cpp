#include "host/input_shape.h"

#include <algorithm>
#include <cstdio>

#include "core/estimate/difference_resistance.h"
#include "host/stats.h"

namespace battsim {
namespace host {

namespace {
// The units --time-unit takes.
struct TimeUnit {
    const char* option;
    const char* words;
    double scale_s;
};
constexpr TimeUnit kTimeUnits[] = {{"s", "seconds", 1.0}, {"ms", "milliseconds", 1e-3}, {"us", "microseconds", 1e-6}};

const TimeUnit* time_unit_of(double scale_s) {
    for (const TimeUnit& u : kTimeUnits)
        if (std::fabs(scale_s / u.scale_s - 1.0) < 1e-6) return &u;
    return nullptr;
}

// The units a time column read at `read_s` seconds per unit may count instead, `coarser` or
// finer than that: those that put its median interval `dt_s` among battery logs' (from
// `fastest_s` to `slowest_s`), nearest first; else the nearest one that way. None when no
// unit lies that way: advising the unit the column was read in helps no one (a time_s column
// 1 us apart had been told "give --time-unit s").
std::vector<const TimeUnit*> other_time_units(double read_s, double dt_s, bool coarser, double fastest_s,
                                              double slowest_s) {
    std::vector<const TimeUnit*> way;
    for (const TimeUnit& u : kTimeUnits)
        if (coarser ? u.scale_s > 1.5 * read_s : u.scale_s < read_s / 1.5) way.push_back(&u);
    std::sort(way.begin(), way.end(), [read_s](const TimeUnit* a, const TimeUnit* b) {
        return std::fabs(std::log(a->scale_s / read_s)) < std::fabs(std::log(b->scale_s / read_s));
    });
    std::vector<const TimeUnit*> fits;
    for (const TimeUnit* u : way) {
        const double as_u_s = dt_s * u->scale_s / read_s;
        if (as_u_s >= fastest_s && as_u_s <= slowest_s) fits.push_back(u);
    }
    if (fits.empty() && !way.empty()) fits.push_back(way.front());
    return fits;
}

// "if the time column counts seconds, give --time-unit s; if milliseconds, --time-unit ms"
std::string time_unit_advice(const std::vector<const TimeUnit*>& units) {
    std::string s;
    for (size_t k = 0; k < units.size(); ++k)
        s += (k == 0 ? std::string("if the time column counts ") + units[k]->words + ", give --time-unit "
                     : std::string("; if ") + units[k]->words + ", --time-unit ") +
             units[k]->option;
    return s;
}

// "the time column "time_s" is read in seconds"
std::string time_column_read(const ColumnUnits& units) {
    const TimeUnit* u = time_unit_of(units.time_scale_to_s);
    char scale[48];
    std::snprintf(scale, sizeof scale, "as %.3g s a unit", units.time_scale_to_s);
    return "the time column \"" + units.time_column + "\" is read " + (u ? std::string("in ") + u->words : scale);
}
}  // namespace

void InputShape::add(const core::Sample& s) {
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
        if (std::isfinite(s.current_a)) counted_mah_ += static_cast<double>(s.current_a) * step_s / 3.6;
        // 1 % short of the bar still counts: a lab file's rest sampled every 60 s, its
        // intervals a few ms either side, had counted as 46 jumps of 119.
        const bool long_step = step_s > kGapCountShare * kLongestGapS;
        if (long_step) {
            if (gaps_++ == 0) first_long_at_s_ = static_cast<double>(last_us_ - first_us_) * 1e-6;
            if (!last_step_long_) ++gap_runs_;
            gaps_s_ += step_s;
            if (std::isfinite(s.current_a)) gaps_mah_ += static_cast<double>(s.current_a) * step_s / 3.6;
        }
        last_step_long_ = long_step;
        if (step_s > longest_s_) {
            longest_s_ = step_s;
            longest_at_s_ = static_cast<double>(last_us_ - first_us_) * 1e-6;
            // At the log's current after the gap: the monitor's own count over the step
            // had also taken its first charge estimate when that came at the same sample
            // (a ULog's 3600 s jump at 0 A read "4953 mAh counted over the gap").
            longest_mah_ = std::isfinite(s.current_a) ? static_cast<double>(s.current_a) * step_s / 3.6 : 0.0;
        }
    }
    if (s.has_temperature && std::isfinite(s.temperature_c)) {
        min_temperature_c_ = std::min(min_temperature_c_, static_cast<double>(s.temperature_c));
        max_temperature_c_ = std::max(max_temperature_c_, static_cast<double>(s.temperature_c));
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
        if (have_current_ && std::fabs(current_a) >= ground_a_ &&
            std::fabs(current_a - last_a_) >= std::max(1.0, 0.1 * std::fabs(current_a)) && std::isfinite(s.voltage_v)) {
            ++load_steps_;
            if (s.voltage_v == prev_v_) ++held_steps_;
        }
        last_a_ = current_a;
        have_current_ = true;
    }
    prev_v_ = s.voltage_v;
}

std::vector<std::string> InputShape::notes(bool flew, double takeoff_a, const Lags& lags, double window_s, bool csv,
                                           bool merged, bool milliamperes, const ColumnUnits& units) const {
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
    // The units advised are those the time column was not read in: a column read in
    // milliseconds may count microseconds; one in microseconds has no finer unit to try.
    const bool time_unit_known = units.time_scale_to_s > 0.0 && !units.time_column.empty();
    // `odd`: what is odd about the spacing; `coarser`: which way the other units lie; `last`:
    // what to say when --time-unit has no unit further that way.
    const auto time_note = [&](const std::string& head, const char* odd, bool coarser, const char* last) {
        const auto others = time_unit_known ? other_time_units(units.time_scale_to_s, dt_s, coarser, kFastestIntervalS,
                                                               kSlowestIntervalS)
                                            : std::vector<const TimeUnit*>();
        if (!time_unit_known)
            out.push_back(head + ", " + odd + ": its time stamps may be in another unit than its format's");
        else if (!others.empty())
            out.push_back(head + ": " + time_unit_advice(others) + " (or --time-col with a column in seconds)");
        else
            out.push_back(head + ", " + odd + ", though " + time_column_read(units) + ", " + last +
                          "; if it is not the log's clock, give --time-col NAME");
    };
    if (dt_s > kSlowestIntervalS && !(dt_s <= 1.5 * window_s)) {
        std::snprintf(buf, sizeof buf, "the samples are %.4g s apart (median)", dt_s);
        time_note(buf, "slower than a battery logger writes", false,
                  "the finest unit --time-unit takes: if it counts a finer one (nanoseconds), convert it to microseconds");
    }
    // The other way round: seconds read as milliseconds squeeze a flight into a fraction
    // of a second, too short for any take-off (a CMU flight as time_ms: 200 s in 0.2 s).
    const double span_s = static_cast<double>(last_us_ - first_us_) * 1e-6;
    const bool seconds_as_ms = dt_s > 0.0 && dt_s < kFastestIntervalS && span_s < kShortestSpanS && !flew &&
                               intervals_s_.size() >= static_cast<size_t>(kCoarseMinSamples);
    if (seconds_as_ms) {
        std::snprintf(buf, sizeof buf, "the samples are %.3g ms apart (median) and the log spans %.3g s", dt_s * 1e3,
                      span_s);
        // A column read in seconds is in the coarsest unit there is: what may be wrong is the
        // unit it was written in (hours; a spreadsheet's days put 0.1 s 1.16 us apart), or the
        // column.
        time_note(buf, "faster and shorter than a battery log", true,
                  "the coarsest unit --time-unit takes: if it counts a coarser one (hours, or a spreadsheet's days), "
                  "convert it to seconds");
    }
    // A time or current unit a thousand times too small that still flies: a 1 ms spacing is a
    // blackbox log's too, so the spacing alone cannot tell; the charge the pack emptied on can.
    const double range_v = pack_.full_v - pack_.empty_v;
    const double capacity_mah = 1000.0 * pack_.capacity_ah;
    if (!seconds_as_ms && range_v > 0.0 && capacity_mah > 0.0 && voltages_ >= kCoarseMinSamples &&
        first_v_ >= pack_.empty_v + kEmptiedFromShare * range_v && last_v_ <= pack_.empty_v + kEmptiedToShare * range_v &&
        std::fabs(counted_mah_) < kEmptiedMaxCapacityShare * capacity_mah) {
        std::snprintf(buf, sizeof buf,
                      "the pack voltage fell from %.4g to %.4g V (the config's range: %.4g to %.4g V) on %.3g mAh "
                      "counted over %.4g s, %.2g %% of the config's %.4g Ah",
                      static_cast<double>(first_v_), static_cast<double>(last_v_), pack_.full_v, pack_.empty_v,
                      std::fabs(counted_mah_), span_s, 100.0 * std::fabs(counted_mah_) / capacity_mah, pack_.capacity_ah);
        // Only the units the columns were not read in: a coarser time unit, amperes for a
        // current read in milliamperes.
        const auto coarser = time_unit_known ? other_time_units(units.time_scale_to_s, dt_s, true, kFastestIntervalS,
                                                                kSlowestIntervalS)
                                             : std::vector<const TimeUnit*>();
        const bool current_known = units.current_scale_to_a > 0.0;
        const bool amperes_advised = current_known && units.current_scale_to_a < 0.01;
        std::string advice = time_unit_advice(coarser);
        if (amperes_advised)
            advice += advice.empty() ? "if the current column counts amperes, give --current-unit A"
                                     : "; if the current column counts amperes, --current-unit A";
        if (!time_unit_known)
            advice = "the log's time or current may be in another unit than its format's, or the config another pack's";
        else if (advice.empty())
            advice = "no coarser unit to read them in, as " + time_column_read(units) +
                     (current_known ? " and the current in amperes" : "") +
                     ": check that they are the log's time and current columns, and that the config is this pack's";
        out.push_back(std::string(buf) + ": " + advice);
    }
    // A temperature in kelvin reads as a pack far past burning: a model's temperature terms
    // then run it hot (its resistance near nothing).
    if (std::isfinite(min_temperature_c_) && min_temperature_c_ > kKelvinMinC) {
        std::snprintf(buf, sizeof buf,
                      "the temperature reads %.4g to %.4g degC, every reading above %.0f: in kelvin? battsim reads "
                      "degrees Celsius (subtract 273.15 from the column)",
                      min_temperature_c_, max_temperature_c_, kKelvinMinC);
        out.push_back(buf);
    }
    // Not of a pack read a thousand times high: whole millivolts are tenths too.
    if (coarse_ && varied_ && voltages_ >= kCoarseMinSamples && first_v_ < kHighestPackV) {
        out.push_back("the pack voltage moves in 0.1 V steps, as a radio's telemetry carries it: the capacity, "
                      "resistance and short-flight warnings read from it are rougher than from the monitor's own "
                      "sensors (README, \"Radio telemetry logs\")");
    }
    // Not of a radio's 0.1 V steps (said above), where a repeat is the resolution's.
    if (!coarse_ && load_steps_ >= kHeldMinSteps && held_steps_ >= kHeldShare * static_cast<double>(load_steps_)) {
        std::snprintf(buf, sizeof buf,
                      "the voltage repeats the sample before's value at %ld of %ld steps of the current in flight: it is "
                      "recorded less often than the current and held between, so a current step's sag shows late and the "
                      "resistance, capacity and warnings read from it are rougher (ArduPilot's log171.bin: its capacity "
                      "at the landing 3.02 Ah as logged, 3.55 Ah with --average-ms 150)",
                      held_steps_, load_steps_);
        out.push_back(buf);
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
    const double mean_long_s = gaps_ > 0 ? gaps_s_ / static_cast<double>(gaps_) : 0.0;
    // Runs of three or more on average, all within 5 % of their mean.
    const bool slow_stretches = gaps_ >= 3 * gap_runs_ && gap_runs_ > 0 && longest_s_ < 1.05 * mean_long_s;
    if (dt_s > 0.0 && longest_s_ > kLongestGapS && longest_s_ > kGapMedians * dt_s && slow_stretches) {
        // All alike and in runs: the log was written that slowly for a while (Panasonic's
        // -10 degC file rests 2 h at one row a minute), no gap and no second session.
        std::snprintf(buf, sizeof buf,
                      "the log is written every %.4g s (their mean) at %ld intervals in %ld stretch%s, %.4g s in all, "
                      "the first at %.4g s into the log: the monitor counts the charge over each at the current after it "
                      "(%.4g mAh in all), and the resistance and the filters see no step there",
                      mean_long_s, gaps_, gap_runs_, gap_runs_ == 1 ? "" : "es", gaps_s_, first_long_at_s_,
                      gaps_mah_ + 0.0);
        out.push_back(buf);
    } else if (dt_s > 0.0 && longest_s_ > kLongestGapS && longest_s_ > kGapMedians * dt_s) {
        std::snprintf(buf, sizeof buf,
                      "the log's clock jumps %.4g s at %.4g s into the log (a logging gap, or two sessions in one "
                      "file): the monitor counts the charge over the gap at the currents either side (%.4g mAh at the "
                      "current after it) and a flight's time spans it; replay two sessions apart",
                      longest_s_, longest_at_s_, std::isfinite(longest_mah_) ? longest_mah_ + 0.0 : 0.0);  // + 0.0: no "-0 mAh"
        std::string note = buf;
        // The longest of several: a lab file's pulse sets, hours apart, had read as one jump.
        if (gaps_ > 1) {
            std::snprintf(buf, sizeof buf,
                          "; it is the longest of %ld jumps over %.0f s, %.4g s in all, %.4g mAh counted over them", gaps_,
                          kLongestGapS, gaps_s_, gaps_mah_ + 0.0);
            note += buf;
        }
        out.push_back(note);
    }
    // A log written once a second (ArduCopter 3.0's CURR rows): no pair is close enough,
    // so R0 is never measured and a resistive pack hides (underpowered.log, README).
    if (flew && lags.slowest_s > 0.0 && dt_s > lags.slowest_s) {
        std::snprintf(buf, sizeof buf,
                      "the samples are %.3g s apart (median): the joint estimator's resistance pairs samples at "
                      "most %.3g s apart, so it measures few or none and keeps the config's %.3g mOhm: a pack of "
                      "higher resistance is not seen as one (no high-resistance warning; its short flight is "
                      "missed or put down to capacity): give the pack's measured resistance (battery."
                      "internal_resistance_ohm; make-config --resistance-mohm, a charger's reading)",
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

}  // namespace host
}  // namespace battsim
