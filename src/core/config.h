// Every setting of the monitor as one plain struct: filled from JSON on the host, from
// the generated header on the firmware. Defaults are the reference 4S pack with the
// dissertation's hand-modified parameters.
#pragma once
#include <stdint.h>

#include "core/cells/cell_analyzer.h"
#include "core/cells/piao.h"
#include "core/estimate/flight_time.h"
#include "core/estimate/flying_state.h"
#include "core/estimate/initial_state.h"
#include "core/estimate/joint_estimator.h"
#include "core/estimate/low_pass.h"
#include "core/estimate/reference_capacity.h"
#include "core/estimate/resistance_estimator.h"
#include "core/estimate/rolling_average.h"
#include "core/model/extensions/extended_model.h"
#include "core/model/tremblay.h"
#include "core/sensor.h"

namespace battsim {
namespace core {

struct WarningConfig {
    float low_capacity_fraction = 0.8f;   // capacity estimate below this × rated
    float high_resistance_factor = 1.5f;  // resistance estimate above this × configured
    uint32_t min_resistance_updates = 20; // before the resistance can raise a warning
    float cell_outlier_score = 0.5f;      // |normalised cell score| at or above this
    uint32_t min_cell_outlier_samples = 50;
};

// Plausibility limits: a sample outside them is a sensor fault and is kept out of the
// estimators (a collapsing balance lead must not be blamed on a cell).
struct SensorLimits {
    float max_pack_voltage_v = 21.0f;
    float min_pack_voltage_v = 1.0f;  // any pack's; the host reads 2.0 V per cell where a config is silent
    float max_current_a = 400.0f;
    float min_current_a = -50.0f;
    float min_cell_voltage_v = 0.5f;
    float max_cell_voltage_v = 5.0f;
    float max_cell_sum_error_v = 0.5f;  // |Σ cells − pack|
};

// Which estimator fills the monitor's capacity, resistance and flight-time outputs. The
// reference one stays selectable forever, so the two can be compared on every log.
enum class EstimatorKind : uint8_t { Reference = 0, Joint = 1 };

struct MonitorConfig {
    EstimatorKind estimator = EstimatorKind::Reference;
    int cells_in_series = 4;
    TremblayParams battery;
    ModelExtensions extensions;   // optional effects on top of the model (all off by default)
    float max_voltage_v = 16.8f;  // the pack's range: bench-discharge tables and the exported header (the monitor does not read it)
    float min_voltage_v = 13.3f;
    LowPassFilter::Config current_filter;  // i* of the model: the reaction time
    ResistanceEstimator::Config resistance;
    ReferenceCapacityEstimator::Config capacity;
    FlightTimeEstimator::Config flight_time;
    RollingAverage::Config current_average;
    RollingAverage::Config power_average;
    FlyingState::Config flying;
    InitialState::Config initial;
    PiaoCellScorer::Config cells;
    JointEstimator::Config joint;
    CellAnalyzer::Config cell_analysis;  // the joint estimator's cell check
    WarningConfig warnings;
    SensorLimits sensor;
    ShuntCalibration shunt;
};

}  // namespace core
}  // namespace battsim
