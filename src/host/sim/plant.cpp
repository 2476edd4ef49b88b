#include "host/sim/plant.h"

#include <cmath>

#include "host/sim/det_math.h"

namespace battsim {
namespace host {
namespace sim {

namespace {
constexpr double kGasConstant = 8.314462618;  // J/(mol·K)
constexpr double kKelvin = 273.15;
}  // namespace

void Plant::configure(const PlantParams& params, double initial_soc, double initial_temperature_c) {
    params_ = params;
    state_ = PlantState{};
    for (int c = 0; c < params_.cells; ++c) state_.soc[c] = initial_soc;
    state_.temperature_c = initial_temperature_c;
    decay_dt_s_ = -1.0;
}

double Plant::temperature_factor_at(double temperature_c) const {
    const double t = temperature_c + kKelvin;
    const double tref = params_.reference_temperature_c + kKelvin;
    return det_exp(params_.activation_energy_j_per_mol / kGasConstant * (1.0 / t - 1.0 / tref));
}

double Plant::temperature_factor() const { return temperature_factor_at(state_.temperature_c); }

double Plant::cell_r0(int c, double temp_factor) const {
    const double soc = state_.soc[c] > 0.0 ? state_.soc[c] : 0.0;
    const double rise = params_.low_soc_resistance_rise * det_exp(-soc / params_.low_soc_resistance_scale);
    return params_.cell[c].r0_ohm * temp_factor * (1.0 + rise);
}

double Plant::pack_r0_ohm() const {
    const double f = temperature_factor();
    double r = 0.0;
    for (int c = 0; c < params_.cells; ++c) r += cell_r0(c, f);
    return r;
}

double Plant::pack_r0_reference_ohm() const {
    double r = 0.0;
    const double rise = params_.low_soc_resistance_rise * det_exp(-1.0 / params_.low_soc_resistance_scale);
    for (int c = 0; c < params_.cells; ++c) r += params_.cell[c].r0_ohm * (1.0 + rise);
    return r;
}

double Plant::min_soc() const {
    double m = state_.soc[0];
    for (int c = 1; c < params_.cells; ++c) m = state_.soc[c] < m ? state_.soc[c] : m;
    return m;
}

void Plant::refresh_decay(double dt_s) {
    if (dt_s == decay_dt_s_) return;
    for (int c = 0; c < params_.cells; ++c) {
        decay1_[c] = det_exp(-dt_s / params_.cell[c].tau1_s);
        decay2_[c] = det_exp(-dt_s / params_.cell[c].tau2_s);
    }
    decay_dt_s_ = dt_s;
}

PlantOutput Plant::evaluate_current(double current_a) const {
    PlantOutput out;
    const double f = temperature_factor();
    out.current_a = current_a;
    for (int c = 0; c < params_.cells; ++c) {
        const double v = params_.ocv->voltage_v(state_.soc[c]) - state_.v1_v[c] - state_.v2_v[c] - current_a * cell_r0(c, f);
        out.cell_v[c] = v;
        out.voltage_v += v;
    }
    out.power_w = out.voltage_v * current_a;
    return out;
}

PlantOutput Plant::step_power(double power_w, double dt_s, bool airborne) {
    const double f = temperature_factor();
    double e = 0.0, r = 0.0;
    double ocv[kMaxCells], r0[kMaxCells];
    for (int c = 0; c < params_.cells; ++c) {
        ocv[c] = params_.ocv->voltage_v(state_.soc[c]);
        r0[c] = cell_r0(c, f);
        e += ocv[c] - state_.v1_v[c] - state_.v2_v[c];
        r += r0[c];
    }
    PlantOutput out;
    // P = (E − R·I)·I: the smaller root is the stable operating point. Written as
    // 2P/(E + √(E² − 4RP)) to avoid cancellation at small power.
    double current = 0.0;
    const double disc = e * e - 4.0 * r * power_w;
    if (e <= 0.0) {
        out.brownout = power_w > 0.0;
    } else if (disc < 0.0) {
        out.brownout = true;
        current = e / (2.0 * r);  // the most power the pack can give
    } else {
        current = 2.0 * power_w / (e + std::sqrt(disc));
    }
    out.current_a = current;
    for (int c = 0; c < params_.cells; ++c) {
        out.cell_v[c] = ocv[c] - state_.v1_v[c] - state_.v2_v[c] - current * r0[c];
        out.voltage_v += out.cell_v[c];
    }
    out.power_w = out.voltage_v * current;

    // Advance: charge exactly (current held over the step), RC branches by their exact
    // exponential response, temperature by one Euler step (its time constant is minutes).
    refresh_decay(dt_s);
    double heat_w = 0.0;
    for (int c = 0; c < params_.cells; ++c) {
        const CellParams& p = params_.cell[c];
        const double r1 = p.r1_ohm * f, r2 = p.r2_ohm * f;
        heat_w += current * current * r0[c];
        if (r1 > 0.0) heat_w += state_.v1_v[c] * state_.v1_v[c] / r1;
        if (r2 > 0.0) heat_w += state_.v2_v[c] * state_.v2_v[c] / r2;
        state_.soc[c] -= current * dt_s / (3600.0 * p.capacity_ah);
        state_.v1_v[c] = state_.v1_v[c] * decay1_[c] + current * r1 * (1.0 - decay1_[c]);
        state_.v2_v[c] = state_.v2_v[c] * decay2_[c] + current * r2 * (1.0 - decay2_[c]);
    }
    const double g = airborne ? params_.conductance_flight_w_per_k : params_.conductance_ground_w_per_k;
    state_.temperature_c += dt_s * (heat_w - g * (state_.temperature_c - params_.ambient_c)) / params_.heat_capacity_j_per_k;
    state_.charge_ah += current * dt_s / 3600.0;
    state_.energy_wh += out.power_w * dt_s / 3600.0;
    state_.heat_j += heat_w * dt_s;
    return out;
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
