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
    void update(float used_ah, float current_a, float filtered_current_a, float measured_v, float resistance_ohm);
    // Model outputs without adapting (used while not flying).
    void evaluate(float used_ah, float current_a, float filtered_current_a);
    // The fixed model only (the adapted output then mirrors it).
    void evaluate_fixed(float used_ah, float current_a, float filtered_current_a);

    const Status& status() const { return status_; }
    const TremblayModel& fixed_model() const { return fixed_; }
    const TremblayModel& adapted_model() const { return adapted_; }

private:
    Config config_;
    Status status_;
    TremblayModel fixed_;
    TremblayModel adapted_;
    float rated_capacity_ah_ = 0.0f;
    int beyond_count_ = 0;
};

}  // namespace core
}  // namespace battsim
