// Per-log summary: the quantities of the dissertation's appendix table and more,
// accumulated sample by sample in memory that does not grow with the log's length.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/monitor.h"

namespace battsim {
namespace host {

// The warnings' names in summaries and scoreboards (host only: the device sends bits and
// its own sentences, so the names stay out of the core's flash).
const char* warning_name(core::Warning w);

constexpr const char* kSummarySchema = "battsim.summary";
constexpr int kSummaryVersion = 1;

// Rounds to `digits` significant digits so summaries print short, stable numbers.
double round_sig(double x, int digits = 6);
// A time stamp in seconds to the microsecond, whatever its size: significant digits would
// round a Unix-time stamp (1.7e9 s) to 10 s and read a 3 s warning spell as none.
double time_s_of_us(uint64_t time_us);
double round_time_s(double time_s);

// A summary number for people: `decimals` fixed decimals of the value × `scale`, `none` for
// a null (or any non-number); -0.000 prints as 0.000. The tables and the brief share it.
std::string fixed_text(const nlohmann::json& v, int decimals, const char* none = "–", double scale = 1.0);

// The names of core::SensorFaultCause bits, in bit order ("reading", "cells",
// "current_offset", "sample_gap"): the summary's and the scoreboard's sensor-fault causes.
nlohmann::json sensor_fault_cause_names(uint8_t causes);

// The summary's key for a core::SampleFault, and the config key whose limit it broke.
const char* sample_fault_key(uint8_t fault);
const char* sample_fault_limit(uint8_t fault);

class SummaryAccumulator {
public:
    // Bucket count before neighbouring buckets merge. The buckets fill from the take-off to
    // the end of the log, so a log whose flight and rest after it stay within this many
    // samples (about 18 min at 15 Hz) is summarised exactly; a longer one (hours logged on the
    // ground after a landing) gets its 20 % means and time points to within one bucket.
    explicit SummaryAccumulator(size_t max_buckets = 16384);

    void add(const core::MonitorStatus& s);
    // The current below which a pack is on the ground: a log that ends within the landing
    // hold (its last sample down, the flight not yet ended) has landed all the same.
    void set_landed_below_a(float current_a) { landed_below_a_ = current_a; }
    // The telemetry's LOW and CRITICAL battery states (remaining flight time below these):
    // when each began in flight, which a ground station hears but the warnings do not list.
    void set_battery_state_times(float low_time_s, float critical_time_s) {
        low_time_s_ = low_time_s;
        critical_time_s_ = critical_time_s;
    }

    struct Totals {
        double n = 0;
        double capacity_ah = 0, resistance_ohm = 0;
        double resistance_n = 0;  // samples with a resistance estimate (0 = none yet: not averaged in)
        double error_v = 0, abs_error_v = 0, sq_error_v = 0;
        double adapted_error_v = 0, adapted_abs_error_v = 0, adapted_sq_error_v = 0;
        void add(const Totals& o);
    };
    struct Bucket {
        uint64_t first_us = 0, last_us = 0;
        float remaining_time_s = 0;  // at the bucket's first sample
        bool time_valid = false;
        Totals totals;
    };

    // Everything except the input description; `cells` = pack cell count; `cell_scores`:
    // whether the estimator computes the cells' Piao scores (the reference; the joint
    // estimator does not, and its zeros had read as "every cell typical").
    nlohmann::json to_json(int cells, bool cell_scores = true) const;

    uint64_t samples() const { return samples_; }

private:
    void push(const Bucket& b);
    // The sensor-fault warning's causes and what each measured, into its summary entry.
    void add_fault_causes(nlohmann::json& entry) const;

    size_t max_buckets_;
    size_t per_bucket_ = 1;
    std::vector<Bucket> buckets_;
    Bucket open_;
    size_t open_count_ = 0;

    uint64_t samples_ = 0, valid_samples_ = 0, flying_samples_ = 0;
    float landed_below_a_ = 1.0f;
    uint64_t take_offs_ = 0;     // flying after a sample that was not (two hops: one window, said)
    bool was_flying_ = false;
    uint64_t rejected_[core::kSampleFaultCount] = {};  // samples (or their cells) kept out, by reason
    // The time the pack readings kept out spanned: the monitor counts it at the next valid
    // sample's current, which a limit below the flight's current reads low.
    double rejected_span_s_ = 0.0;
    bool after_rejected_ = false;
    bool have_time_ = false, have_flight_ = false;
    uint64_t first_time_us_ = 0, last_time_us_ = 0;
    uint64_t flight_first_us_ = 0, flight_last_us_ = 0;
    Totals running_;        // from the first flying sample
    Totals at_last_flying_; // snapshot of running_ at the last flying sample
    float rest_capacity_ah_ = 0.0f;  // the latest from a rest after the flight (0 = none)
    float low_time_s_ = -1.0f, critical_time_s_ = -1.0f;  // -1: not set
    bool low_seen_ = false, critical_seen_ = false;
    uint64_t low_from_us_ = 0, critical_from_us_ = 0;
    // Each state's spells in flight, and when the last began: a LOW at take-off that cleared
    // 13 s later and came back 80 s before the landing had read as LOW from take-off on.
    bool low_on_ = false, critical_on_ = false;
    long low_spells_ = 0, critical_spells_ = 0;
    uint64_t low_last_us_ = 0, critical_last_us_ = 0;
    float max_pack_deficit_ = 0.0f;  // the most the pack counted of a weak cell, in flight
    core::MonitorStatus first_flying_, last_flying_, last_;
    core::MonitorStatus latest_;  // any sample, valid or not: warnings and fault counts
    bool have_last_ = false, have_latest_ = false;
    bool have_initial_ = false;
    uint64_t initial_time_us_ = 0;
    float initial_consumed_mah_ = 0, initial_consumed_mwh_ = 0;
    bool initial_forced_ = false;
    uint8_t seen_raised_ = 0;        // warnings already recorded below
    uint8_t short_cause_ = 0;        // cause bits when the short-flight warning was first raised
    int8_t outlier_cell_ = -1;       // cell named when the cell warning was first raised
    uint8_t outlier_finding_ = 0;
    // When each warning was on: a verdict can clear and hold again (a cold pack warms, then
    // its capacity shows), which the first raise alone does not say. The first kMaxSpells
    // are kept (memory stays bounded on a flickering sensor fault); all are counted.
    struct Spell {
        uint64_t from_us = 0, to_us = 0;
        bool open = true;
        uint8_t cause = 0;  // short flight: every cause seen while it was on
    };
    static constexpr size_t kMaxSpells = 16;
    std::vector<Spell> spells_[core::kWarnCount];
    uint64_t spell_count_[core::kWarnCount] = {};
    uint64_t active_us_[core::kWarnCount] = {};
    uint8_t previous_warnings_ = 0;
    uint64_t previous_time_us_ = 0;
    uint8_t fault_causes_ = 0;        // core::SensorFaultCause bits seen on any sample
    uint64_t gap_count_ = 0;          // samples ending a gap the joint estimator called a fault
    float longest_gap_s_ = 0.0f;
    float fault_offset_a_ = 0.0f;     // the learnt current offset on the latest sample it was a fault
};

}  // namespace host
}  // namespace battsim
