// The scoreboard's columns: anything that turns a flight's samples into per-sample
// estimates. Adding an estimator to `battsim score` is one line in standard_columns().
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/monitor.h"
#include "core/sample.h"
#include "host/config_json.h"
#include "host/sim/simulate.h"

namespace battsim {
namespace host {
namespace score {

// What an estimator says after one sample. Quantities it does not estimate stay unset.
struct Estimate {
    double time_s = 0.0;
    bool has_remaining_time = false;
    double remaining_time_s = 0.0;
    bool has_remaining_energy = false;
    double remaining_energy_wh = 0.0;  // usable energy left until the cutoff
    bool has_capacity = false;
    double capacity_ah = 0.0;
    bool has_resistance = false;
    double resistance_ohm = 0.0;
    bool has_rest_capacity = false;  // read from the rests before and after a flight
    double rest_capacity_ah = 0.0;
    uint8_t warnings = 0;      // bit per core::Warning, active after this sample
    uint8_t fault_cause = 0;   // core::SensorFaultCause bits of this sample
    int8_t outlier_cell = -1;  // 0-based cell named while the cell warning is active
};

// One flight as an estimator sees it: the log's samples, read by the same readers as
// `battsim replay`, and the monitor config for the pack. `truth` is for the oracle only.
struct FlightInput {
    std::string name;
    const LoadedConfig* config = nullptr;
    const std::vector<core::Sample>* samples = nullptr;
    const sim::SimulationResult* truth = nullptr;
};

struct EstimatorColumn {
    std::string name;
    std::string description;
    // One Estimate per sample, in order.
    std::function<std::vector<Estimate>(const FlightInput&)> run;
};

// core::Monitor as a column; `tweak` adjusts its config first (e.g. to select another
// estimator inside the core).
EstimatorColumn monitor_column(std::string name, std::string description,
                               std::function<void(core::MonitorConfig&)> tweak = nullptr);
// CoulombBaseline with the config's rated capacity: what ArduPilot/PX4 users get.
EstimatorColumn baseline_column();
// Knows the true pack and state; assumes the flight's average power so far continues.
// The floor for remaining-time error that no estimator can beat.
EstimatorColumn oracle_column();

// The joint estimator's flight-time solve (core::PowerTimeSolver on the config's OCV
// curve, minimum voltage and cutoff delay) fed the true pack every quarter second: its
// error is the model's own, apart from the estimates' (docs/estimator.md, twelfth session).
EstimatorColumn solve_truth_column();

// The scoreboard's columns, in order.
std::vector<EstimatorColumn> standard_columns();
// Columns run only when named (`battsim score --columns`): diagnostics, not estimators.
std::vector<EstimatorColumn> diagnostic_columns();
// `battsim score --columns`: the columns named, comma-separated, in that order, from the
// standard and the diagnostic ones; no name at all: the standard columns. Throws
// std::invalid_argument for a name of none, listing the names there are.
std::vector<EstimatorColumn> select_columns(const std::string& names);

}  // namespace score
}  // namespace host
}  // namespace battsim
