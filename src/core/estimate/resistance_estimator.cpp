#include "core/estimate/resistance_estimator.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void ResistanceEstimator::configure(const Config& config) {
    config_ = config;
    status_ = Status{};
    status_.resistance_ohm = config.initial_resistance_ohm;
    current_max_a_ = 0.0f;
    voltage_ref_v_ = 0.0f;
    current_ref_a_ = 0.0f;
    started_ = false;
}

void ResistanceEstimator::update(float voltage_v, float current_a, float dt_s) {
    if (!(current_a >= config_.min_current_a)) return;  // no load, nothing to learn
    if (!started_) {
        // Start the filters on the first loaded sample rather than at zero: from zero, the
        // first few "steps" are the filters' own start-up and read as ohms of resistance.
        started_ = true;
        status_.voltage_filtered_v = voltage_v;
        status_.current_filtered_a = current_a;
        voltage_ref_v_ = voltage_v;
        current_ref_a_ = current_a;
        current_max_a_ = current_a;
        status_.resting_voltage_v = voltage_v + current_a * status_.resistance_ohm;
        return;
    }
    current_max_a_ = maxf(current_max_a_, current_a);
    const float current_delta_a = current_a - status_.current_filtered_a;
    if (current_delta_a == 0.0f) return;

    if (voltage_v > voltage_ref_v_) {
        voltage_ref_v_ = voltage_v;
        current_ref_a_ = current_a;
    }

    const float tc = config_.filter_time_constant_s;
    const float filter_alpha = clampf(dt_s / (dt_s + tc), 0.0f, config_.max_filter_alpha);
    const float blend = minf(1.0f, config_.blend_gain * fabsf(current_delta_a / current_max_a_));
    const float estimate_ohm = -(voltage_v - status_.voltage_filtered_v) / current_delta_a;
    if (estimate_ohm >= config_.min_current_a) {  // ArduPilot's "is positive"
        status_.resistance_ohm = status_.resistance_ohm * (1.0f - blend) + estimate_ohm * blend;
        ++status_.updates;
    }
    // The sag from the best point seen can only be this large: cap R by it.
    if (voltage_ref_v_ > voltage_v && current_a > current_ref_a_) {
        const float max_ohm = (voltage_ref_v_ - voltage_v) / (current_a - current_ref_a_);
        status_.resistance_ohm = minf(status_.resistance_ohm, max_ohm);
    }

    status_.voltage_filtered_v += filter_alpha * (voltage_v - status_.voltage_filtered_v);
    status_.current_filtered_a += filter_alpha * (current_a - status_.current_filtered_a);
    status_.resting_voltage_v = voltage_v + current_a * status_.resistance_ohm;
}

}  // namespace core
}  // namespace battsim
