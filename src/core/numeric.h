// Small numeric helpers for the core: float only, no heap, no exceptions.
#pragma once
#include <math.h>

namespace battsim {
namespace core {

inline float clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }
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

}  // namespace core
}  // namespace battsim
