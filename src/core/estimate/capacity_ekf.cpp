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
    x_[0] = clampf(soc, 0.0f, 1.05f);
    x_[1] = rated_ah_;
    x_[2] = config_.polarisation_initial_ohm;
    x_[3] = 0.0f;
    for (int r = 0; r < kN; ++r)
        for (int c = 0; c < kN; ++c) p_[r][c] = 0.0f;
    p_[0][0] = config_.soc_sigma0 * config_.soc_sigma0;
    const float sq = config_.capacity_sigma0_fraction * rated_ah_;
    p_[1][1] = sq * sq;
    p_[2][2] = config_.polarisation_sigma0_ohm * config_.polarisation_sigma0_ohm;
    p_[3][3] = config_.offset_sigma0_a * config_.offset_sigma0_a;
    status_.rejected = 0;
    status_.innovation_v = 0.0f;
    publish();
}

void CapacityEkf::predict(float current_a, float dt_s, bool ground, float ground_process_scale, float extra_soc_var) {
    if (!(dt_s > 0.0f)) return;
    const float q = x_[1];
    const float k = dt_s / (3600.0f * q);
    const float dsoc = (current_a - x_[3]) * k;
    x_[0] -= dsoc;
    // F = I except row 0: ∂soc/∂q = dsoc/q, ∂soc/∂b = +dt/(3600·q).
    const float f[kN] = {1.0f, ground ? 0.0f : dsoc / q, 0.0f, k};
    // P ← F P Fᵀ: only row and column 0 change.
    float row[kN];
    for (int c = 0; c < kN; ++c) row[c] = f[0] * p_[0][c] + f[1] * p_[1][c] + f[3] * p_[3][c];
    const float p00 = row[0] * f[0] + row[1] * f[1] + row[3] * f[3];
    p_[0][0] = p00;
    for (int c = 1; c < kN; ++c) p_[0][c] = p_[c][0] = row[c];
    const float qs = config_.soc_process_per_sqrt_s * (ground ? ground_process_scale : 1.0f);
    const float qc = config_.capacity_process_fraction_per_sqrt_s * rated_ah_;
    const float qp = config_.polarisation_process_ohm_per_sqrt_s;
    const float qb = config_.offset_process_a_per_sqrt_s;
    p_[0][0] += qs * qs * dt_s + extra_soc_var;
    p_[1][1] += qc * qc * dt_s;
    p_[2][2] += qp * qp * dt_s;
    p_[3][3] += qb * qb * dt_s;
    x_[0] = clampf(x_[0], -0.05f, 1.05f);
    publish();
}

namespace {
// The OCV curve and its slope, continued linearly past both ends: a pack charged slightly
// above the table's top must still show its voltage falling as charge is drawn.
float ocv_extended(const OcvCurve& ocv, float soc, float& slope) {
    if (soc > 1.0f) {
        slope = ocv.slope_v_per_soc(1.0f);
        return ocv.voltage_v(1.0f) + slope * (soc - 1.0f);
    }
    if (soc < 0.0f) {
        slope = ocv.slope_v_per_soc(0.0f);
        return ocv.voltage_v(0.0f) + slope * soc;
    }
    slope = ocv.slope_v_per_soc(soc);
    return ocv.voltage_v(soc);
}
}  // namespace

float CapacityEkf::soc_at_rest_voltage(const OcvCurve& ocv, float voltage_v) {
    float slope = 0.0f;
    const float top = ocv_extended(ocv, 1.0f, slope);
    if (voltage_v > top && slope > 0.0f) return minf(1.05f, 1.0f + (voltage_v - top) / slope);
    return ocv.soc_at_voltage(voltage_v);
}

