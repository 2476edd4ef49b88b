// Resistance from short-lag differences: over ~0.2 s the open-circuit voltage barely
// moves, so ΔV = −R·ΔI. An exponentially weighted least-squares fit of ΔV on ΔI (a
// recursive least squares with forgetting) gives R and its standard error. Offsets in
// the current sensor cancel in the differences. On the dissertation's flights this
// matches the charger-measured pack resistance within 12 % over the first fifth of
// every flight (see docs/estimator.md).
#pragma once
#include <stdint.h>

namespace battsim {
namespace core {

class DifferenceResistanceEstimator {
public:
    struct Config {
        float lag_s = 0.05f;            // difference lag: the previous sample (67 ms on the reference hardware)
        float memory_s = 60.0f;         // forgetting time constant
        float min_step_a = 0.5f;        // smaller current steps carry only noise
        float min_excitation_a2 = 400.0f;  // Σ weighted ΔI² before the estimate counts
        float initial_resistance_ohm = 0.02f;
    };
    struct Status {
        float resistance_ohm = 0.0f;
        float sigma_ohm = 0.0f;       // standard error of the estimate
        float excitation_a2 = 0.0f;   // Σ weighted ΔI²
        bool valid = false;
    };

    void configure(const Config& config);
    void update(uint64_t time_us, float voltage_v, float current_a);
    // Drops the history (after a gap or a sensor fault) without forgetting the estimate.
    void break_history() { count_ = 0; }
    const Status& status() const { return status_; }

private:
    static constexpr int kHistory = 16;
    Config config_;
    Status status_;
    uint64_t t_us_[kHistory] = {};
    float v_[kHistory] = {};
    float i_[kHistory] = {};
    int head_ = 0;
    int count_ = 0;
    float sxx_ = 0.0f, sxy_ = 0.0f, syy_ = 0.0f, n_ = 0.0f;
    uint64_t last_us_ = 0;
};

}  // namespace core
}  // namespace battsim
