// The unit tests' equivalent-circuit plant (OCV table, series resistance, one RC branch):
// not the Tremblay model the reference monitor runs, so estimators cannot win by sharing
// the plant's equations. Deterministic noise, the same on every platform.
#pragma once
#include <cmath>
#include <cstdint>

#include "core/model/ocv.h"

namespace testplant {

// Per-cell LiPo-like OCV at SOC 0, 0.1, …, 1.
inline battsim::core::OcvTable lipo_table() {
    battsim::core::OcvTable t;
    const float v[11] = {3.30f, 3.60f, 3.68f, 3.73f, 3.77f, 3.81f, 3.86f, 3.92f, 3.99f, 4.07f, 4.17f};
    t.points = 11;
    for (int k = 0; k < 11; ++k) t.cell_voltage_v[k] = v[k];
    return t;
}

// Pseudo-noise in [−1, 1] (no library RNG).
struct Lcg {
    uint32_t s = 12345u;
    float next() {
        s = s * 1664525u + 1013904223u;
        return static_cast<float>(s >> 8) / 8388608.0f - 1.0f;
    }
};

struct Plant {
    battsim::core::OcvCurve ocv;
    float capacity_ah, r0_ohm, r1_ohm, tau_s;
    float soc = 1.0f, v1 = 0.0f;
    float step(float current_a, float dt_s) {
        soc -= current_a * dt_s / (3600.0f * capacity_ah);
        v1 += (current_a * r1_ohm - v1) * (1.0f - std::exp(-dt_s / tau_s));
        return ocv.voltage_v(soc) - r0_ohm * current_a - v1;
    }
};

}  // namespace testplant