void CapacityEkf::correct(float y_v, float ip_a, float extra_var_v2, const OcvCurve& ocv,
                          bool learn_parameters, bool learn_offset, float polarisation_scale) {
    float h_soc = 0.0f;
    const float ocv_v = ocv_extended(ocv, x_[0], h_soc);
    status_.ocv_slope_v_per_soc = h_soc;
    // The polarisation voltage is Rp·scale·(i_p − b): the scale rides on the current, so
    // the state stays in ohms at the rated resistance and H keeps its form.
    const float ip_true = (ip_a - x_[3]) * (polarisation_scale > 0.0f ? polarisation_scale : 1.0f);
    // y = V + R0·(I_m − b) = OCV(soc) − Rp·(i_p − b). The offset's direct effect on y
    // (R0·b + Rp·b, tens of mV) is left out of H: it would be read off the OCV table's own
    // error at a single instant. The offset is learnt through the state of charge alone.
    // Held parameters are left out of H as well: as "consider" states the polarisation's
    // wide prior would act as an unknown voltage bias on the ground and mask the offset.
    const float hx[kN] = {h_soc, 0.0f, learn_parameters ? -ip_true : 0.0f, 0.0f};
    const float predicted = ocv_v - x_[2] * ip_true;
    const float nu = y_v - predicted;
    status_.innovation_v = nu;
    status_.soc_gain_per_v = 0.0f;

    float ph[kN];  // P·Hᵀ
    for (int r = 0; r < kN; ++r) ph[r] = p_[r][0] * hx[0] + p_[r][2] * hx[2];
    const float table_v = h_soc * config_.ocv_soc_sigma;
    const float rv = config_.voltage_sigma_v * config_.voltage_sigma_v + table_v * table_v + maxf(0.0f, extra_var_v2);
    const float s = hx[0] * ph[0] + hx[2] * ph[2] + rv;
    if (!(s > 0.0f) || !finitef(nu)) return;
    if (nu * nu > config_.gate_sigmas * config_.gate_sigmas * s) {
        ++status_.rejected;  // a glitch, not information
        return;
    }
    float k[kN];
    for (int r = 0; r < kN; ++r) k[r] = ph[r] / s;
    if (!learn_parameters) k[1] = k[2] = 0.0f;  // the Joseph update below stays valid for any gain
    if (!learn_offset) k[3] = 0.0f;
    for (int r = 0; r < kN; ++r) x_[r] += k[r] * nu;
    status_.soc_gain_per_v = k[0];

    // Joseph form: P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ keeps P symmetric and positive.
    // With A = I − K H: A P = P − K (H P), and (A P) Aᵀ = A P − (A P H) Kᵀ.
    float ap[kN][kN];
    for (int r = 0; r < kN; ++r)
        for (int c = 0; c < kN; ++c) ap[r][c] = p_[r][c] - k[r] * ph[c];
    float aph[kN];
    for (int r = 0; r < kN; ++r) aph[r] = ap[r][0] * hx[0] + ap[r][2] * hx[2];
    for (int r = 0; r < kN; ++r)
        for (int c = r; c < kN; ++c) {
            const float v = ap[r][c] - aph[r] * k[c] + k[r] * rv * k[c];
            p_[r][c] = v;
            p_[c][r] = v;
        }

    x_[0] = clampf(x_[0], -0.05f, 1.05f);
    x_[1] = clampf(x_[1], config_.min_capacity_fraction * rated_ah_, config_.max_capacity_fraction * rated_ah_);
    x_[2] = clampf(x_[2], 0.0f, 1.0f);
    publish();
}

void CapacityEkf::shift_soc(float dsoc) {
    x_[0] = clampf(x_[0] + dsoc, -0.05f, 1.05f);
    publish();
}

void CapacityEkf::publish() {
    status_.soc = x_[0];
    status_.capacity_ah = x_[1];
    status_.polarisation_ohm = x_[2];
    status_.offset_a = x_[3];
    status_.sigma_soc = sqrtf(maxf(0.0f, p_[0][0]));
    status_.sigma_capacity_ah = sqrtf(maxf(0.0f, p_[1][1]));
    status_.sigma_polarisation_ohm = sqrtf(maxf(0.0f, p_[2][2]));
    status_.sigma_offset_a = sqrtf(maxf(0.0f, p_[3][3]));
}

}  // namespace core
}  // namespace battsim
