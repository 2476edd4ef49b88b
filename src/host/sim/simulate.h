// One simulated flight end to end: plant + load profile + sensor layer → the log text and
// its truth. The truth keeps simulating past the planned landing at the flight's own power
// demand until the pack reaches its cutoff, so the true remaining flight time is known at
// every instant; a healthy twin of the pack (same seed, no ageing or weak cell) flown the
// same way gives the flight time a degraded pack is compared with.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/sim/plant.h"
#include "host/sim/scenario.h"
#include "host/sim/sensor.h"

namespace battsim {
namespace host {
namespace sim {

constexpr const char* kTruthSchema = "battsim.truth";
constexpr int kTruthVersion = 1;

// The plant at the moment a row was read: what an oracle may know.
struct RowSnapshot {
    int64_t time_ms = 0;
    double time_s = 0.0;
    PlantState state;
    double cutoff_filter_v = 0.0;      // the truth's low-passed pack voltage
    double flight_energy_wh = 0.0;     // delivered since take-off (0 before)
    bool in_flight = false;
};

struct TruthPoint {
    double time_s = 0, current_a = 0, voltage_v = 0, power_w = 0, temperature_c = 0, soc = 0, resistance_ohm = 0;
    double energy_wh = 0;  // delivered since power-on
    bool in_flight = false;
    double remaining_time_s = 0, remaining_energy_wh = 0;  // meaningful only in flight
};

struct Truth {
    double takeoff_s = 0, planned_landing_s = 0, landing_s = 0, log_end_s = 0;
    double cutoff_s = 0;                  // when the pack reaches cutoff flying on
    double total_flight_time_s = 0;       // cutoff − take-off
    double healthy_total_flight_time_s = 0;
    bool landed_by_cutoff = false;        // the planned flight was cut short
    bool cutoff_by_brownout = false;      // the pack could not deliver the demanded power
    double cutoff_voltage_v = 0;
    double energy_to_cutoff_wh = 0;       // from take-off
    double charge_to_cutoff_ah = 0;
    double mean_flight_power_w = 0;       // take-off → cutoff
    double pack_capacity_ah = 0;          // the weakest cell: what the series string can give
    double mean_cell_capacity_ah = 0;
    double nominal_pack_capacity_ah = 0;  // healthy cell capacity of the scenario, no spread
    double pack_r0_reference_ohm = 0;     // Σ R0 at 25 °C, full
    double nominal_pack_r0_reference_ohm = 0;
    double initial_charge_ah = 0;         // already drawn from the weakest cell at power-on
    double log_charge_ah = 0;             // drawn from power-on to the log's end (a charger puts back this + initial)
    // Cells beyond the bar against the median of the other cells (capacity more
    // than 10 % lower, or R0 more than 10 % higher), 0-based; whatever the scenario
    // declared: the cell-to-cell spread can push a declared 10 % cell inside the bar or
    // an undeclared one beyond it. weak_cell is the furthest of them (−1 none).
    std::vector<int> outlier_cells;
    int weak_cell = -1;
    bool degraded = false;
    bool sensor_faulty = false;
    std::vector<std::string> justified_warnings;  // low_capacity, high_resistance, cell_outlier
    PlantParams plant;
    SensorUnit sensor_unit;
    SensorStats sensor_stats;
    long rows = 0;
    std::vector<TruthPoint> series;
    double final_temperature_c = 0;
    // The plant runs on below 0 % state of charge (its OCV table extrapolated) when the
    // cutoff lets it: recorded, not prevented, so a truth past empty is seen, not trusted.
    double lowest_cell_soc = 1.0;            // over the log
    int empty_cell = -1;                     // the first cell below 0 % in the log (0-based), −1 none
    double cell_empty_s = -1.0;              // when it passed 0 %, −1 never
    double lowest_cell_soc_at_cutoff = 1.0;  // when the truth's cutoff comes (flying on past the landing)

    bool short_flight() const { return total_flight_time_s < 0.8 * healthy_total_flight_time_s; }
};

struct SimulateOptions {
    bool keep_snapshots = false;  // one RowSnapshot per logged row (for the oracle)
};

struct SimulationResult {
    Scenario scenario;
    SimLogFormat format = SimLogFormat::Raw;
    std::string log_text;
    Truth truth;
    std::vector<RowSnapshot> snapshots;
};

// Throws ScenarioError when the scenario cannot be flown (the pack is at cutoff before
// take-off, or never reaches it within max_continuation_s).
SimulationResult simulate(const Scenario& scenario, const SimulateOptions& options = {});

// The total flight time (take-off to cutoff) of the scenario's pack, or of its healthy
// twin, flown straight on without landing and without sensors; −1 if the cutoff is not
// reached within max_continuation_s after the planned landing.
double flight_time_to_cutoff(const Scenario& scenario, bool healthy);

// Flies the pack from the given state at a constant power until cutoff (the oracle's
// forward run). Returns the seconds until cutoff and the energy delivered.
struct ForwardResult {
    double time_s = 0;
    double energy_wh = 0;
    bool reached = false;
};
ForwardResult fly_to_cutoff(const PlantParams& plant, const PlantState& state, double cutoff_filter_v,
                            double power_w, double cutoff_v, double filter_s, double dt_s, double max_s);

nlohmann::json truth_to_json(const SimulationResult& r);

// When the simulated ground idle draws at least the monitor config's take-off current: the
// monitor then reads the log as one flight from its first sample, never landed (a 1S 300 mAh
// scenario at the default 5 W idle draws 1.2 A against make-config's 0.81 A bar). The text
// says what to change; empty when the ground reads as ground.
std::string ground_draw_note(const SimulationResult& r);
// The opposite: the flight draws (median) below the take-off current, so the monitor never
// sees the take-off. Empty when the flight reads as flight. Unlike ground_draw_note, without
// the scenario's name (score prints its notes after the flight's).
std::string flight_draw_note(const SimulationResult& r);
// When a cell went below 0 % state of charge in the log (a cutoff below the empty cell's
// voltage, a very weak cell): the truth is extrapolated there. Empty otherwise; without the
// scenario's name.
std::string empty_cell_note(const SimulationResult& r);

// simulate -o LOG's truth file without --truth: LOG with its extension (after the last dot of
// its file name, not of a directory's) replaced by ".truth.json".
std::string default_truth_path(const std::string& log_path);

// Writes the log and the truth JSON atomically.
void write_simulation(const SimulationResult& r, const std::string& log_path, const std::string& truth_path);

}  // namespace sim
}  // namespace host
}  // namespace battsim
