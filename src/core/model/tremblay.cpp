#include "core/model/tremblay.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

namespace {
// Guards that keep a bad configuration from producing NaN: capacities are kept positive
// and the exponential zone inside the capacity.
constexpr float kMinCapacityAh = 1.0e-3f;
}  // namespace

void TremblayModel::configure(const TremblayParams& params) {
    params_ = params;
    derive();
}

void TremblayModel::derive() {
    TremblayParams& p = params_;
    if (!(p.capacity_ah > kMinCapacityAh)) p.capacity_ah = kMinCapacityAh;
    if (!(p.exponential_capacity_ah > 0.0f)) p.exponential_capacity_ah = p.capacity_ah * 0.01f;
    if (p.exponential_capacity_ah >= p.capacity_ah) p.exponential_capacity_ah = p.capacity_ah * 0.99f;
    if (!(p.internal_resistance_ohm >= 0.0f)) p.internal_resistance_ohm = 0.0f;
    if (!(p.curve_current_a >= 0.0f)) p.curve_current_a = 0.0f;

    const float q = p.capacity_ah;
    const float q_exp = p.exponential_capacity_ah;
    const float i = p.curve_current_a;
    a_v_ = p.full_voltage_v - p.exponential_voltage_v;
    b_per_ah_ = 3.0f / q_exp;  // the exponential term has decayed to e^-3 at the zone's end
    e0_v_ = p.full_voltage_v + p.internal_resistance_ohm * i - a_v_;
    // K from the exponential-zone point: V(Qexp) = Vexp at the curve current (i = i*).
    k_v_ = ((q - q_exp) * (e0_v_ - p.internal_resistance_ohm * i + a_v_ * expf(-b_per_ah_ * q_exp) -
                           p.exponential_voltage_v)) /
           (q * (q_exp + i));
}

float TremblayModel::voltage_v(float used_ah, float current_a, float filtered_current_a) const {
    const float q = params_.capacity_ah;
    const float it = clampf(used_ah, 0.0f, max_used_ah());
    const float polarisation = k_v_ * (q / (q - it));
    return e0_v_ - params_.internal_resistance_ohm * current_a - polarisation * filtered_current_a -
           polarisation * it + a_v_ * expf(-b_per_ah_ * it);
}

void TremblayModel::set_capacity_ah(float capacity_ah) {
    if (!(capacity_ah > kMinCapacityAh)) capacity_ah = kMinCapacityAh;
    const float ratio = capacity_ah / params_.capacity_ah;
    params_.capacity_ah = capacity_ah;
    params_.exponential_capacity_ah *= ratio;
    params_.nominal_zone_capacity_ah *= ratio;
    derive();
}

void TremblayModel::set_resistance_ohm(float resistance_ohm, bool keep_e0) {
    if (keep_e0) {
        // E0 = V_exp + R·i of the curve points: to keep the open-circuit voltage, the points
        // (measured at the curve current) move by −ΔR·i. With a fitted large curve current
        // the re-derived E0 would otherwise move by volts.
        const float r_ohm = resistance_ohm >= 0.0f ? resistance_ohm : 0.0f;
        const float shift_v = (r_ohm - params_.internal_resistance_ohm) * params_.curve_current_a;
        params_.full_voltage_v -= shift_v;
        params_.exponential_voltage_v -= shift_v;
        params_.nominal_zone_voltage_v -= shift_v;
    }
    params_.internal_resistance_ohm = resistance_ohm;
    derive();
}

float TremblayModel::used_ah_at_voltage(float voltage_v, float current_a) const {
    return invert_falling([&](float used_ah) { return this->voltage_v(used_ah, current_a, current_a); }, 0.0f,
                          max_used_ah(), voltage_v);
}

float TremblayModel::energy_wh_to(float used_ah, float current_a) const {
    // ∫0^x V ds with i = i* = current:
    //   (E0 − R·i)·x − K·Q·[(Q + i)·ln(Q/(Q − x)) − x] + (A/B)·(1 − e^(−B·x))
    const float q = params_.capacity_ah;
    const float x = clampf(used_ah, 0.0f, max_used_ah());
    const float linear = (e0_v_ - params_.internal_resistance_ohm * current_a) * x;
    const float polarisation = k_v_ * q * ((q + current_a) * logf(q / (q - x)) - x);
    const float exponential = (a_v_ / b_per_ah_) * (1.0f - expf(-b_per_ah_ * x));
    return linear - polarisation + exponential;
}

}  // namespace core
}  // namespace battsim
