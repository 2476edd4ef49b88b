#include "core/monitor.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void Monitor::configure(const MonitorConfig& config) {
    config_ = config;
    status_ = MonitorStatus{};
    current_filter_ = LowPassFilter{};
    current_filter_.configure(config.current_filter);
    counter_.reset(0.0f, 0.0f);
    model_.configure(config.battery, config.extensions);
    resistance_.configure(config.resistance);
    capacity_.configure(config.capacity, config.battery);
    flight_time_.configure(config.flight_time, capacity_.adapted_model().capacity_ah());
    current_average_.configure(config.current_average);
    power_average_.configure(config.power_average);
    flying_.configure(config.flying);
    initial_.configure(config.initial);
    cells_.configure(config.cells);
    JointEstimator::Config jc = config.joint;
    jc.min_voltage_v = config.flight_time.min_flight_voltage_v;
    jc.min_flying_current_a = config.flying.min_flying_current_a;
    jc.landed_hold_s = config.flying.landed_hold_s;
    joint_.configure(jc, config.battery, config.cells_in_series);
    cell_analyzer_.configure(config.cell_analysis);
    have_time_ = false;
    last_time_us_ = 0;
    status_.capacity_ah = capacity_.status().capacity_ah;
    status_.usable_capacity_ah = flight_time_.status().usable_capacity_ah;
}

SampleFault Monitor::validate(const Sample& s, bool& cells_ok) const {
    const SensorLimits& lim = config_.sensor;
    cells_ok = false;
    if (!finitef(s.voltage_v) || !finitef(s.current_a)) return kSampleNotFinite;
    if (s.voltage_v < lim.min_pack_voltage_v) return kSamplePackVoltageLow;
    if (s.voltage_v > lim.max_pack_voltage_v) return kSamplePackVoltageHigh;
    if (s.current_a < lim.min_current_a) return kSampleCurrentLow;
    if (s.current_a > lim.max_current_a) return kSampleCurrentHigh;
    if (s.cell_count < 2 || s.cell_count > kMaxCells) return kSampleOk;
    float sum = 0.0f;
    SampleFault cells = kSampleOk;
    for (int c = 0; c < s.cell_count; ++c) {
        const float v = s.cell_voltage_v[c];
        if (!finitef(v) || v < lim.min_cell_voltage_v || v > lim.max_cell_voltage_v) cells = kSampleCellVoltage;
        sum += v;
    }
    if (cells == kSampleOk && !(fabsf(sum - s.voltage_v) <= lim.max_cell_sum_error_v)) cells = kSampleCellSum;
    cells_ok = cells == kSampleOk;
    return cells;
}

void Monitor::raise(Warning w, bool condition) {
    const uint8_t bit = static_cast<uint8_t>(1u << w);
    if (condition) {
        if (!(status_.warnings_raised & bit)) status_.warning_time_us[w] = status_.time_us;
        status_.warnings |= bit;
        status_.warnings_raised |= bit;
    } else {
        status_.warnings &= static_cast<uint8_t>(~bit);
    }
}

