#include "core/model/extensions/extended_model.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

namespace {
constexpr float kKelvinOffset = 273.15f;
// Arrhenius factors are kept within this range so a wild temperature reading or a bad
// fit cannot make the resistance vanish or explode.
constexpr float kMinFactor = 0.01f;
constexpr float kMaxFactor = 100.0f;
// Below this current the hysteresis holds its state (no direction to move towards).
constexpr float kHysteresisMinCurrentA = 1.0e-3f;
constexpr float kMinTimeConstantS = 1.0e-3f;
}  // namespace

bool extensions_active(const ModelExtensions& e) {
    return e.rc_count > 0 || e.temperature.enabled || e.thermal.enabled || e.hysteresis.magnitude_v != 0.0f ||
           e.ocv.count >= 2 || e.current_sensor.gain != 1.0f || e.current_sensor.offset_a != 0.0f ||
           e.current_sensor.lead_s != 0.0f;
}

void ExtendedModel::configure(const TremblayParams& params, const ModelExtensions& extensions) {
    base_.configure(params);
    ext_ = extensions;
    // Guards that keep a bad configuration from producing NaN.
    if (ext_.rc_count > kMaxRcBranches) ext_.rc_count = kMaxRcBranches;
    for (int k = 0; k < kMaxRcBranches; ++k) {
        if (!(ext_.rc[k].time_constant_s > kMinTimeConstantS)) ext_.rc[k].time_constant_s = kMinTimeConstantS;
        if (!finitef(ext_.rc[k].resistance_ohm)) ext_.rc[k].resistance_ohm = 0.0f;
    }
    if (ext_.ocv.count == 1 || ext_.ocv.count > kMaxOcvPoints) ext_.ocv.count = 0;
    if (!(ext_.ocv.span_ah > 0.0f)) ext_.ocv.count = 0;
    if (!(ext_.thermal.time_constant_s > kMinTimeConstantS)) ext_.thermal.time_constant_s = kMinTimeConstantS;
    if (!(ext_.hysteresis.rate_per_ah >= 0.0f)) ext_.hysteresis.rate_per_ah = 0.0f;
    active_ = extensions_active(ext_);
    reset();
}

void ExtendedModel::reset() {
    status_ = Status{};
    status_.temperature_c = ext_.thermal.enabled ? ext_.thermal.ambient_c : ext_.temperature.reference_c;
    status_.temperature_measured = false;
    have_current_ = false;
    previous_current_a_ = 0.0f;
    current_slope_a_per_s_ = 0.0f;
    apply_temperature(status_.temperature_c);
}

void ExtendedModel::apply_temperature(float temperature_c) {
    const TemperatureDependence& t = ext_.temperature;
    if (!t.enabled) {
        e0_v_ = base_.e0_v();
        r_ohm_ = base_.resistance_ohm();
        k_v_ = base_.k_v();
        q_ah_ = base_.capacity_ah();
        polarisation_factor_ = 1.0f;
    } else {
        const float inverse = 1.0f / (temperature_c + kKelvinOffset) - 1.0f / (t.reference_c + kKelvinOffset);
        const float f_r = clampf(expf(t.resistance_activation_k * inverse), kMinFactor, kMaxFactor);
        const float f_k = clampf(expf(t.polarisation_activation_k * inverse), kMinFactor, kMaxFactor);
        const float delta_c = temperature_c - t.reference_c;
        r_ohm_ = base_.resistance_ohm() * f_r;
        k_v_ = base_.k_v() * f_k;
        polarisation_factor_ = f_k;
        // Capacity never below 5 % of its reference value: the Q/(Q − it) pole must stay ahead.
        q_ah_ = maxf(base_.capacity_ah() + t.capacity_ah_per_c * delta_c, 0.05f * base_.capacity_ah());
        e0_v_ = base_.e0_v() + t.e0_v_per_c * delta_c;
    }
    status_.resistance_ohm = r_ohm_;
    status_.capacity_ah = q_ah_;
}

