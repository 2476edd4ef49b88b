// The monitor: composes the model, the estimators and the cell scorer per sample behind
// one status struct. The same object runs on the ESP8266 and in `battsim replay`; it
// sees only samples and their time stamps. To embed it in other firmware (the sources to
// compile, the config, the costs, the assumptions): docs/embedding.md and its compiled
// example, tests/embed/embed_example.cpp.
#pragma once
#include <stdint.h>

#include "core/cells/piao.h"
#include "core/config.h"
#include "core/estimate/coulomb_counter.h"
#include "core/sample.h"

namespace battsim {
namespace core {

// Bits of MonitorStatus::warnings. With the joint estimator, low capacity and high resistance
// are the short flight's causes and are raised only with it; with the reference estimator
// they compare the estimates with the config's rating (WarningConfig).
enum Warning : uint8_t {
    kWarnLowCapacity = 0,
    kWarnHighResistance = 1,
    kWarnCellOutlier = 2,
    kWarnSensorFault = 3,
    kWarnShortFlight = 4,  // the flight will be > 20 % shorter than a healthy pack's
    kWarnCount = 5,
};

// Why a sample was kept out (the last sample's; the pack reading's reason wins over the
// cells'): replay reports them, since a config for another pack rejects whole flights.
enum SampleFault : uint8_t {
    kSampleOk = 0,
    kSampleNotFinite,
    kSamplePackVoltageLow,   // below sensor.min_pack_voltage_v
    kSamplePackVoltageHigh,  // above sensor.max_pack_voltage_v
    kSampleCurrentLow,       // below sensor.min_current_a
    kSampleCurrentHigh,      // above sensor.max_current_a
    kSampleCellVoltage,      // a cell outside sensor.min/max_cell_voltage_v (cells only)
    kSampleCellSum,          // the cells' sum off the pack voltage by more than max_cell_sum_error_v (cells only)
    kSampleFaultCount,
};

// Why the sensor-fault warning holds on a sample (bits, several at once): a pilot, a log's
// reader and a fleet table should tell a dropped log line from a broken sensor.
enum SensorFaultCause : uint8_t {
    kFaultReading = 1,        // the pack reading kept out (sample_fault says which limit)
    kFaultCells = 2,          // a cell reading kept out, the pack reading kept
    kFaultCurrentOffset = 4,  // joint: a current offset learnt on the ground beyond offset_fault_a
    kFaultSampleGap = 8,      // joint: this sample ends a gap longer than max_sample_gap_s (dt_s is its length)
};

// What update() returns. Units are in the names; "joint" marks what only the joint estimator
// fills. Before `initialised` (the first rest settles the state of charge: a few seconds at
// rest after power-up, or forced at a take-off) soc, consumed_* and the models read 0; the
// remaining and total times mean something only while `time_valid` (from the first take-off
// on); a resistance of 0 is none yet.
struct MonitorStatus {
    uint64_t time_us = 0;
    float dt_s = 0.0f;
    float voltage_v = 0.0f;
    float current_a = 0.0f;
    float filtered_current_a = 0.0f;
    bool sample_valid = false;  // false: sensor fault, sample kept out of the estimators
    uint8_t sample_fault = kSampleOk;  // SampleFault: why this sample (or its cells) was kept out
    bool cells_valid = false;
    bool initialised = false;   // initial state of charge known
    bool initial_forced = false;
    bool flying = false;        // joint estimator: its own flight (offset-corrected take-off, landing hold)

