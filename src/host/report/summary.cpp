#include "host/report/summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace battsim {
namespace host {

const char* warning_name(core::Warning w) {
    switch (w) {
        case core::kWarnLowCapacity: return "low_capacity";
        case core::kWarnHighResistance: return "high_resistance";
        case core::kWarnCellOutlier: return "cell_outlier";
        case core::kWarnSensorFault: return "sensor_fault";
        case core::kWarnShortFlight: return "short_flight";
        default: return "unknown";
    }
}

using nlohmann::json;

double round_sig(double x, int digits) {
    if (!std::isfinite(x) || x == 0.0) return std::isfinite(x) ? 0.0 : x;
    // Through the decimal text: the nearest double to the rounded decimal prints as that
    // decimal; round(x·10ⁿ)/10ⁿ could land an ulp off and print as 6.799999999999999e-23.
    char text[40];
    std::snprintf(text, sizeof text, "%.*e", std::max(0, digits - 1), x);
    return std::strtod(text, nullptr);
}

double time_s_of_us(uint64_t time_us) { return static_cast<double>(time_us) / 1e6; }

double round_time_s(double time_s) {
    if (!std::isfinite(time_s)) return time_s;
    return std::round(time_s * 1e6) / 1e6;
}

std::string fixed_text(const json& v, int decimals, const char* none, double scale) {
    if (!v.is_number()) return none;
    // A half of the decimal the JSON prints rounds away from zero: 1.3175 is 1.317499… as a
    // double and had printed as 1.317 beside 1.7515 as 1.752. The nudge is far below the six
    // significant digits the figures carry.
    double x = v.get<double>() * scale;
    x += std::copysign(std::fabs(x) * 1e-12, x);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
    std::string s = buf;
    if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
    return s;
}

namespace {
// Indexed by core::SampleFault: the summary's key, and the limit it broke.
const char* const kSampleFaultText[core::kSampleFaultCount][2] = {
    {"ok", ""},
    {"not_finite", "a finite voltage and current"},
    {"pack_voltage_low", "sensor.min_pack_voltage_v"},
    {"pack_voltage_high", "sensor.max_pack_voltage_v"},
    {"current_low", "sensor.min_current_a"},
    {"current_high", "sensor.max_current_a"},
    {"cell_voltage", "sensor.min_cell_voltage_v / max_cell_voltage_v"},
    {"cell_sum", "sensor.max_cell_sum_error_v"},
};
}  // namespace

const char* sample_fault_key(uint8_t fault) { return fault < core::kSampleFaultCount ? kSampleFaultText[fault][0] : "ok"; }
const char* sample_fault_limit(uint8_t fault) { return fault < core::kSampleFaultCount ? kSampleFaultText[fault][1] : ""; }

void SummaryAccumulator::Totals::add(const Totals& o) {
    n += o.n;
    capacity_ah += o.capacity_ah;
    resistance_ohm += o.resistance_ohm;
    resistance_n += o.resistance_n;
    error_v += o.error_v;
    abs_error_v += o.abs_error_v;
    sq_error_v += o.sq_error_v;
    adapted_error_v += o.adapted_error_v;
    adapted_abs_error_v += o.adapted_abs_error_v;
    adapted_sq_error_v += o.adapted_sq_error_v;
}

SummaryAccumulator::SummaryAccumulator(size_t max_buckets) : max_buckets_(max_buckets < 16 ? 16 : max_buckets) {
    buckets_.reserve(max_buckets_);
}

void SummaryAccumulator::push(const Bucket& b) {
    if (buckets_.size() == max_buckets_) {
        // Halve the resolution: merge neighbours, double the samples per bucket.
        size_t w = 0;
        for (size_t r = 0; r + 1 < buckets_.size(); r += 2) {
            Bucket m = buckets_[r];
            m.last_us = buckets_[r + 1].last_us;
            m.totals.add(buckets_[r + 1].totals);
            buckets_[w++] = m;
        }
        buckets_.resize(w);
        per_bucket_ *= 2;
    }
    buckets_.push_back(b);
}

void SummaryAccumulator::add(const core::MonitorStatus& s) {
    ++samples_;
    latest_ = s;
    have_latest_ = true;
    const uint8_t fresh = static_cast<uint8_t>(s.warnings_raised & ~seen_raised_);
    if (fresh & (1u << core::kWarnShortFlight)) short_cause_ = s.short_flight_cause;
    if (fresh & (1u << core::kWarnCellOutlier)) {
        outlier_cell_ = s.outlier_cell;
        outlier_finding_ = s.cell_finding;
    }
    seen_raised_ = s.warnings_raised;
    for (int w = 0; w < core::kWarnCount; ++w) {
        const uint8_t bit = static_cast<uint8_t>(1u << w);
        const bool on = (s.warnings & bit) != 0, was_on = (previous_warnings_ & bit) != 0;
        std::vector<Spell>& spells = spells_[w];
        if (on && !was_on) {
            ++spell_count_[w];
            if (spells.size() < kMaxSpells) spells.push_back(Spell{s.time_us, s.time_us, true, 0});
        }
        if (on && was_on && s.time_us > previous_time_us_) active_us_[w] += s.time_us - previous_time_us_;
        // The kept spells only: a spell past kMaxSpells is counted, not listed.
        if (spells.empty() || !spells.back().open || spell_count_[w] != spells.size()) continue;
        Spell& last = spells.back();
        last.to_us = s.time_us;
        if (on && w == core::kWarnShortFlight) last.cause |= s.short_flight_cause;
        if (!on) last.open = false;
    }
    previous_warnings_ = s.warnings;
    previous_time_us_ = s.time_us;
    fault_causes_ |= s.sensor_fault_cause;
    if (s.sensor_fault_cause & core::kFaultSampleGap) {
        ++gap_count_;
        longest_gap_s_ = std::max(longest_gap_s_, s.dt_s);
    }
    if (s.sensor_fault_cause & core::kFaultCurrentOffset) fault_offset_a_ = s.current_offset_a;
    if (s.sample_fault != core::kSampleOk && s.sample_fault < core::kSampleFaultCount) ++rejected_[s.sample_fault];
    if (!s.sample_valid) {
        after_rejected_ = true;
        return;
    }
    if (after_rejected_ && have_time_) rejected_span_s_ += s.dt_s;
    after_rejected_ = false;
    ++valid_samples_;
    if (!have_time_) first_time_us_ = s.time_us;
    have_time_ = true;
    last_time_us_ = s.time_us;
    last_ = s;
    have_last_ = true;
    if (!s.initialised) return;
    if (!have_initial_) {
        have_initial_ = true;
        initial_time_us_ = s.time_us;
        initial_consumed_mah_ = s.consumed_mah;
        initial_consumed_mwh_ = s.consumed_mwh;
        initial_forced_ = s.initial_forced;
    }
    if (s.flying) ++flying_samples_;
    if (s.flying && !was_flying_) ++take_offs_;
    was_flying_ = s.flying;
    if (!have_flight_ && !s.flying) return;  // before take-off
    if (!have_flight_) {
        have_flight_ = true;
        flight_first_us_ = s.time_us;
        first_flying_ = s;
    }

    Totals t;
    t.n = 1;
    t.capacity_ah = s.capacity_ah;
    // No estimate yet (0, or the joint estimator's configured prior) is no measurement: a
    // flight too short to measure one had read the config's 0.02 ohm as mean and final.
    t.resistance_n = s.resistance_measured ? 1 : 0;
    t.resistance_ohm = s.resistance_measured ? s.resistance_ohm : 0.0f;
    const double e = static_cast<double>(s.voltage_v) - s.model_voltage_v;
    const double ea = static_cast<double>(s.voltage_v) - s.adapted_model_voltage_v;
    t.error_v = e;
    t.abs_error_v = std::fabs(e);
    t.sq_error_v = e * e;
    t.adapted_error_v = ea;
    t.adapted_abs_error_v = std::fabs(ea);
    t.adapted_sq_error_v = ea * ea;
    running_.add(t);

    if (open_count_ == 0) {
        open_ = Bucket{};
        open_.first_us = s.time_us;
        open_.remaining_time_s = s.remaining_time_s;
        open_.time_valid = s.time_valid;
    }
    open_.last_us = s.time_us;
    open_.totals.add(t);
    if (++open_count_ >= per_bucket_) {
        push(open_);
        open_count_ = 0;
    }
    if (s.flying && s.time_valid) {
        if (!low_seen_ && s.remaining_time_s < low_time_s_) {
            low_seen_ = true;
            low_from_us_ = s.time_us;
        }
        if (!critical_seen_ && s.remaining_time_s < critical_time_s_) {
            critical_seen_ = true;
            critical_from_us_ = s.time_us;
        }
        const auto spell = [&s](bool below, bool& on, long& spells, uint64_t& last_us) {
            if (below && !on) {
                ++spells;
                last_us = s.time_us;
            }
            on = below;
        };
        spell(s.remaining_time_s < low_time_s_, low_on_, low_spells_, low_last_us_);
        spell(s.remaining_time_s < critical_time_s_, critical_on_, critical_spells_, critical_last_us_);
    }
    if (s.flying) {
        flight_last_us_ = s.time_us;
        at_last_flying_ = running_;
        last_flying_ = s;
        max_pack_deficit_ = std::max(max_pack_deficit_, s.pack_capacity_deficit);
        rest_capacity_ah_ = 0.0f;  // a new flight: wait for the rest after it
    } else if (s.rest_capacity_ah > 0.0f) {
        rest_capacity_ah_ = s.rest_capacity_ah;
    }
}

namespace {
json mean_or_null(double sum, double n) { return n > 0 ? json(round_sig(sum / n)) : json(nullptr); }

json short_cause_names(uint8_t cause) {
    json names = json::array();
    if (cause & core::JointEstimator::kCauseCapacity) names.push_back("capacity");
    if (cause & core::JointEstimator::kCauseResistance) names.push_back("resistance");
    return names;
}
}  // namespace

json sensor_fault_cause_names(uint8_t causes) {
    json names = json::array();
    if (causes & core::kFaultReading) names.push_back("reading");  // `samples.rejected` counts them by limit
    if (causes & core::kFaultCells) names.push_back("cells");
    if (causes & core::kFaultCurrentOffset) names.push_back("current_offset");
    if (causes & core::kFaultSampleGap) names.push_back("sample_gap");
    return names;
}

void SummaryAccumulator::add_fault_causes(json& e) const {
    if (fault_causes_ & core::kFaultCurrentOffset) e["current_offset_a"] = round_sig(fault_offset_a_, 4);
    if (fault_causes_ & core::kFaultSampleGap)
        e["sample_gaps"] = {{"count", gap_count_}, {"longest_s", round_sig(longest_gap_s_, 4)}};
    e["cause"] = sensor_fault_cause_names(fault_causes_);
}

json SummaryAccumulator::to_json(int cells, bool cell_scores) const {
    json j;
    j["samples"] = {{"total", samples_}, {"valid", valid_samples_}, {"flying", flying_samples_}};
    // Only the reasons that occurred: a whole flight rejected (a config for another pack)
    // must be visible, an empty object is the usual case.
    nlohmann::json rejected = nlohmann::json::object();
    for (int f = 1; f < core::kSampleFaultCount; ++f)
        if (rejected_[f] > 0) rejected[sample_fault_key(static_cast<uint8_t>(f))] = rejected_[f];
    j["samples"]["rejected"] = rejected;
    j["samples"]["rejected_span_s"] = round_sig(rejected_span_s_, 6);
    j["duration_s"] = have_time_ ? json(round_sig((last_time_us_ - first_time_us_) * 1e-6, 7)) : json(nullptr);

    if (!have_flight_) {
        j["flight"] = nullptr;
    } else {
        const double dur_s = (flight_last_us_ - flight_first_us_) * 1e-6;
        const uint64_t cut20_us = flight_first_us_ + static_cast<uint64_t>(0.2 * (flight_last_us_ - flight_first_us_));

        // Buckets inside the flight (the open one too), for the 20 % means and time points.
        std::vector<Bucket> all = buckets_;
        if (open_count_ > 0) all.push_back(open_);
        Totals first20;
        for (const Bucket& b : all) {
            if (b.first_us > cut20_us) break;
            first20.add(b.totals);
        }
        auto remaining_at = [&](double fraction) -> json {
            const uint64_t t = flight_first_us_ + static_cast<uint64_t>(fraction * (flight_last_us_ - flight_first_us_));
            for (const Bucket& b : all) {
                if (b.first_us >= t) return b.time_valid ? json(round_sig(b.remaining_time_s)) : json(nullptr);
            }
            return nullptr;
        };
        const Totals& f = at_last_flying_;
        json flight;
        flight["start_s"] = time_s_of_us(flight_first_us_);
        flight["end_s"] = time_s_of_us(flight_last_us_);
        flight["duration_s"] = round_sig(dur_s, 7);
        flight["samples"] = static_cast<uint64_t>(f.n);
        // The window runs from the first take-off to the last flying sample: more than one
        // take-off puts the time on the ground between them in it, and a log that ends in the
        // air has no landing (its "final" figures are the last sample's).
        flight["take_offs"] = take_offs_;
        flight["landed"] = !last_.flying || last_.current_a < landed_below_a_;
        flight["capacity_ah"] = {{"mean", mean_or_null(f.capacity_ah, f.n)},
                                 {"first20_mean", mean_or_null(first20.capacity_ah, first20.n)},
                                 {"final", round_sig(last_flying_.capacity_ah)},
                                 {"final_sigma", last_flying_.capacity_sigma_ah > 0.0f
                                                     ? json(round_sig(last_flying_.capacity_sigma_ah))
                                                     : json(nullptr)},
                                 {"after_rest", rest_capacity_ah_ > 0.0f ? json(round_sig(rest_capacity_ah_)) : json(nullptr)}};
        flight["resistance_ohm"] = {{"mean", mean_or_null(f.resistance_ohm, f.resistance_n)},
                                    {"first20_mean", mean_or_null(first20.resistance_ohm, first20.resistance_n)},
                                    {"final", last_flying_.resistance_measured ? json(round_sig(last_flying_.resistance_ohm))
                                                                               : json(nullptr)}};
        flight["voltage_error_v"] = {
            {"model", {{"mean", mean_or_null(f.error_v, f.n)},
                       {"mean_abs", mean_or_null(f.abs_error_v, f.n)},
                       {"rms", f.n > 0 ? json(round_sig(std::sqrt(f.sq_error_v / f.n))) : json(nullptr)}}},
            {"adapted", {{"mean", mean_or_null(f.adapted_error_v, f.n)},
                         {"mean_abs", mean_or_null(f.adapted_abs_error_v, f.n)},
                         {"rms", f.n > 0 ? json(round_sig(std::sqrt(f.adapted_sq_error_v / f.n))) : json(nullptr)}}}};
        flight["consumed"] = {
            {"ah", round_sig((last_flying_.consumed_mah - first_flying_.consumed_mah) * 1e-3)},
            {"wh", round_sig((last_flying_.consumed_mwh - first_flying_.consumed_mwh) * 1e-3)}};
        flight["remaining_time_s"] = {{"at10", remaining_at(0.1)}, {"at20", remaining_at(0.2)}, {"at50", remaining_at(0.5)}};
        // In log time, as the warnings' first_time_s; null: never in flight.
        const auto began = [](bool seen, uint64_t us) { return seen ? json(time_s_of_us(us)) : json(nullptr); };
        flight["remaining_time_s"]["low_from_s"] = began(low_seen_, low_from_us_);
        flight["remaining_time_s"]["critical_from_s"] = began(critical_seen_, critical_from_us_);
        flight["remaining_time_s"]["low_spells"] = low_spells_;
        flight["remaining_time_s"]["low_last_from_s"] = began(low_seen_, low_last_us_);
        flight["remaining_time_s"]["critical_spells"] = critical_spells_;
        flight["remaining_time_s"]["critical_last_from_s"] = began(critical_seen_, critical_last_us_);
        flight["total_time_s"] = {{"final", last_flying_.time_valid ? json(round_sig(last_flying_.total_time_s)) : json(nullptr)}};
        json scores = json::array();
        for (int c = 0; c < cells && c < core::kMaxCells; ++c) scores.push_back(round_sig(last_flying_.cell_score[c], 4));
        flight["cell_scores"] = cell_scores ? scores : json(nullptr);
        bool cell_analysis = false;
        for (int c = 0; c < cells && c < core::kMaxCells; ++c)
            if (last_flying_.cell_resistance_ohm[c] != 0.0f) cell_analysis = true;
        if (cell_analysis) {  // the joint estimator's per-cell check
            json r = json::array(), d = json::array(), ds = json::array();
            for (int c = 0; c < cells && c < core::kMaxCells; ++c) {
                r.push_back(round_sig(last_flying_.cell_resistance_ohm[c], 4));
                d.push_back(round_sig(last_flying_.cell_capacity_deficit[c], 3));
                // No standard error yet is none, not a certainty of 0 (a flight too short for
                // the cell check had read [0, 0, 0, 0]).
                const float sigma = last_flying_.cell_capacity_deficit_sigma[c];
                ds.push_back(sigma > 0.0f ? json(round_sig(sigma, 3)) : json(nullptr));
            }
            flight["cell_resistance_ohm"] = r;
            // The short-lag fit's values, or until it is ready the big steps' (which carry
            // the first half second's polarisation too): a lead calibration reads the former.
            flight["cell_resistance_source"] = last_flying_.cell_resistance_from_differences ? "differences" : "steps";
            flight["cell_capacity_deficit"] = d;
            flight["cell_capacity_deficit_sigma"] = ds;
            flight["pack_capacity_deficit"] = {{"final", round_sig(last_flying_.pack_capacity_deficit, 3)},
                                               {"max", round_sig(max_pack_deficit_, 3)}};
        }
        j["flight"] = flight;
    }

    // Totals at the end of the log, including the initial estimate of charge drawn.
    if (have_last_ && last_.initialised) {
        j["consumed"] = {{"ah", round_sig(last_.consumed_mah * 1e-3)}, {"wh", round_sig(last_.consumed_mwh * 1e-3)}};
    } else {
        j["consumed"] = nullptr;
    }

    if (have_initial_) {
        j["initial_state"] = {{"time_s", time_s_of_us(initial_time_us_)},
                              {"consumed_mah", round_sig(initial_consumed_mah_)},
                              {"consumed_mwh", round_sig(initial_consumed_mwh_)},
                              {"from_rest", !initial_forced_}};
    } else {
        j["initial_state"] = nullptr;
    }

    json warnings = json::array();
    if (have_latest_) {
        const core::MonitorStatus& last_ = latest_;
        for (int w = 0; w < core::kWarnCount; ++w) {
            const uint8_t bit = static_cast<uint8_t>(1u << w);
            if (!(last_.warnings_raised & bit)) continue;
            json e;
            e["name"] = warning_name(static_cast<core::Warning>(w));
            e["first_time_s"] = time_s_of_us(last_.warning_time_us[w]);
            e["flight_time_s"] = have_flight_ && last_.warning_time_us[w] >= flight_first_us_
                                     ? json(round_sig((last_.warning_time_us[w] - flight_first_us_) * 1e-6, 7))
                                     : json(nullptr);
            e["active_at_end"] = (last_.warnings & bit) != 0;
            // Each time it was on: from its first sample to the first sample without it (null
            // when still on at the end); the short flight with the causes seen meanwhile.
            json spells = json::array();
            for (const Spell& sp : spells_[w]) {
                json o = {{"from_s", time_s_of_us(sp.from_us)},
                          {"to_s", sp.open ? json(nullptr) : json(time_s_of_us(sp.to_us))}};
                if (w == core::kWarnShortFlight) o["cause"] = short_cause_names(sp.cause);
                spells.push_back(o);
            }
            e["spells"] = spells;
            e["spell_count"] = spell_count_[w];
            e["active_s"] = round_sig(active_us_[w] * 1e-6, 7);
            if (w == core::kWarnCellOutlier && outlier_cell_ >= 0) {
                e["cell"] = outlier_cell_ + 1;
                if (outlier_finding_ == core::CellAnalyzer::kHighResistance) e["finding"] = "high_resistance";
                if (outlier_finding_ == core::CellAnalyzer::kLowCapacity) e["finding"] = "low_capacity";
            }
            if (w == core::kWarnShortFlight) {
                e["cause"] = short_cause_names(short_cause_);
            }
            if (w == core::kWarnSensorFault) add_fault_causes(e);
            warnings.push_back(e);
        }
        j["sensor_fault_samples"] = last_.sensor_fault_samples;
    }
    j["warnings"] = warnings;
    return j;
}

}  // namespace host
}  // namespace battsim
