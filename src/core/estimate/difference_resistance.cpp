#include "core/estimate/difference_resistance.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void DifferenceResistanceEstimator::configure(const Config& config) {
    config_ = config;
    status_ = Status{};
    status_.resistance_ohm = status_.resistance_now_ohm = config.initial_resistance_ohm;
    head_ = 0;
    count_ = 0;
    sxx_ = sxy_ = syy_ = n_ = 0.0f;
    sxxt_ = sxxtt_ = sxyt_ = 0.0f;
    last_us_ = 0;
}

void DifferenceResistanceEstimator::update(uint64_t time_us, float voltage_v, float current_a) {
    const float dt_s = count_ > 0 && time_us > last_us_ ? static_cast<float>(time_us - last_us_) * 1.0e-6f : 0.0f;
    last_us_ = time_us;
    // Through 32 bits (lags are at most 60 s): a float to 64-bit conversion is a library call
    // that works in double on some targets (libgcc's on ARM), per update.
    const uint64_t lag_us = static_cast<uint32_t>(config_.lag_s * 1.0e6f);
    // Newest sample at least `lag` old; a gap much longer than the lag breaks the pair.
    const int pick = pick_lagged(t_us_, head_, count_, kHistory, time_us, lag_us);
    t_us_[head_] = time_us;
    voltage_v_[head_] = voltage_v;
    current_a_[head_] = current_a;
    head_ = (head_ + 1) % kHistory;
    if (count_ < kHistory) ++count_;

    // Forget by elapsed time, so irregular sample rates weigh time, not sample counts.
    const float keep = config_.memory_s > 0.0f ? clampf(1.0f - dt_s / config_.memory_s, 0.0f, 1.0f) : 0.0f;
    sxx_ *= keep;
    sxy_ *= keep;
    syy_ *= keep;
    n_ *= keep;
    if (config_.trend_sigma_per_s > 0.0f) {
        // Every pair ages by dt: τ → τ − dt.
        sxxtt_ = keep * (sxxtt_ - 2.0f * dt_s * sxxt_) + dt_s * dt_s * sxx_;
        sxxt_ = keep * sxxt_ - dt_s * sxx_;
        sxyt_ = keep * sxyt_ - dt_s * sxy_;
    }
    if (pick < 0) return;
    const float di = current_a - current_a_[pick];
    const float dv = voltage_v - voltage_v_[pick];
    if (fabsf(di) < config_.min_step_a) return;
    // A garbled reading, not the pack: a heavy pair that shows far less sag than the pack's
    // resistance (one 100 A read with no sag, weighted by ΔI², had pulled R0 to a sixth; one
    // 200 A read in a racing window, to 0.6; one 1 s after a take-off, the first fifth's R0
    // to a quarter). While the fit stands (the window holds its bar and three pairs), heavy is
    // a pair that would outweigh the whole window or a hundred of its mean pairs (a step ten
    // times its RMS step), and "far less" under half the window's R. Before, heavy is a pair
    // that alone would fill the window, and far less under 0.15 of the configured R. A skipped
    // pair adds nothing, so a window that forgets falls back to the configured R; and the test
    // is one-sided: a pack above its rating, or a wrong first estimate, is never locked out.
    const float di2 = di * di;
    const bool judged = sxx_ >= config_.min_excitation_a2 && n_ >= 3.0f;  // as the fit below counts
    const bool heavy = judged ? di2 * maxf(n_, 100.0f) > 100.0f * sxx_ : di2 >= config_.min_excitation_a2;
    const float sag_floor_ohm = judged ? 0.5f * status_.resistance_ohm : 0.15f * config_.initial_resistance_ohm;
    if (heavy && -dv * di < sag_floor_ohm * di2) return;
    sxx_ += di * di;
    sxy_ += di * dv;
    syy_ += dv * dv;
    n_ += 1.0f;
    if (sxx_ < config_.min_excitation_a2 || n_ < 3.0f) return;
    const float r = -sxy_ / sxx_;
    if (!(r > 0.0f) || !finitef(r)) return;
    // Residual variance of ΔV about −R·ΔI over the weighted points, then var(R) = s²/Σx².
    const float rss = maxf(0.0f, syy_ - sxy_ * sxy_ / sxx_);
    const float s2 = rss / maxf(1.0f, n_ - 1.0f);
    status_.resistance_ohm = r;
    status_.sigma_ohm = sqrtf(s2 / sxx_);
    status_.resistance_now_ohm = status_.resistance_ohm;
    status_.sigma_now_ohm = status_.sigma_ohm;
    if (config_.trend_sigma_per_s > 0.0f) {
        // −ΔV = (R_now + S·τ)·ΔI, with S ~ N(0, (σ·R)²): a ridge of s²/(σ·R)² on S.
        const float sigma_s = config_.trend_sigma_per_s * r;
        const float a11 = sxx_, a12 = sxxt_, a22 = sxxtt_ + s2 / maxf(sigma_s * sigma_s, 1.0e-30f);
        const float det = a11 * a22 - a12 * a12;
        if (det > 0.0f && finitef(det)) {
            const float r_now = (-sxy_ * a22 + sxyt_ * a12) / det;
            if (r_now > 0.0f && finitef(r_now)) {
                status_.resistance_now_ohm = r_now;
                status_.sigma_now_ohm = sqrtf(s2 * a22 / det);
            }
        }
    }
    status_.valid = true;
}

}  // namespace core
}  // namespace battsim
