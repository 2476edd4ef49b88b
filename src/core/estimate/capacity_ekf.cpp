#include "core/estimate/capacity_ekf.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void CapacityEkf::configure(const Config& config, float rated_capacity_ah) {
    config_ = config;
    rated_ah_ = rated_capacity_ah > 0.0f ? rated_capacity_ah : 1.0f;
    start(1.0f);
}

void CapacityEkf::start(float soc) {
    x_[0] = clampf(soc, 0.0f, 1.0f);
    x_[1] = rated_ah_;
    x_[2] = config_.polarisation_initial_ohm;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) p_[r][c] = 0.0f;
    p_[0][0] = config_.soc_sigma0 * config_.soc_sigma0;
    const float sq = config_.capacity_sigma0_fraction * rated_ah_;
    p_[1][1] = sq * sq;
    p_[2][2] = config_.polarisation_sigma0_ohm * config_.polarisation_sigma0_ohm;
    status_.rejected = 0;
    status_.innovation_v = 0.0f;
    publish();
}

void CapacityEkf::predict(float current_a, float dt_s) {
    if (!(dt_s > 0.0f)) return;
    const float q = x_[1];
    const float dsoc = current_a * dt_s / (3600.0f * q);
    x_[0] -= dsoc;
    // F = I except F[0][1] = ∂soc/∂q = I·dt/(3600·q²).
    const float f01 = dsoc / q;
    // P ← F P Fᵀ, written out for the single off-diagonal term.
    const float p00 = p_[0][0] + 2.0f * f01 * p_[0][1] + f01 * f01 * p_[1][1];
    const float p01 = p_[0][1] + f01 * p_[1][1];
    const float p02 = p_[0][2] + f01 * p_[1][2];
    p_[0][0] = p00;
    p_[0][1] = p_[1][0] = p01;
    p_[0][2] = p_[2][0] = p02;
    const float qs = config_.soc_process_per_sqrt_s;
    const float qc = config_.capacity_process_fraction_per_sqrt_s * rated_ah_;
    const float qp = config_.polarisation_process_ohm_per_sqrt_s;
    p_[0][0] += qs * qs * dt_s;
    p_[1][1] += qc * qc * dt_s;
    p_[2][2] += qp * qp * dt_s;
    x_[0] = clampf(x_[0], -0.05f, 1.05f);
    publish();
}

void CapacityEkf::correct(float y_v, float ip_a, float extra_var_v2, const OcvCurve& ocv, bool learn_parameters) {
    const float h_soc = ocv.slope_v_per_soc(x_[0]);
    const float hx[3] = {h_soc, 0.0f, -ip_a};
    const float predicted = ocv.voltage_v(x_[0]) - x_[2] * ip_a;
    const float nu = y_v - predicted;
    status_.innovation_v = nu;

    float ph[3];  // P·Hᵀ
    for (int r = 0; r < 3; ++r) ph[r] = p_[r][0] * hx[0] + p_[r][1] * hx[1] + p_[r][2] * hx[2];
    const float rv = config_.voltage_sigma_v * config_.voltage_sigma_v + maxf(0.0f, extra_var_v2);
    const float s = hx[0] * ph[0] + hx[1] * ph[1] + hx[2] * ph[2] + rv;
    if (!(s > 0.0f) || !finitef(nu)) return;
    if (nu * nu > config_.gate_sigmas * config_.gate_sigmas * s) {
        ++status_.rejected;  // a glitch, not information
        return;
    }
    float k[3];
    for (int r = 0; r < 3; ++r) k[r] = ph[r] / s;
    if (!learn_parameters) k[1] = k[2] = 0.0f;  // the Joseph update below stays valid for any gain
    for (int r = 0; r < 3; ++r) x_[r] += k[r] * nu;

    // Joseph form: P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ keeps P symmetric and positive.
    float a[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[r][c] = (r == c ? 1.0f : 0.0f) - k[r] * hx[c];
    float ap[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) ap[r][c] = a[r][0] * p_[0][c] + a[r][1] * p_[1][c] + a[r][2] * p_[2][c];
    for (int r = 0; r < 3; ++r)
        for (int c = r; c < 3; ++c) {
            const float v = ap[r][0] * a[c][0] + ap[r][1] * a[c][1] + ap[r][2] * a[c][2] + k[r] * rv * k[c];
            p_[r][c] = v;
            p_[c][r] = v;
        }

    x_[0] = clampf(x_[0], -0.05f, 1.05f);
    x_[1] = clampf(x_[1], config_.min_capacity_fraction * rated_ah_, config_.max_capacity_fraction * rated_ah_);
    x_[2] = clampf(x_[2], 0.0f, 1.0f);
    publish();
}

void CapacityEkf::publish() {
    status_.soc = x_[0];
    status_.capacity_ah = x_[1];
    status_.polarisation_ohm = x_[2];
    status_.sigma_soc = sqrtf(maxf(0.0f, p_[0][0]));
    status_.sigma_capacity_ah = sqrtf(maxf(0.0f, p_[1][1]));
    status_.sigma_polarisation_ohm = sqrtf(maxf(0.0f, p_[2][2]));
}

}  // namespace core
}  // namespace battsim
