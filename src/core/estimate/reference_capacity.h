// The reference in-flight capacity estimator (the source dissertation's method): a
// fixed model with the configured parameters and an adapted copy. When the adapted
// model misses the measured voltage by more than the allowed variance, it first takes
// the online resistance estimate; if it still misses for `persistence_updates` updates
// in a row, its capacity moves one step towards the measurement.
#pragma once
#include "core/model/tremblay.h"

namespace battsim {
namespace core {

class ReferenceCapacityEstimator {
public:
    struct Config {
        float max_voltage_variance_v = 0.2f;
        float capacity_step_fraction = 0.01f;  // of the configured capacity
        int persistence_updates = 5;
        float min_capacity_fraction = 0.2f;    // bounds on the estimate, of the configured capacity
        float max_capacity_fraction = 3.0f;
        // Adopting a resistance keeps the model's E0 (see TremblayModel::set_resistance_ohm);
        // off = the dissertation's behaviour, on for fitted models with a large curve current.
        bool resistance_keeps_e0 = false;
    };
    struct Status {
        float capacity_ah = 0.0f;
        float resistance_ohm = 0.0f;          // resistance the adapted model uses
        float fixed_model_voltage_v = 0.0f;
        float adapted_model_voltage_v = 0.0f;
        int capacity_steps = 0;               // net steps taken (+ up, − down)
    };

    void configure(const Config& config, const TremblayParams& params);
    // used_ah: charge drawn since full; resistance_ohm: the online estimate (≤ 0 = none yet).
    // extension_v: what the configured model extensions add to the plain model's voltage
    // (RC branches, temperature, ...); both models carry it, so only the capacity and the
    // resistance are adapted.
    void update(float used_ah, float current_a, float filtered_current_a, float measured_v, float resistance_ohm,
                float extension_v = 0.0f);
    // Model outputs without adapting (used while not flying).
    void evaluate(float used_ah, float current_a, float filtered_current_a, float extension_v = 0.0f);
    // The fixed model only (the adapted output then mirrors it).
    void evaluate_fixed(float used_ah, float current_a, float filtered_current_a, float extension_v = 0.0f);

    const Status& status() const { return status_; }
    const TremblayModel& fixed_model() const { return fixed_; }
    const TremblayModel& adapted_model() const { return adapted_; }

private:
    float adapted_voltage_v(float used_ah, float current_a, float filtered_current_a) const {
        return adapted_.voltage_v(used_ah, current_a, filtered_current_a) + extension_v_;
    }
    Config config_;
    Status status_;
    TremblayModel fixed_;
    TremblayModel adapted_;
    float rated_capacity_ah_ = 0.0f;
    int beyond_count_ = 0;
    float extension_v_ = 0.0f;
};

}  // namespace core
}  // namespace battsim
