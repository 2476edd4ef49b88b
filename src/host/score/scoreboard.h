// `battsim score`: fly every scenario, run every column's estimator over the log, and
// judge the estimates against the truth. One table (text or JSON); deterministic however
// many threads run it.
//
// Definitions (also in the JSON's "definitions"):
// - flight fractions are of the true total flight time T (take-off to the pack's cutoff
//   flying on): "at 20 %" is the last sample at or before take-off + 0.2·T; a point past
//   the logged landing is left out;
// - remaining-time error = (estimate − true remaining) / T, in % of T; against the floor,
//   per flight |error| − the oracle's |error| (median and largest, in points);
// - remaining-energy error = (estimate − true energy to cutoff) / true energy to cutoff;
// - capacity error against the weakest cell's capacity; resistance error against the
//   pack's series ohmic resistance at that instant (temperature and charge included);
//   "end" is the last flying sample;
// - a short flight has T < 0.8 × the healthy twin's; it is warned in time when a
//   warning the pack justifies (low capacity, high resistance, or the weak cell named)
//   is active at or before 20 % of T;
// - a false health warning is a low-capacity or high-resistance warning the pack does not
//   justify (capacity above 0.9 × nominal, resistance below 1.2 × nominal at 25 °C), or a
//   short-flight warning on a flight that is not short;
// - a sensor fault is blamed on a cell when a cell the truth does not call an outlier is
//   named on a sensor-fault flight (naming a true outlier there is right, not blame).
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/score/estimator.h"
#include "host/sim/scenario.h"

namespace battsim {
namespace host {
namespace score {

constexpr const char* kScoreSchema = "battsim.score";
constexpr int kScoreVersion = 1;

struct ScoreOptions {
    int jobs = 1;
    // Non-empty: estimators read DIR/NAME.csv instead of the in-memory log; it must be the
    // log the scenario simulates now (an InputError otherwise), as the truth is its.
    std::string logs_dir;
    // Copies of the suite flown: the suite itself, then sim::reseeded copies 1 … copies − 1
    // (other gusts, cell spreads and sensor noise). The table pools every copy's flights and
    // shows the spread of the copies' own figures. Not with logs_dir.
    int copies = 1;
};

// Per flight and column.
struct ColumnFlight {
    bool has_rt[3] = {false, false, false};  // 10, 20, 50 %
    double rt_err_pct[3] = {0, 0, 0};
    bool has_energy20 = false;
    double energy_err20_pct = 0;
    bool has_cap20 = false, has_cap_end = false, has_res20 = false, has_res_end = false;
    double cap_err20_pct = 0, cap_err_end_pct = 0, res_err20_pct = 0, res_err_end_pct = 0;
    bool has_cap_rest = false;  // capacity read at the rest after landing (end of the log)
    double cap_err_rest_pct = 0;
    bool warned_in_time = false;
    std::vector<std::string> false_warnings;
    bool cell_warning = false;
    int named_cell = -1;
    bool sensor_warning = false;
    uint8_t fault_causes = 0;  // core::SensorFaultCause bits named over the log
    double first_warning_s[core::kWarnCount];  // since take-off (0 = on the ground), −1 never
    ColumnFlight() {
        for (double& t : first_warning_s) t = -1.0;
    }
};

struct FlightScore {
    std::string name;
    int copy = 0;  // which copy of the suite (0: as written)
    std::string kind;
    int cells = 0;
    double total_flight_time_s = 0, healthy_total_flight_time_s = 0, flown_s = 0;
    bool short_flight = false, degraded = false, sensor_faulty = false;
    uint8_t nameable_fault_causes = 0;  // what a monitor should name of the injected sensor faults
    int weak_cell = -1;
    std::vector<int> outlier_cells;  // any of them named counts as right (see sim::Truth)
    std::vector<std::string> justified;
    std::vector<std::string> notes;
    std::vector<ColumnFlight> columns;
};

struct ScoreResult {
    int copies = 1;
    std::vector<std::string> columns;
    std::vector<std::string> descriptions;
    std::vector<FlightScore> flights;
};

// Throws sim::ScenarioError (a scenario cannot be flown) or InputError (a log cannot be read,
// or a log of logs_dir is not the one its scenario simulates now).
ScoreResult score_scenarios(const std::vector<sim::Scenario>& scenarios, const std::vector<EstimatorColumn>& columns,
                            const ScoreOptions& options);

// One flight (exposed for tests).
FlightScore score_flight(const sim::SimulationResult& sim, const std::vector<core::Sample>& samples,
                         const std::vector<EstimatorColumn>& columns);

// The table: one row per metric, one column per estimator. With copies, each figure is
// the pooled one followed by the range of the copies' own, "0.7 (0.4..1.5)".
std::string format_table(const ScoreResult& r);
nlohmann::json to_json(const ScoreResult& r);

}  // namespace score
}  // namespace host
}  // namespace battsim