    float consumed_mah = 0.0f;  // since full, including the initial estimate
    float consumed_mwh = 0.0f;
    float model_voltage_v = 0.0f;          // fixed (configured) model
    float adapted_model_voltage_v = 0.0f;  // adapted model: the reference's; the joint estimator's tracking filter one step ahead
    float soc = 0.0f;                      // 0…1; reference: 1 − consumed / estimated capacity; joint: its tracking filter's
    float capacity_ah = 0.0f;              // estimated pack capacity
    float capacity_sigma_ah = 0.0f;        // joint estimator: its standard error (0 = none)
    float resistance_ohm = 0.0f;           // online resistance estimate
    // Measured from this pack's current steps: the joint estimator's resistance_ohm is its
    // configured prior until then, which a summary must not average in as a measurement.
    bool resistance_measured = false;
    float usable_capacity_ah = 0.0f;
    float remaining_time_s = 0.0f;  // flight left at the flight's mean power to the loaded cutoff (min_flight_voltage_v)
    float total_time_s = 0.0f;      // the whole flight's, from the take-off
    bool time_valid = false;
    float avg_current_a = 0.0f;
    float avg_power_w = 0.0f;
    float long_avg_power_w = 0.0f;
    float expected_time_s = 0.0f;      // joint estimator: a healthy pack's flight time
    float remaining_energy_wh = 0.0f;  // joint estimator: to the cutoff at the mean power
    float rest_capacity_ah = 0.0f;     // joint estimator: from the rests before and after a flight (0 = none)
    uint8_t short_flight_cause = 0;    // JointEstimator::Cause bits

    uint8_t cell_count = 0;  // the reference's Piao scores' cells (cell_score); 0 with the joint estimator
    float cell_score[kMaxCells] = {};
    int8_t outlier_cell = -1;  // the cell named by kWarnCellOutlier: 0-based (cell 1 = 0), −1 = none
    uint8_t cell_finding = 0;  // joint estimator: CellAnalyzer::Finding of outlier_cell
    float cell_resistance_ohm[kMaxCells] = {};
    bool cell_resistance_from_differences = false;  // false: the big steps' values (CellAnalyzer::Status)
    float cell_capacity_deficit[kMaxCells] = {};
    float cell_capacity_deficit_sigma[kMaxCells] = {};  // its standard error (the naming bar is in these)
    float pack_capacity_deficit = 0.0f;  // what the pack's capacity counts of its weakest cell (CellAnalyzer::Status)

    uint8_t warnings = 0;                       // bit per Warning, currently active
    uint8_t warnings_raised = 0;                // bit per Warning, ever raised
    uint64_t warning_time_us[kWarnCount] = {};  // first time each was raised
    uint32_t sensor_fault_samples = 0;
    uint8_t sensor_fault_cause = 0;  // SensorFaultCause bits of this sample (0: no sensor fault now)
    float current_offset_a = 0.0f;   // joint: the current-sensor offset learnt on the ground
};

// No heap, no global state (two packs: two monitors), about 6.5 KB (sizeof on the ESP8266:
// 6,496 B, the config's copy included), so usually a static object rather than a local.
class Monitor {
public:
    // Before the first update, and again to start afresh (a new pack, or a clock that went
    // back): every estimate and state is reset. The config is copied.
    void configure(const MonitorConfig& config);
    // One call per reading; the status it returns stays valid until the next call.
    const MonitorStatus& update(const Sample& sample);
    const MonitorStatus& status() const { return status_; }
    const MonitorConfig& config() const { return config_; }
    const JointEstimator& joint() const { return joint_; }
    const CellAnalyzer& cell_analyzer() const { return cell_analyzer_; }

private:
    SampleFault validate(const Sample& s, bool& cells_ok) const;  // the pack reading's fault, or the cells' (cells_ok false)
    void raise(Warning w, bool condition);

    MonitorConfig config_;
    MonitorStatus status_;
    ExtendedModel model_;  // the configured model with its extensions (plain if none)
    LowPassFilter current_filter_;
    CoulombCounter counter_;
    ResistanceEstimator resistance_;
    ReferenceCapacityEstimator capacity_;
    FlightTimeEstimator flight_time_;
    RollingAverage current_average_;
    RollingAverage power_average_;
    FlyingState flying_;
    InitialState initial_;
    PiaoCellScorer cells_;
    JointEstimator joint_;
    CellAnalyzer cell_analyzer_;
    bool have_time_ = false;
    uint64_t last_time_us_ = 0;
};

}  // namespace core
}  // namespace battsim
