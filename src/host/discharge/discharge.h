// Constant-current discharge processing (`battsim discharge`): crop to where the battery was
// connected, smooth, decimate, count charge and energy, build the voltage → consumed-mAh and
// voltage → consumed-mWh lookup tables (one row per 10 mV), and locate the ends of the
// exponential and nominal zones from the curve's gradient — the points the Tremblay model's
// parameters are read from.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/model/ocv.h"
#include "core/model/tremblay.h"
#include "host/config_json.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {
namespace discharge {

// No pack the monitor reads is near this (a 14S LiPo is 58.8 V full).
constexpr double kMaxTableVoltage_v = 200.0;

struct DischargeOptions {
    ReaderOptions reader;
    double min_voltage_v = 0;   // crop: the battery counts as connected above this; also the table's bottom
    double max_voltage_v = 0;   // top of the table
    double reaction_s = 0;      // exponential moving average time constant; 0 = no smoothing
    double alpha = 0;           // or a fixed per-sample constant in (0, 1]; 0 = use reaction_s
    int decimate = 1;           // average every x samples
    double step_v = 0.01;       // table spacing
    double gradient_span = 0.01;  // fraction of the capacity the gradient is taken over
    double loaded_current_a = 1.0;  // the config's take-off current: below it the log's shape notes count a rest
    double rated_capacity_ah = 0;   // the config's, when one was given (0: none)
};

struct CurvePoint {
    double time_s = 0;  // since the first kept sample
    double voltage_v = 0;
    double current_a = 0;
    double consumed_mah = 0;
    double consumed_mwh = 0;
    double gradient_v_per_ah = 0;  // dV/dQ (negative while discharging)
};

struct TableRow {
    double voltage_v = 0;
    double consumed_mah = 0;
    double consumed_mwh = 0;
    bool measured = false;  // false: filled from the next available voltage or the nearest edge
};

struct Zones {
    bool found = false;
    std::string note;  // why not found
    double full_voltage_v = 0;
    double exponential_end_ah = 0, exponential_end_v = 0;
    double nominal_end_ah = 0, nominal_end_v = 0;
    double nominal_gradient_v_per_ah = 0;  // median dV/dQ over 30–70 % of the capacity
};

struct DischargeResult {
    std::string path;
    SourceInfo info;
    size_t samples_read = 0;
    size_t samples_kept = 0;
    double start_time_s = 0, end_time_s = 0;  // of the kept run, in the log's time
    double duration_s = 0;
    double mean_current_a = 0;  // charge / duration
    double rated_capacity_ah = 0;  // DischargeOptions' (0: no config given)
    double capacity_mah = 0;
    double energy_mwh = 0;
    double first_voltage_v = 0, last_voltage_v = 0;
    std::string ended_early;  // why the log is part of a discharge (it stops above the minimum), or empty
    std::vector<CurvePoint> curve;  // smoothed and decimated
    std::vector<TableRow> table;    // max → min voltage
    Zones zones;
};

// Throws InputError (bad log, nothing above the minimum, negative mean current) and
// std::invalid_argument (options). Notes in info.notes what makes the result doubtful: the
// log's shape (InputShape), a delivered charge far from the rated capacity, a current that
// was not constant.
DischargeResult process_discharge(const std::string& path, const DischargeOptions& options);

nlohmann::json discharge_to_json(const DischargeResult& r, bool with_table);
// Mean current / capacity, per hour: of the config's rated capacity when one was given, else
// of the charge the discharge delivered (which says nothing of a discharge stopped early, or
// of a flight).
double mean_c_rate(const DischargeResult& r);
// The same in words: "1011C of the config's rated 2.97 Ah", "14C of the charge it delivered, ...".
std::string c_rate_text(const DischargeResult& r);
std::string table_csv(const DischargeResult& r);
std::string curve_csv(const DischargeResult& r);
// Voltage against consumed charge with the gradient on the right axis and the zone ends marked.
void plot_discharge(const DischargeResult& r, const std::string& path);

// The Tremblay parameters read off the curve (as the reference did by eye): full voltage,
// the exponential-zone end, the nominal-zone end, the capacity to the minimum voltage and
// the mean current; the resistance is kept from `keep` (a single constant-current curve
// cannot separate it from E0). Throws std::invalid_argument if no zones were found.
core::TremblayParams params_from_discharge(const DischargeResult& r, const core::TremblayParams& keep);
// The joint estimator's OCV table (`joint.ocv_cell_voltage_v`) read off a slow discharge:
// per cell, evenly spaced in state of charge from the minimum voltage (SOC 0, all the charge
// the discharge delivered) to the first kept sample (SOC 1), with the ohmic sag I·R added
// back (R: the pack's internal resistance). Normalised to the delivered charge, not to a
// rated capacity: a table normalised to more charge than the pack gave ends in an
// extrapolated tail (the simulator's C/5 tables: 3.25 V at 0 % where the cutoff was 3.3).
// What is left is the polarisation's sag, I·Rp (under 1 mV per cell at C/10 on a LiPo) and
// the voltage sensor's own error; the monitor's figures move with millivolts here
// (scripts/ocv-sensitivity.py).
struct OcvTableRead {
    int cells = 1;
    double capacity_ah = 0;         // the charge the table spans (the discharge's, to its minimum)
    double sag_resistance_ohm = 0;  // R used for the I·R correction
    double mean_c_rate = 0;         // the discharge's (DischargeResult::mean_c_rate)
    std::vector<double> cell_voltage_v;  // SOC 0 … 1, ascending
    std::vector<std::string> notes;      // e.g. the discharge was too fast for a rest curve
};
// Throws std::invalid_argument for points outside 2..core::kOcvTableMaxPoints, cells < 1,
// a negative resistance, or a curve too short to read.
OcvTableRead ocv_table_from_discharge(const DischargeResult& r, int cells, double resistance_ohm, int points);
nlohmann::json ocv_table_to_json(const OcvTableRead& t);

// `base` with params_from_discharge() written in, named after the log: a start for `battsim fit`.
// With `ocv` (may be null) the joint estimator's table as well.
LoadedConfig start_config_from_discharge(const DischargeResult& r, const LoadedConfig& base, const OcvTableRead* ocv = nullptr);

}  // namespace discharge
}  // namespace host
}  // namespace battsim
