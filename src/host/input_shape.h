// Notes on a log's shape for the user: replay_log() and discharge feed it every sample, so
// replay, discharge and the commands that fit along replays say the same.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/sample.h"

namespace battsim {
namespace host {

// Two misreadings no reader can tell from the data alone, and no number shows: a log that
// counts discharge as negative flies nothing, and a time column in milliseconds read as
// seconds spreads a flight over days. Both read on without complaint, so say so. Two more
// shapes make every estimate rougher without any error: a pack voltage in 0.1 V steps (a
// radio's telemetry log) and samples too close together for the resistance's lag.
// The config's pack, for the notes that judge a log against it (NaN: not known).
struct ShapePack {
    double empty_v = NAN, full_v = NAN;  // its voltage range (min_voltage_v, max_voltage_v)
    double capacity_ah = NAN;
};

// The units a headered CSV log's columns were read in, for the notes that advise another
// unit: they advise only units the column was not read in. 0: not known (another format, whose
// units no option changes).
struct ColumnUnits {
    double time_scale_to_s = 0.0;     // seconds per unit of the time column (1, 1e-3, 1e-6)
    std::string time_column;          // its name in the header
    double current_scale_to_a = 0.0;  // amperes per unit of the current column (1, 1e-3)
};

class InputShape {
public:
    // An interval this long (and kGapMedians of the usual one) is a clock jump, not sampling;
    // fit-ocv counts a log's gaps by it too.
    static constexpr double kLongestGapS = 60.0;
    // `negated`: --negative-discharge given; `ground_a`: the take-off current (below it, the
    // craft is on the ground).
    InputShape(bool negated, double ground_a, const ShapePack& pack = ShapePack())
        : negated_(negated), ground_a_(ground_a), pack_(pack) {}
    void add(const core::Sample& s);
    // A flight (or a discharge) shorter than this is no load a pack was flown on: a clock read
    // in too fine a unit (a CMU flight's 200 s as milliseconds "flew" 0.2 s with a config
    // that confirms a take-off at once). The callers pass such a one as not flown.
    static constexpr double kShortestFlightS = 1.0;
    // Whether the joint estimator's resistance can pair this log's samples:
    struct Lags {
        double fastest_s = 0.0;  // the shortest median interval at which its lags are reached (0: no limit)
        double slowest_s = 0.0;  // the longest pair it takes (0: no limit)
        double prior_ohm = 0.0;  // what it uses when it measures none
        double hover_min_step_a = 0.0;  // the smallest step its hover estimate pairs (0: not the joint estimator)
    };
    // `flew`: the monitor saw a take-off; `csv`: the log is a headered CSV (the only format
    // --negative-discharge flips); `merged`: the --average-ms windows held more than one
    // sample on average; `milliamperes`: the log's current column was read in mA (a CSV log's
    // name or --current-unit), for the note on a log that never flies; `units`: the units its
    // columns were read in, for the notes on a clock or a charge that looks misread.
    std::vector<std::string> notes(bool flew, double takeoff_a, const Lags& lags, double window_s, bool csv,
                                   bool merged, bool milliamperes = false, const ColumnUnits& units = ColumnUnits()) const;

private:
    static constexpr double kSlowestIntervalS = 10.0;
    static constexpr double kLongestMergedIntervalS = 0.075;  // the reference logger's 67.7 ms and its jitter
    // A loaded count this far below zero while the voltage fell by over 3 %.
    static constexpr double kSignMinMah = 10.0;
    // (the fall also tells a flight in amperes read as mA from a log that stayed on the ground)
    static constexpr float kSignMinFall = 0.97f;
    static constexpr double kFastestIntervalS = 1e-3;  // a flight controller's blackbox at most
    static constexpr double kShortestSpanS = 10.0;
    static constexpr long kCoarseMinSamples = 20;
    static constexpr float kHighestPackV = 200.0f;  // no drone pack's (a 48S pack rests under 202 V)
    static constexpr size_t kMaxIntervals = 65536;
    static constexpr double kGapMedians = 100.0;
    // The scatter (σ) at which a step of hover_min_step_a is a quarter noise: at ±100 mA
    // (σ 0.058 A) on 0.2 A steps a simulated hover's capacity already read 7–10 % low.
    static constexpr double kNoiseShareOfStep = 0.25;
    // A pack run from over half its range to within a tenth of empty on under 5 % of its
    // capacity: no cell does that (a 3 Ah cell's 1C discharge, its seconds read as
    // milliseconds, emptied in 3.5 s on 3 mAh).
    static constexpr double kEmptiedFromShare = 0.5, kEmptiedToShare = 0.1, kEmptiedMaxCapacityShare = 0.05;
    bool negated_;  // --negative-discharge given
    bool coarse_ = true, varied_ = false;
    float first_v_ = 0.0f, last_v_ = 0.0f;
    long voltages_ = 0;
    std::vector<double> intervals_s_;
    uint64_t first_us_ = 0, last_us_ = 0;
    double loaded_mah_ = 0.0;  // current × interval at currents beyond the take-off threshold, as read
    double counted_mah_ = 0.0;  // current × interval over the whole log, as read
    double min_temperature_c_ = INFINITY, max_temperature_c_ = -INFINITY;
    // Above this every reading: kelvin (a cell at 200 degC has long burnt).
    static constexpr double kKelvinMinC = 200.0;
    double longest_s_ = 0.0, longest_at_s_ = 0.0, longest_mah_ = 0.0;  // the longest interval, where, its charge
    static constexpr double kGapCountShare = 0.99;     // of kLongestGapS: an interval counted as long
    long gaps_ = 0;                                    // intervals over kGapCountShare × kLongestGapS
    long gap_runs_ = 0;                                // runs of consecutive such intervals
    bool last_step_long_ = false;
    double first_long_at_s_ = 0.0;                     // where the first such interval begins
    double gaps_s_ = 0.0, gaps_mah_ = 0.0;             // their time, and the charge counted over them
    double ground_a_;
    ShapePack pack_;
    bool have_current_ = false;
    double last_a_ = 0.0;
    std::vector<double> ground_steps_a_;  // |ΔI| between ground readings
    bool have_ = false;
    double min_a_ = INFINITY, max_a_ = -INFINITY;
    // Loaded current steps (the current moving by a tenth, at least 1 A) and those at which
    // the voltage repeated the sample before's value exactly: a voltage held between slower
    // updates (ArduPilot's log171.bin: 87 % of 158 steps; the shared logs otherwise 0-8 %).
    float prev_v_ = NAN;
    long load_steps_ = 0, held_steps_ = 0;
    static constexpr long kHeldMinSteps = 30;
    static constexpr double kHeldShare = 0.5;
};



}  // namespace host
}  // namespace battsim
