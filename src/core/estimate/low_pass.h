// First-order low-pass with a time constant: alpha = dt/tau, clamped to 1, so a long
// gap between samples simply takes the new value instead of overshooting.
#pragma once
#include "core/numeric.h"

namespace battsim {
namespace core {

class LowPassFilter {
public:
    struct Config {
        float time_constant_s = 30.0f;
    };

    void configure(const Config& config) { config_ = config; }
    void reset(float value) {
        value_ = value;
        initialised_ = true;
    }
    // The first update after construction takes the input as it is.
    float update(float input, float dt_s) {
        if (!initialised_) {
            reset(input);
            return value_;
        }
        const float alpha = config_.time_constant_s > 0.0f ? clampf(dt_s / config_.time_constant_s, 0.0f, 1.0f) : 1.0f;
        value_ += alpha * (input - value_);
        return value_;
    }
    float value() const { return value_; }
    bool initialised() const { return initialised_; }

private:
    Config config_;
    float value_ = 0.0f;
    bool initialised_ = false;
};

}  // namespace core
}  // namespace battsim
