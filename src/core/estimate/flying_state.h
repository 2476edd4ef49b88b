// Flying when the current reaches the minimum flying current; landed again only after
// it has stayed below that for the hold time (throttle dips in flight do not count).
#pragma once
#include <stdint.h>

namespace battsim {
namespace core {

class FlyingState {
public:
    struct Config {
        float min_flying_current_a = 1.0f;
        float landed_hold_s = 1.0f;
        // Current must hold at or above the threshold this long before the flight starts;
        // 0 = at once. Arming blips on the bench last a few samples.
        float takeoff_confirm_s = 0.0f;
    };

    void configure(const Config& config) {
        config_ = config;
        flying_ = false;
        below_s_ = 0.0f;
        above_s_ = 0.0f;
    }
    bool update(float current_a, float dt_s) {
        if (current_a >= config_.min_flying_current_a) {
            above_s_ = was_above_ ? above_s_ + dt_s : 0.0f;
            was_above_ = true;
            if (above_s_ + 1.0e-4f >= config_.takeoff_confirm_s) flying_ = true;
            below_s_ = 0.0f;
            return flying_;
        }
        was_above_ = false;
        above_s_ = 0.0f;
        if (flying_) {
            below_s_ += dt_s;
            if (below_s_ > config_.landed_hold_s + 1.0e-4f) flying_ = false;  // slack as in InitialState
        }
        return flying_;
    }
    bool flying() const { return flying_; }

private:
    Config config_;
    bool flying_ = false;
    float below_s_ = 0.0f;
    float above_s_ = 0.0f;
    bool was_above_ = false;
};

}  // namespace core
}  // namespace battsim
