#include "core/estimate/power_time_solver.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void PowerTimeSolver::start(float soc_from, float capacity_ah, float resistance_ohm, float power_w,
                            float min_voltage_v, int steps, float weak_cell_share, float weak_cell_ratio) {
    weak_share_ = weak_cell_ratio > 0.05f && weak_cell_ratio < 1.0f ? clampf(weak_cell_share, 0.0f, 1.0f) : 0.0f;
    weak_ratio_ = weak_share_ > 0.0f ? weak_cell_ratio : 1.0f;
    soc_from_ = clampf(soc_from, 0.0f, 1.0f);
    capacity_ah_ = maxf(capacity_ah, 1.0e-3f);
    resistance_ohm_ = maxf(resistance_ohm, 0.0f);
    power_w_ = maxf(power_w, 1.0e-3f);
    min_v_ = min_voltage_v;
    steps_ = steps > 1 ? steps : 2;
    step_ = 0;
    done_ = false;
    result_ = Result{};
    prev_v_ = -1.0f;
}

float PowerTimeSolver::loaded_voltage(const OcvCurve& ocv, float soc, float& current_a, bool& feasible) const {
    float e = ocv.voltage_v(soc);
    if (weak_share_ > 0.0f) {
        const float weak_soc = 1.0f - (1.0f - soc) / weak_ratio_;
        float weak_v = ocv.voltage_v(weak_soc);
        if (weak_soc < 0.0f) weak_v += ocv.slope_v_per_soc(0.0f) * weak_soc;
        e = (1.0f - weak_share_) * e + weak_share_ * weak_v;
    }
    const float disc = e * e - 4.0f * resistance_ohm_ * power_w_;
    feasible = disc >= 0.0f && e > 0.0f;
    if (!feasible) {
        current_a = e > 0.0f && resistance_ohm_ > 0.0f ? e / (2.0f * resistance_ohm_) : 0.0f;
        return 0.5f * e;
    }
    // The smaller root: the operating point on the stable side of maximum power.
    current_a = resistance_ohm_ > 1.0e-9f ? (e - sqrtf(disc)) / (2.0f * resistance_ohm_) : power_w_ / e;
    return e - resistance_ohm_ * current_a;
}

bool PowerTimeSolver::advance(const OcvCurve& ocv, int max_steps) {
    if (done_) return true;
    const float dsoc = soc_from_ / static_cast<float>(steps_);
    for (int n = 0; n < max_steps && !done_; ++n) {
        bool feasible = true;
        float i_a = 0.0f;
        if (prev_v_ < 0.0f) {  // the starting point
            prev_v_ = loaded_voltage(ocv, soc_from_, prev_i_, feasible);
            if (!feasible || prev_v_ <= min_v_) {
                result_.cutoff = true;
                done_ = true;
                break;
            }
        }
        const float soc = soc_from_ - dsoc * static_cast<float>(step_ + 1);
        const float v = loaded_voltage(ocv, soc, i_a, feasible);
        float fraction = 1.0f;
        bool stop = false;
        if (!feasible || v <= min_v_) {
            // Linear interpolation to where the loaded voltage crosses the minimum.
            fraction = feasible && prev_v_ > v ? clampf((prev_v_ - min_v_) / (prev_v_ - v), 0.0f, 1.0f) : 0.0f;
            stop = true;
        }
        const float dq_ah = dsoc * capacity_ah_ * fraction;
        const float i_end = feasible ? i_a : prev_i_;  // where the power can no longer be met, the last current it was
        const float i_mean = 0.5f * (prev_i_ + i_end);
        if (i_mean > 0.0f) {
            const float dt_s = dq_ah * 3600.0f / i_mean;
            result_.time_s += dt_s;
            result_.charge_ah += dq_ah;
            result_.energy_wh += power_w_ * dt_s / 3600.0f;
        }
        prev_v_ = v;
        prev_i_ = i_a;
        ++step_;
        if (stop) {
            // Past the crossing the voltage is below the minimum, and a delay of seconds
            // moves little charge: the power (and the current at the crossing) held.
            result_.cutoff = true;
            result_.time_s += cutoff_delay_s_;
            result_.energy_wh += power_w_ * cutoff_delay_s_ / 3600.0f;
            result_.charge_ah += i_end * cutoff_delay_s_ / 3600.0f;
        }
        if (stop || step_ >= steps_) done_ = true;
    }
    return done_;
}

}  // namespace core
}  // namespace battsim
