// Small numeric helpers for the core: float only, no heap, no exceptions.
#pragma once
#include <math.h>
#include <stdint.h>

namespace battsim {
namespace core {

// NaN gives lo: a NaN state must not become an index (a table lookup casts the result).
inline float clampf(float x, float lo, float hi) { return x > lo ? (x < hi ? x : hi) : lo; }
inline float minf(float a, float b) { return a < b ? a : b; }
inline float maxf(float a, float b) { return a > b ? a : b; }
inline bool finitef(float x) { return isfinite(x) != 0; }

// Kahan-compensated running sum: a float accumulator that keeps milliamp-hour
// resolution over hours of 15 Hz samples (a plain float sum loses ~3 % of each step
// once the total passes 1000 mAh).
class CompensatedSum {
public:
    void reset(float value) { sum_ = value; carry_ = 0.0f; }
    void add(float x) {
        const float y = x - carry_;
        const float t = sum_ + y;
        carry_ = (t - sum_) - y;
        sum_ = t;
    }
    float value() const { return sum_; }

private:
    float sum_ = 0.0f;
    float carry_ = 0.0f;
};

// The oldest pair a lag of `lag_us` accepts: further apart, a logging gap (or a log written
// once a second) would pair two samples between which the polarisation moved.
inline uint64_t max_pair_span_us(uint64_t lag_us) { return 3 * lag_us + 200000u; }

// Index in a ring of time stamps (newest at head − 1) of the newest entry at least
// `lag_us` older than `now_us`; −1 if there is none or it is more than max_pair_span_us
// old. Shared by the difference-based resistance estimators.
inline int pick_lagged(const uint64_t* t_us, int head, int count, int capacity, uint64_t now_us, uint64_t lag_us) {
    for (int n = 0; n < count; ++n) {
        const int k = (head - 1 - n + capacity) % capacity;
        if (now_us >= t_us[k] + lag_us) return now_us - t_us[k] <= max_pair_span_us(lag_us) ? k : -1;
    }
    return -1;
}

// The x in [lo, hi] where a non-increasing voltage curve v(x) crosses `target_v`, by
// bisection (the ends when the target lies outside). 32 halvings resolve the range well
// below float resolution. Inverts the models for the charge drawn at a rested voltage.
template <typename VoltageOf>
float invert_falling(VoltageOf&& v, float lo, float hi, float target_v) {
    if (v(lo) <= target_v) return lo;
    if (v(hi) >= target_v) return hi;
    for (int n = 0; n < 32; ++n) {
        const float mid = 0.5f * (lo + hi);
        if (v(mid) > target_v) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return 0.5f * (lo + hi);
}

}  // namespace core
}  // namespace battsim
