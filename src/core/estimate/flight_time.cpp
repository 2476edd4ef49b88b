#include "core/estimate/flight_time.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void FlightTimeEstimator::configure(const Config& config, float initial_capacity_ah) {
    config_ = config;
    status_ = Status{};
    status_.usable_capacity_ah = initial_capacity_ah;
    status_.usable_energy_wh = initial_capacity_ah * config.nominal_voltage_v;
}

void FlightTimeEstimator::track(const TremblayModel& model, float average_power_w) {
    if (!(average_power_w > 0.0f) || !(config_.min_flight_voltage_v > 0.0f)) return;
    const float current_a = average_power_w / config_.min_flight_voltage_v;
    float c = status_.usable_capacity_ah;
    if (model.voltage_v(c, current_a, current_a) > config_.min_flight_voltage_v) {
        c += c * config_.step_fraction;
    } else {
        c -= c * config_.step_fraction;
    }
    const float lo = model.capacity_ah() * 0.01f;
    const float hi = model.capacity_ah() * config_.max_capacity_factor;
    status_.usable_capacity_ah = clampf(c, lo, hi);
    status_.usable_energy_wh = status_.usable_capacity_ah * config_.nominal_voltage_v;
}

void FlightTimeEstimator::compute(float used_energy_wh, float average_power_w) {
    if (!(average_power_w > 0.0f)) {
        status_.valid = false;
        status_.remaining_time_s = 0.0f;
        status_.total_time_s = 0.0f;
        return;
    }
    status_.valid = true;
    status_.total_time_s = status_.usable_energy_wh / average_power_w * 3600.0f;
    status_.remaining_time_s = maxf(0.0f, (status_.usable_energy_wh - used_energy_wh) / average_power_w * 3600.0f);
}

}  // namespace core
}  // namespace battsim
