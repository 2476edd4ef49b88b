// Tremblay–Dessaint (2009) Li-ion discharge model:
//   V = E0 − R·i − K·Q/(Q−it)·i* − K·Q/(Q−it)·it + A·exp(−B·it)
// with i the current (A, positive = discharge), i* the low-pass-filtered current and
// it the charge drawn (Ah). The parameters come from points read off a constant-current
// discharge curve; this class derives A, B, E0 and K from them and evaluates the model.
#pragma once

namespace battsim {
namespace core {

struct TremblayParams {
    float full_voltage_v = 16.8f;           // voltage of the full pack on the curve
    float exponential_voltage_v = 15.26f;   // end of the exponential zone
    float exponential_capacity_ah = 0.3f;
    float nominal_zone_voltage_v = 14.75f;  // end of the nominal zone (kept for the record and scaling)
    float nominal_zone_capacity_ah = 1.5f;
    float capacity_ah = 1.55f;              // maximum capacity Q
    float internal_resistance_ohm = 0.02f;
    float curve_current_a = 7.0f;           // current of the discharge the points were read from
};

class TremblayModel {
public:
    // it is kept below Q·(1 − kMinRemainingFraction): the Q/(Q−it) term then stays below
    // 1000 and the voltage stays finite however far the charge count runs.
    static constexpr float kMinRemainingFraction = 1.0e-3f;

    void configure(const TremblayParams& params);

    // Model terminal voltage. used_ah is clamped to [0, Q·(1 − kMinRemainingFraction)],
    // so the result is always finite and falls monotonically as used_ah grows.
    float voltage_v(float used_ah, float current_a, float filtered_current_a) const;

    // Scales Q and the exponential- and nominal-zone capacities by the same ratio.
    void set_capacity_ah(float capacity_ah);
    // Re-derives E0 (and K) for a new internal resistance: E0 moves by ΔR × the curve
    // current (the reference monitor's behaviour), or, with keep_e0, the curve points move
    // instead so that the open-circuit voltage stays.
    void set_resistance_ohm(float resistance_ohm, bool keep_e0 = false);

    // Charge drawn at which the model, at a steady current, gives `voltage_v`
    // (bisection; the model is monotonic in it). Clamped to the model's range.
    float used_ah_at_voltage(float voltage_v, float current_a) const;
    // Energy delivered from full down to `used_ah` at a steady current (closed form of
    // the integral of voltage_v over it), in Wh.
    float energy_wh_to(float used_ah, float current_a) const;

    const TremblayParams& params() const { return params_; }
    float capacity_ah() const { return params_.capacity_ah; }
    float resistance_ohm() const { return params_.internal_resistance_ohm; }
    float a_v() const { return a_v_; }
    float b_per_ah() const { return b_per_ah_; }
    float e0_v() const { return e0_v_; }
    float k_v() const { return k_v_; }
    float max_used_ah() const { return params_.capacity_ah * (1.0f - kMinRemainingFraction); }

private:
    void derive();

    TremblayParams params_;
    float a_v_ = 0.0f;
    float b_per_ah_ = 0.0f;
    float e0_v_ = 0.0f;
    float k_v_ = 0.0f;
};

}  // namespace core
}  // namespace battsim
