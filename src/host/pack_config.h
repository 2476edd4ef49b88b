// A config for a pack nobody has fitted yet: from its rating (cells, capacity), or from
// what an autopilot log says about it (ArduPilot BATT_CAPACITY, BATT_LOW_VOLT; PX4
// BAT1_CAPACITY, BAT1_N_CELLS, BAT1_R_INTERNAL) and how high it rests. Without one, a
// user replaying their own log ran the dissertation's 1.55 Ah 4S pack against it: a 1.76 Ah
// octocopter pack resting at 3.75 V per cell started the reference model past empty, and
// its voltage error read 89 V. `battsim make-config` writes it; `replay` notes the mismatch.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/config_json.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

struct PackRating {
    int cells = 0;                  // cells in series
    double capacity_ah = NAN;       // rated capacity
    double resistance_ohm = NAN;    // pack resistance; NaN = the reference pack's per cell, scaled by capacity
    double cutoff_voltage_v = NAN;  // loaded pack voltage the remaining time runs to; NaN = 3.325 V per cell
    double cutoff_delay_s = NAN;    // how long the flight goes on past it (joint.cutoff_delay_s); NaN = 5 s
    std::string name;               // empty: "pack-<cells>s-<mAh>"
    // "lipo" (the reference pack's curve) or "li-ion" (an 18650 cell's, read off its C/10
    // discharge: lower and longer, empty at 2.5 V, and ten times the resistance per Ah).
    std::string chemistry = "lipo";
    std::vector<std::string> sources;  // where the values came from, for the description
};

// The reference pack (configs/sim-4s.json: the dissertation's hand-modified Tremblay
// parameters and the simulator's LiPo rest curve) scaled per cell and by capacity as
// configs/generic-3s.json and sim-4s-1800.json were by hand; for "li-ion", the Samsung
// INR18650-30Q's curve and resistance scaled alike. Checked by config_from_json.
// Throws std::invalid_argument naming the value out of range.
nlohmann::json pack_config_json(const PackRating& rating);
// The settings that belong to the monitor board and its wiring rather than to the pack
// (JSON pointers): the shunt calibration, the current sensor's range and correction, which
// cells' readings carry a lead, and the MAVLink output. A fleet flies one board with many
// packs; a config made for a new pack had carried the dissertation board's calibration.
extern const char* const kBoardKeys[11];
// Sets `config`'s board settings to `board`'s (a config written for the same monitor, e.g.
// by `replay --config-out` after a charger check), as their effective values: a key `board`
// leaves at its default is set to the default. Returns the keys that changed, dotted
// ("sensor.shunt_offset_ma"), in kBoardKeys' order. A lead cell's calibrated share is not
// taken to a pack of another cell count (it depends on it): those keys go to `left`, if given.
// Throws ConfigError if the result is no valid config.
std::vector<std::string> apply_board(nlohmann::json& config, const LoadedConfig& board,
                                     std::vector<std::string>* left = nullptr);

// A note when a given pack resistance looks like one cell's (a charger shows each cell's
// internal resistance, and --resistance-mohm is the whole pack's); empty otherwise.
std::string per_cell_resistance_note(const PackRating& rating);

// What a log says about its pack; a field stays empty (0 / NaN) when the log does not say.
struct LogPack {
    int cells = 0;
    std::string cells_from;
    bool cells_declared = false;  // from a parameter (PX4's), not the log's columns or voltage
    double capacity_ah = NAN;
    std::string capacity_from;
    double cutoff_voltage_v = NAN;
    std::string cutoff_from;
    double resistance_ohm = NAN;
    std::string resistance_from;
    double cutoff_delay_s = NAN;
    std::string cutoff_delay_from;
    std::vector<std::string> ignored;  // parameters present but not taken, and why
    std::vector<std::string> notes;    // taken, with a caveat
    // Caveats on the log's cutoff, moot when the user gives one (they had said "it is the
    // cutoff all the same" beside a --cutoff-v that replaced it).
    std::vector<std::string> cutoff_notes;
    int declared_cells_beyond = 0;     // a declared count above core::kMaxCells (then cells = 0)
};
// The rating make-config writes: each value given (`given`: cells 0 and NaN = not given)
// over the log's, and `sources` saying where each came from ("capacity given", "capacity
// from BATT_CAPACITY"), in the order cells, capacity, resistance, cutoff, cutoff delay.
PackRating merge_rating(const PackRating& given, const LogPack& log);
// `resting_voltage_v`: the log's first pack voltage while at rest (NaN = not at rest).
// `cells_given` > 0: the count the values per cell (cutoff, PX4's resistance) are judged and
// converted with, when the user says the log's is wrong.
LogPack log_pack(const SourceInfo& info, double resting_voltage_v, int cells_given = 0);

// The first pack voltage at rest (|current| at most `max_current_a`) in the log's first
// 10 s: a log may open with the motors armed, and a pack rests before a flight, not after.
class FirstRest {
public:
    explicit FirstRest(double max_current_a) : max_current_a_(max_current_a) {}
    void add(const core::Sample& s);
    double voltage_v() const { return voltage_v_; }

private:
    double max_current_a_;
    double voltage_v_ = NAN;
    uint64_t t0_us_ = 0;
    bool started_ = false;
};
// Reads the whole log (its parameters may come anywhere) and gives log_pack() of it; the
// first sample counts as at rest below 1 A. Throws InputError like open_reader().
LogPack read_log_pack(const std::string& path, const ReaderOptions& options, int cells_given = 0);

// The cell count a pack resting at `voltage_v` has: the one count whose per-cell voltage lies
// where a pack takes off from (3.6-4.40 V), else the one where a charged or part-charged
// lithium cell rests (3.45-4.40 V); 0 when neither rule finds exactly one.
int cells_from_resting_voltage(double voltage_v);

}  // namespace host
}  // namespace battsim