const MonitorStatus& Monitor::update(const Sample& sample) {
    // dt from the samples' own time stamps, in one place; time never runs backwards here.
    float dt_s = 0.0f;
    if (have_time_ && sample.time_us > last_time_us_) {
        dt_s = static_cast<float>(sample.time_us - last_time_us_) * 1.0e-6f;
    }
    status_.time_us = sample.time_us;

    bool cells_ok = false;
    const SampleFault fault = validate(sample, cells_ok);
    status_.sample_fault = fault;
    const bool valid = fault == kSampleOk || fault >= kSampleCellVoltage;  // a cell fault keeps the pack reading
    const bool cells_present = sample.cell_count >= 2;
    status_.sample_valid = valid;
    status_.cells_valid = valid && cells_ok;
    status_.sensor_fault_cause =
        static_cast<uint8_t>(!valid ? kFaultReading : cells_present && !cells_ok ? kFaultCells : 0);
    raise(kWarnSensorFault, status_.sensor_fault_cause != 0);
    if (status_.sensor_fault_cause != 0) ++status_.sensor_fault_samples;
    if (!valid) {
        // Keep last_time_us_: the next good sample's dt spans the gap, so its charge counts.
        return status_;
    }
    have_time_ = true;
    last_time_us_ = sample.time_us;
    status_.dt_s = dt_s;
    status_.voltage_v = sample.voltage_v;
    // A configured current-sensor correction applies before anything sees the current.
    const bool extended = model_.active();
    const float current_a = extended ? model_.corrected_current_a(sample.current_a) : sample.current_a;
    status_.current_a = current_a;

    const bool flying = flying_.update(current_a, dt_s);
    status_.flying = flying;
    const float filtered_a = current_filter_.update(current_a, dt_s);
    status_.filtered_current_a = filtered_a;
    // The extension states (RC branches, temperature, hysteresis) run on every valid sample,
    // also before the initial state is known: they start relaxing from the first one.
    if (extended) model_.update(current_a, dt_s, sample.has_temperature, sample.temperature_c);
    // Only under load: at ground idle the current steps are noise-sized and would make
    // −ΔV/ΔI meaningless (the reference monitor also ran it only while flying).
    const bool reference = config_.estimator == EstimatorKind::Reference;
    if (flying && reference) resistance_.update(sample.voltage_v, current_a, dt_s);
    status_.resistance_ohm = resistance_.status().resistance_ohm;
    status_.resistance_measured = resistance_.status().updates > 0;

    if (!status_.initialised) {
        const TremblayModel& model = capacity_.fixed_model();
        initial_.update(model, sample.voltage_v, current_a, dt_s);
        if (!initial_.status().done && flying) initial_.force(model, sample.voltage_v, current_a);
        if (!initial_.status().done) return status_;
        status_.initialised = true;
        status_.initial_forced = initial_.status().forced;
        float initial_ah = initial_.status().used_ah;
        float initial_wh = initial_.status().used_wh;
        // The sample it settled from: this one, or the last at rest before a take-off.
        const float settle_v = initial_.status().voltage_v;
        const float settle_a = initial_.status().current_a;
        // The charge drawn from the extended model (its RC and temperature states at this
        // moment); with the joint estimator, what its own state of charge says (its OCV
        // table), not the loaded Tremblay curve's: a pack resting part-charged had read 96 %
        // drawn in `consumed` next to a state of charge of 38 %. The energy to it from the
        // plain model's closed form.
        if (extended) initial_ah = model_.used_ah_at_voltage(settle_v, settle_a);
        if (!reference) {
            joint_.start(settle_v, settle_a);
            initial_ah = (1.0f - joint_.status().soc) * model.params().capacity_ah;
        }
        if (extended || !reference) initial_wh = model.energy_wh_to(initial_ah, settle_a);
        counter_.reset(initial_ah * 1000.0f, initial_wh * 1000.0f);
    } else {
        counter_.update(current_a, sample.voltage_v, dt_s);
    }
    const CoulombCounter::Status counted = counter_.status();
    status_.consumed_mah = counted.consumed_mah;
    status_.consumed_mwh = counted.consumed_mwh;
    const float used_ah = counted.consumed_mah * 0.001f;

    // What the extensions add to the plain model's voltage; the adapted model carries it too.
    float extended_v = 0.0f;
    float extension_v = 0.0f;
    if (extended) {
        extended_v = model_.voltage_v(used_ah, current_a, filtered_a);
        extension_v = extended_v - model_.base().voltage_v(used_ah, current_a, filtered_a);
    }

    // The joint estimator replaces the reference's capacity, flight-time and cell parts;
    // only the fixed model's voltage is kept for the outputs (each skipped part saves
    // model evaluations, which are soft-float exponentials on the ESP8266).
    if (flying) {
        current_average_.update(current_a, dt_s);
        power_average_.update(current_a * sample.voltage_v, dt_s);
    }
    if (flying && reference) {
        capacity_.update(used_ah, current_a, filtered_a, sample.voltage_v, status_.resistance_ohm, extension_v);
        flight_time_.track(capacity_.adapted_model(), power_average_.status().short_avg);
        if (status_.cells_valid) cells_.update(sample.cell_voltage_v, sample.cell_count);
    } else if (reference) {
        capacity_.evaluate(used_ah, current_a, filtered_a, extension_v);
    } else {
        capacity_.evaluate_fixed(used_ah, current_a, filtered_a, extension_v);
    }
    const ReferenceCapacityEstimator::Status& cap = capacity_.status();
    status_.model_voltage_v = extended ? extended_v : cap.fixed_model_voltage_v;
    status_.adapted_model_voltage_v = cap.adapted_model_voltage_v;
    status_.capacity_ah = cap.capacity_ah;
    status_.soc = cap.capacity_ah > 0.0f ? clampf(1.0f - used_ah / cap.capacity_ah, 0.0f, 1.0f) : 0.0f;

    status_.avg_current_a = current_average_.status().short_avg;
    status_.avg_power_w = power_average_.status().short_avg;
    status_.long_avg_power_w = power_average_.status().long_avg;
    // The reference's flight time; the joint estimator writes its own below (its usable
    // capacity is never tracked there, so it keeps the configured value).
    if (reference) flight_time_.compute(counted.consumed_mwh * 0.001f, status_.avg_power_w);
    const FlightTimeEstimator::Status& ft = flight_time_.status();
    status_.usable_capacity_ah = ft.usable_capacity_ah;
    status_.remaining_time_s = ft.remaining_time_s;
    status_.total_time_s = ft.total_time_s;
    status_.time_valid = ft.valid;

    bool short_flight = false;
    if (!reference) {
        joint_.set_weakest_cell_deficit(cell_analyzer_.status().pack_capacity_deficit);
        joint_.update(sample.time_us, sample.voltage_v, current_a, dt_s, flying);
        const JointEstimator::Status& js = joint_.status();
        status_.capacity_ah = js.capacity_ah;
        status_.capacity_sigma_ah = js.sigma_capacity_ah;
        status_.resistance_ohm = js.resistance_ohm;
        status_.resistance_measured = js.resistance_measured;
        status_.soc = js.soc;
        status_.remaining_time_s = js.remaining_time_s;
        status_.total_time_s = js.total_time_s;
        status_.time_valid = js.time_valid;
        status_.expected_time_s = js.expected_time_s;
        status_.remaining_energy_wh = js.remaining_energy_wh;
        status_.rest_capacity_ah = js.rest_capacity_ah;
        status_.short_flight_cause = js.cause;
        short_flight = js.short_flight;
        // The flight reported is the estimator's own, on the offset-corrected current: a
        // sensor reading 1.5 A high had "flown" on the ground, for the summary, the texts
        // and the buzzer alike.
        status_.flying = js.flying;
        // The model this estimator adapts is its tracking filter's (OCV table, R0,
        // polarisation), not the reference's Tremblay curve, which it never adapts: what that
        // filter predicted for this sample before the sample corrected it.
        status_.adapted_model_voltage_v = sample.voltage_v - js.innovation_v;
        // Sensor faults only the joint estimator can see: a current offset learnt on the
        // ground, and samples missing for longer than any logger stall (or than three of the
        // log's own intervals).
        status_.current_offset_a = js.current_offset_a;
        const uint8_t cause =
            static_cast<uint8_t>((js.current_offset_fault ? kFaultCurrentOffset : 0) | (js.sample_gap ? kFaultSampleGap : 0));
        status_.sensor_fault_cause |= cause;
        if (cause != 0) raise(kWarnSensorFault, true);
        if (status_.cells_valid) cell_analyzer_.observe(sample.cell_voltage_v, sample.cell_count, current_a);
        if (js.loaded && status_.cells_valid) {
            cell_analyzer_.update(sample.time_us, sample.cell_voltage_v, sample.cell_count, current_a,
                                  js.polarisation_current_a, used_ah, js.soc, joint_.ocv());
        } else {
            cell_analyzer_.break_history();
        }
        const CellAnalyzer::Status& ca = cell_analyzer_.status();
        for (int c = 0; c < kMaxCells; ++c) {
            status_.cell_resistance_ohm[c] = ca.resistance_ohm[c];
            status_.cell_capacity_deficit[c] = ca.capacity_deficit[c];
            status_.cell_capacity_deficit_sigma[c] = ca.capacity_deficit_sigma[c];
        }
        status_.pack_capacity_deficit = ca.pack_capacity_deficit;
        status_.cell_resistance_from_differences = ca.resistance_from_differences;
    }

    const PiaoCellScorer::Status& cs = cells_.status();
    status_.cell_count = cs.cell_count;
    if (reference) {  // the Piao scores only move in reference mode (zero otherwise)
        for (int c = 0; c < kMaxCells; ++c) status_.cell_score[c] = cs.score[c];
    }

    const WarningConfig& wc = config_.warnings;
    if (!reference) {
        // The joint estimator warns about the flight, naming its cause(s), and its cell.
        raise(kWarnShortFlight, short_flight);
        raise(kWarnLowCapacity, short_flight && (status_.short_flight_cause & JointEstimator::kCauseCapacity));
        raise(kWarnHighResistance, short_flight && (status_.short_flight_cause & JointEstimator::kCauseResistance));
        const CellAnalyzer::Status& ca = cell_analyzer_.status();
        raise(kWarnCellOutlier, ca.flagged_cell >= 0);
        status_.outlier_cell = ca.flagged_cell;
        status_.cell_finding = ca.finding;
    } else {
        const float rated_ah = config_.battery.capacity_ah;
        raise(kWarnLowCapacity, status_.capacity_ah < wc.low_capacity_fraction * rated_ah);
        raise(kWarnHighResistance, resistance_.status().updates >= wc.min_resistance_updates &&
                                       status_.resistance_ohm >
                                           wc.high_resistance_factor * config_.battery.internal_resistance_ohm);
        const bool outlier = cs.worst_cell >= 0 && cs.outlier_samples >= wc.min_cell_outlier_samples &&
                             fabsf(cs.score[cs.worst_cell]) >= wc.cell_outlier_score;
        raise(kWarnCellOutlier, outlier);
        status_.outlier_cell = outlier ? cs.worst_cell : static_cast<int8_t>(-1);
    }
    return status_;
}

}  // namespace core
}  // namespace battsim
