// Swapped shunt sense wires turn a flying drone's current negative, so the monitor never sees
// a take-off and reads the pack as resting for the whole flight. A drone carries no charger
// and an ESC's braking feeds back for moments only: a current held below minus the take-off
// current for kHoldUs is the wiring (or an offset as large). Latched for the boot; the
// firmware's OLED and `status`, and the MAVLink text, each keep one of these: the MAVLink
// output can be switched off or have no port, and the OLED must see it still (one comparison
// a sample each).
#pragma once
#include <stdint.h>

namespace battsim {
namespace telemetry {

class ReversedCurrentCheck {
public:
    static constexpr uint64_t kHoldUs = 2000000;  // longer than any ESC's braking

    void configure(float min_flying_current_a) {
        min_flying_current_a_ = min_flying_current_a;
        run_ = false;
        reversed_ = false;
    }
    // One sample's current; returns reversed().
    bool update(uint64_t time_us, float current_a) {
        if (!(current_a <= -min_flying_current_a_)) {
            run_ = false;
            return reversed_;
        }
        if (!run_) {
            run_ = true;
            since_us_ = time_us;
        }
        if (time_us - since_us_ >= kHoldUs) reversed_ = true;
        return reversed_;
    }
    bool reversed() const { return reversed_; }

private:
    float min_flying_current_a_ = 1.0f;
    bool run_ = false;        // the current is below minus the take-off current...
    uint64_t since_us_ = 0;   // ... since this sample
    bool reversed_ = false;
};

}  // namespace telemetry
}  // namespace battsim
