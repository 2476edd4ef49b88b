#include "core/estimate/initial_state.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

bool InitialState::update(const TremblayModel& model, float voltage_v, float current_a, float dt_s) {
    if (status_.done) return false;
    if (fabsf(current_a) < config_.max_resting_current_a) {
        rested_s_ += dt_s;
        rest_voltage_v_ = voltage_v;
        rest_current_a_ = current_a;
    } else {
        rested_s_ = 0.0f;
    }
    // 0.1 ms slack: a float sum of sample intervals lands a hair short of round numbers.
    if (rested_s_ + 1.0e-4f < config_.stabilisation_time_s) return false;
    settle(model, voltage_v, current_a);
    return true;
}

void InitialState::force(const TremblayModel& model, float voltage_v, float current_a) {
    if (status_.done) return;
    if (rest_voltage_v_ > 0.0f) settle(model, rest_voltage_v_, rest_current_a_);
    else settle(model, voltage_v, current_a);
    status_.forced = true;
}

void InitialState::settle(const TremblayModel& model, float voltage_v, float current_a) {
    status_.used_ah = model.used_ah_at_voltage(voltage_v, current_a);
    status_.used_wh = model.energy_wh_to(status_.used_ah, current_a);
    status_.voltage_v = voltage_v;
    status_.current_a = current_a;
    status_.done = true;
}

}  // namespace core
}  // namespace battsim
