// The joint estimator's OCV table stitched together from a fleet's ordinary flights, for
// packs nobody discharged slowly on a bench. Each flight starts at its own state of charge
// (packs flown again without a recharge) and covers a slice of the curve; the slices overlap.
// All flights are fitted together to the measured voltage, per cell:
//   V/N = OCV(s0 − q/C) − (r + r_w·q)·I − r_fast·LP(I, fast) − r_slow·LP(I, slow)
// with q the charge counted since the log's first sample and C the config's capacity. The
// table, the polarisation (r_fast, r_slow) and the warming (r_w) are the fleet's; the start s0
// and the ohmic r each flight's own. For fixed starts the model is linear in the rest, so the
// fit first alternates a linear least-squares solve with a Gauss-Newton step per flight, then
// finishes with Levenberg-Marquardt on everything at once; robust (Huber) weights throughout:
// real logs have short sags no curve explains.
//
// What the data cannot say is taken from the config: where no flight reaches, the table
// keeps the config's curve (a weak prior, and the correction to it is kept smooth), and the
// state-of-charge axis is the config's capacity (flights that never reach empty do not
// measure it). The table is only as right as that axis: the capacity the monitor then reports
// is against it, which is what a fleet compares pack by pack.
#pragma once
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/config_json.h"
#include "host/fit/trace.h"  // TooLittleData
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {
namespace fit {

// A stitched table no pack has (far outside the voltages measured and the config's curve,
// falling, empty far below the config's minimum voltage, or dragged far from the prior where no
// sample reached): the data's fault, refused rather than written (an InputError, exit 3).
// `file` is the one log fitted, empty for several.
class ImplausibleTable : public InputError {
public:
    ImplausibleTable(const std::string& file, const std::string& what) : InputError(file, 0, 0, what) {}
};

struct OcvStitchOptions {
    int points = 21;                // table points, SOC 0 … 1 (2..core::kOcvTableMaxPoints)
    double fast_time_s = 3.0;       // the polarisation's two low-passes of the current
    double slow_time_s = 0.0;       // 0: the best fit of 20, 30, 45, 60 and 90 s
    double prior_sigma_v = 0.05;    // per cell: the table's distance from the config's curve
    double smooth_sigma_v = 0.005;  // per cell: second difference of that distance
    // Per cell: the table's empty point (SOC 0) against the config's: what "empty" means is
    // the user's choice (the capacity is the charge down to it), and flights rarely get there.
    double empty_sigma_v = 0.01;
    double huber_k = 1.5;           // robust weight beyond this many robust standard deviations
    int iterations = 100;           // most rounds of the joint step (the alternation: at most 20 before it)
    // Weight of a sample at rest (|I| < 1 A) against one in flight: the rests before and
    // after a flight hold the curve itself, the flight holds it behind the sag's model.
    double rest_weight = 10.0;
    double chain_slope_v = 0.5;     // per cell per unit SOC: placing starts below every known rest
    // The fullest flight's start is taken as full (SOC 1): without it only the weak prior
    // pins where the slices sit on the state-of-charge axis.
    bool fullest_is_full = true;
    // Start from the config's table when it has one; false: from its model's no-load curve.
    bool prior_from_table = true;
};

struct OcvStitchFlight {
    std::string log;
    bool test = false;        // evaluated with the fitted table, not fitted
    size_t samples = 0;       // valid samples used
    double charge_ah = 0;     // counted over the log
    double start_soc_before = 0, start_soc = 0;  // fitted on the config's curve / on the table
    double rms_before_v = 0, rms_v = 0;          // per cell
    double resistance_before_ohm = 0, resistance_ohm = 0;  // the flight's own ohmic, pack
    // Per cell, at most about 600 samples: the measured voltage with the fitted sag added
    // back, against the fitted state of charge; what the flight says of the curve (for plots).
    std::vector<double> soc, ocv_v;
};

struct OcvStitch {
    int cells = 1;
    double capacity_ah = 0;
    std::vector<double> prior_v;  // the config's curve at the table's points, per cell
    std::vector<double> table_v;  // fitted, per cell, ascending
    std::vector<double> support;  // samples per point (interpolation weight): what the data holds
    double soc_min = 0, soc_max = 0;   // the fitted flights' span
    // Pack resistances, fitted with the config's curve and with the table: the flights'
    // median ohmic one, and the shared polarisation.
    double resistance_before_ohm = 0, fast_before_ohm = 0, slow_before_ohm = 0;
    double resistance_ohm = 0, fast_ohm = 0, slow_ohm = 0;
    double rms_before_v = 0, rms_v = 0;            // fitted flights, per cell
    double test_rms_before_v = 0, test_rms_v = 0;  // test flights (0 without any)
    int iterations = 0;
    double fast_time_s = 0, slow_time_s = 0;  // the polarisation's low-passes (slow: chosen)
    std::vector<std::pair<double, double>> slow_time_candidates;  // (slow time s, rms V per cell)
    std::vector<OcvStitchFlight> flights;
    std::vector<std::string> notes;  // what the fit could not tell, in words for the user
};

// One log and how to read it (a fleet's logs may come in different formats).
struct OcvStitchLog {
    std::string path;
    ReaderOptions reader;
    bool test = false;  // evaluated with the fitted table, not fitted
};

// fit-ocv --test-every K: marks every Kth log from the 2nd on (indices 1, K+1, 2K+1, ...) as a
// test log and the others as fitted (for K > 1 the first log is always fitted; K = 1 holds
// out all). K = 0 (not given) leaves the marks as they are.
void hold_out_every(std::vector<OcvStitchLog>& logs, unsigned every);

// Reads every log (throws InputError like replay_log) and fits; throws ImplausibleTable for a
// table no pack has (after writing the notes to `notes_out`). Throws std::invalid_argument
// for bad options, TooLittleData (an InputError) for no fitted log of 10 valid samples. With `notes_out`, each of the notes
// is also written there as it is found ("battsim fit-ocv: note: ..."), a log's as it is read.
OcvStitch stitch_ocv(const std::vector<OcvStitchLog>& logs, const LoadedConfig& config, const OcvStitchOptions& options,
                     std::ostream* notes_out = nullptr);
// The same with one reader for all.
OcvStitch stitch_ocv(const std::vector<std::string>& logs, const std::vector<std::string>& test_logs,
                     const ReaderOptions& reader, const LoadedConfig& config, const OcvStitchOptions& options);

// `config` with the fitted table as the joint estimator's `ocv_cell_voltage_v`.
LoadedConfig with_stitched_table(const LoadedConfig& config, const OcvStitch& s);

nlohmann::json to_json(const OcvStitch& s);

}  // namespace fit
}  // namespace host
}  // namespace battsim
