// A small stand-alone generator of flight-like logs for the fit and residual tests: the
// plain Tremblay model (core::TremblayModel with the monitor's 30 s filtered current) plus,
// when asked, effects the config does not declare: one RC branch, a current-sensor gain or
// offset, measurement noise and 10 mV quantisation. Written independently of the extension
// code under test, so a test cannot pass by sharing its bugs.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/estimate/low_pass.h"
#include "core/model/tremblay.h"
#include "test_files.h"

namespace synth {

struct Options {
    battsim::core::TremblayParams params;  // the "true" pack
    double rc_resistance_ohm = 0;          // undeclared RC branch (0 = none)
    double rc_time_constant_s = 5;
    double sensor_gain = 1;                // logged current = gain · true + offset
    double sensor_offset_a = 0;
    double noise_v = 0;                    // Gaussian, before quantisation
    double quantum_v = 0.01;               // 0 = none
    double rest_s = 20, flight_s = 240, after_s = 30;
    double dt_s = 0.1;
    double min_a = 5, max_a = 45;          // flight current levels
    uint32_t seed = 1;
};

// Deterministic PRNG (xorshift32) so the logs are the same on every platform.
class Rng {
public:
    explicit Rng(uint32_t seed) : s_(seed ? seed : 1) {}
    double uniform() {
        s_ ^= s_ << 13;
        s_ ^= s_ >> 17;
        s_ ^= s_ << 5;
        return (s_ + 0.5) / 4294967296.0;
    }
    double normal() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(6.283185307179586 * uniform()); }

private:
    uint32_t s_;
};

// Writes time_s,voltage_v,current_a (positive = discharge) and returns the path.
inline std::string write_log(const std::string& name, const Options& o) {
    static const std::string dir = testsupport::scratch_dir("fit");
    const std::string path = dir + "/" + name + ".csv";
    std::ofstream out(path);
    out << "time_s,voltage_v,current_a\n";
    battsim::core::TremblayModel model;
    model.configure(o.params);
    battsim::core::LowPassFilter filter;
    filter.configure(battsim::core::LowPassFilter::Config{30.0f});
    Rng rng(o.seed);
    double used_ah = 0, rc_v = 0, level = 0.3, hold = 0;
    const double total = o.rest_s + o.flight_s + o.after_s;
    char line[128];
    for (long k = 0;; ++k) {
        const double t = k * o.dt_s;
        if (t > total + 1e-9) break;
        double current = 0.3;  // idle
        if (t >= o.rest_s && t < o.rest_s + o.flight_s) {
            if (hold <= 0) {
                level = o.min_a + (o.max_a - o.min_a) * rng.uniform();
                hold = 0.5 + 3.5 * rng.uniform();
            }
            hold -= o.dt_s;
            current = level;
        }
        const double dt = k == 0 ? 0.0 : o.dt_s;
        used_ah += current * dt / 3600.0;
        const float filtered = filter.update(static_cast<float>(current), static_cast<float>(dt));
        const double decay = std::exp(-dt / o.rc_time_constant_s);
        rc_v = decay * rc_v + (1 - decay) * o.rc_resistance_ohm * current;
        double v = model.voltage_v(static_cast<float>(used_ah), static_cast<float>(current), filtered) - rc_v;
        v += o.noise_v * rng.normal();
        if (o.quantum_v > 0) v = std::round(v / o.quantum_v) * o.quantum_v;
        const double logged = o.sensor_gain * current + o.sensor_offset_a;
        std::snprintf(line, sizeof line, "%.3f,%.4f,%.4f\n", t, v, logged);
        out << line;
    }
    return path;
}

}  // namespace synth
