#include "core/estimate/reference_capacity.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void ReferenceCapacityEstimator::configure(const Config& config, const TremblayParams& params) {
    config_ = config;
    fixed_.configure(params);
    adapted_.configure(params);
    rated_capacity_ah_ = fixed_.capacity_ah();
    beyond_count_ = 0;
    status_ = Status{};
    status_.capacity_ah = adapted_.capacity_ah();
    status_.resistance_ohm = adapted_.resistance_ohm();
}

void ReferenceCapacityEstimator::evaluate(float used_ah, float current_a, float filtered_current_a,
                                          float extension_v) {
    extension_v_ = extension_v;
    status_.fixed_model_voltage_v = fixed_.voltage_v(used_ah, current_a, filtered_current_a) + extension_v;
    status_.adapted_model_voltage_v = adapted_voltage_v(used_ah, current_a, filtered_current_a);
}

void ReferenceCapacityEstimator::evaluate_fixed(float used_ah, float current_a, float filtered_current_a,
                                                float extension_v) {
    extension_v_ = extension_v;
    status_.fixed_model_voltage_v = fixed_.voltage_v(used_ah, current_a, filtered_current_a) + extension_v;
    status_.adapted_model_voltage_v = status_.fixed_model_voltage_v;
}

void ReferenceCapacityEstimator::update(float used_ah, float current_a, float filtered_current_a,
                                        float measured_v, float resistance_ohm, float extension_v) {
    evaluate(used_ah, current_a, filtered_current_a, extension_v);
    float error_v = measured_v - status_.adapted_model_voltage_v;
    if (fabsf(error_v) <= config_.max_voltage_variance_v) {
        beyond_count_ = 0;
        return;
    }
    if (resistance_ohm > 0.0f && resistance_ohm != adapted_.resistance_ohm()) {
        adapted_.set_resistance_ohm(resistance_ohm, config_.resistance_keeps_e0);
        status_.resistance_ohm = resistance_ohm;
        status_.adapted_model_voltage_v = adapted_voltage_v(used_ah, current_a, filtered_current_a);
        error_v = measured_v - status_.adapted_model_voltage_v;
        if (fabsf(error_v) <= config_.max_voltage_variance_v) {
            beyond_count_ = 0;
            return;
        }
    }
    if (++beyond_count_ < config_.persistence_updates) return;
    beyond_count_ = 0;
    // Measured above the model: the pack holds more than the model thinks, and vice versa.
    const float step_ah = rated_capacity_ah_ * config_.capacity_step_fraction;
    const float lo = rated_capacity_ah_ * config_.min_capacity_fraction;
    const float hi = rated_capacity_ah_ * config_.max_capacity_fraction;
    const float next = clampf(adapted_.capacity_ah() + (error_v > 0.0f ? step_ah : -step_ah), lo, hi);
    if (next != adapted_.capacity_ah()) {
        status_.capacity_steps += error_v > 0.0f ? 1 : -1;
        adapted_.set_capacity_ah(next);
        status_.capacity_ah = next;
        status_.adapted_model_voltage_v = adapted_voltage_v(used_ah, current_a, filtered_current_a);
    }
}

}  // namespace core
}  // namespace battsim
