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
        // A pack warming in flight loses resistance steadily, and the forgetting window's
        // average lags it. With this > 0 a second fit carries a linear trend and gives its
        // value now (`resistance_now_ohm`); the trend's prior σ is this fraction of R per
        // second. 0 = no trend (the "now" value is the window's).
        float trend_sigma_per_s = 0.0f;
    };
    struct Status {
        float resistance_ohm = 0.0f;  // the forgetting window's mean
        float sigma_ohm = 0.0f;       // standard error of the estimate
        float resistance_now_ohm = 0.0f;  // with the trend carried to now (see Config)
        float sigma_now_ohm = 0.0f;
        bool valid = false;
    };

    // Samples kept for the lagged difference: a lag longer than kHistory − 1 sample
    // intervals is never reached, so a log sampled faster gives no pairs.
    static constexpr int kHistory = 16;

    void configure(const Config& config);
    void update(uint64_t time_us, float voltage_v, float current_a);
    // Drops the history (after a gap or a sensor fault) without forgetting the estimate.
    void break_history() { count_ = 0; }
    const Status& status() const { return status_; }

private:
    Config config_;
    Status status_;
    uint64_t t_us_[kHistory] = {};
    float voltage_v_[kHistory] = {};
    float current_a_[kHistory] = {};
    int head_ = 0;
    int count_ = 0;
    float sxx_ = 0.0f, sxy_ = 0.0f, syy_ = 0.0f, n_ = 0.0f;
    // The same sums weighted by each pair's age τ = t_pair − t_now (s, ≤ 0), for the trend.
    float sxxt_ = 0.0f, sxxtt_ = 0.0f, sxyt_ = 0.0f;
    uint64_t last_us_ = 0;
};

}  // namespace core
}  // namespace battsim