void ExtendedModel::update(float current_a, float dt_s, bool has_temperature, float temperature_c) {
    if (!finitef(current_a)) return;
    if (!(dt_s > 0.0f)) dt_s = 0.0f;
    current_slope_a_per_s_ = (have_current_ && dt_s > 0.0f) ? (current_a - previous_current_a_) / dt_s : 0.0f;
    previous_current_a_ = current_a;
    have_current_ = true;

    float heat_w = current_a * current_a * r_ohm_;
    for (int k = 0; k < ext_.rc_count; ++k) heat_w += current_a * status_.rc_voltage_v[k];
    status_.heat_w = heat_w;
    if (has_temperature && finitef(temperature_c)) {
        status_.temperature_c = temperature_c;
        status_.temperature_measured = true;
    } else if (ext_.thermal.enabled) {
        const LumpedThermal& th = ext_.thermal;
        const float alpha = 1.0f - expf(-dt_s / th.time_constant_s);
        const float target_c = th.ambient_c + th.thermal_resistance_k_per_w * heat_w;
        status_.temperature_c += alpha * (target_c - status_.temperature_c);
        status_.temperature_measured = false;
    }
    if (ext_.temperature.enabled) apply_temperature(status_.temperature_c);

    // Exact discretisation for a current held over the step (as the counter assumes).
    for (int k = 0; k < ext_.rc_count; ++k) {
        const RcBranch& b = ext_.rc[k];
        const float decay = expf(-dt_s / b.time_constant_s);
        status_.rc_voltage_v[k] =
            decay * status_.rc_voltage_v[k] + (1.0f - decay) * b.resistance_ohm * polarisation_factor_ * current_a;
    }
    const Hysteresis& h = ext_.hysteresis;
    if (h.magnitude_v != 0.0f && fabsf(current_a) > kHysteresisMinCurrentA) {
        const float target_v = current_a > 0.0f ? -h.magnitude_v : h.magnitude_v;
        const float alpha = 1.0f - expf(-h.rate_per_ah * fabsf(current_a) * dt_s * (1.0f / 3600.0f));
        status_.hysteresis_v += alpha * (target_v - status_.hysteresis_v);
    }
}

float ExtendedModel::ocv_correction_v(float used_ah) const {
    const OcvCorrection& c = ext_.ocv;
    const int last = c.count - 1;
    const float x = clampf(used_ah / c.span_ah, 0.0f, 1.0f) * static_cast<float>(last);
    int j = static_cast<int>(x);
    if (j >= last) j = last - 1;
    const float frac = x - static_cast<float>(j);
    return c.delta_v[j] + frac * (c.delta_v[j + 1] - c.delta_v[j]);
}

float ExtendedModel::voltage_v(float used_ah, float current_a, float filtered_current_a) const {
    float current_eff_a = current_a;
    if (ext_.current_sensor.lead_s != 0.0f) current_eff_a += ext_.current_sensor.lead_s * current_slope_a_per_s_;
    // The base formula (see tremblay.h) with the temperature-adjusted E0, R, K and Q (the
    // base model's own when the temperature dependence is off: the same float operations).
    const float q = q_ah_;
    const float it = clampf(used_ah, 0.0f, q * (1.0f - TremblayModel::kMinRemainingFraction));
    const float polarisation = k_v_ * (q / (q - it));
    float v = e0_v_ - r_ohm_ * current_eff_a - polarisation * filtered_current_a - polarisation * it +
              base_.a_v() * expf(-base_.b_per_ah() * it);
    for (int k = 0; k < ext_.rc_count; ++k) v -= status_.rc_voltage_v[k];
    if (ext_.hysteresis.magnitude_v != 0.0f) v += status_.hysteresis_v;
    if (ext_.ocv.count >= 2) v += ocv_correction_v(used_ah);
    return v;
}

float ExtendedModel::used_ah_at_voltage(float voltage_v, float current_a) const {
    return invert_falling([&](float used_ah) { return this->voltage_v(used_ah, current_a, current_a); }, 0.0f,
                          q_ah_ * (1.0f - TremblayModel::kMinRemainingFraction), voltage_v);
}

}  // namespace core
}  // namespace battsim
