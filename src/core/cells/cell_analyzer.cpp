#include "core/cells/cell_analyzer.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void CellAnalyzer::reset() {
    status_ = Status{};
    head_ = count_ = 0;
    sxx_ = n_r_ = n_ = sq_ = sqq_ = 0.0f;
    for (int c = 0; c < kMaxCells; ++c) sxy_[c] = syy_[c] = sd_[c] = sqd_[c] = sdd_[c] = 0.0f;
}

namespace {
// Median of up to kMaxCells values, skipping index `skip` (insertion sort on a copy).
float median_excluding(const float* x, int n, int skip, int also_skip) {
    float a[kMaxCells];
    int m = 0;
    for (int k = 0; k < n; ++k)
        if (k != skip && k != also_skip) a[m++] = x[k];
    for (int k = 1; k < m; ++k) {
        const float v = a[k];
        int j = k - 1;
        while (j >= 0 && a[j] > v) {
            a[j + 1] = a[j];
            --j;
        }
        a[j + 1] = v;
    }
    if (m == 0) return 0.0f;
    return m % 2 ? a[m / 2] : 0.5f * (a[m / 2 - 1] + a[m / 2]);
}
}  // namespace

void CellAnalyzer::update(uint64_t time_us, const float* cell_v, int cells, float current_a, float charge_ah,
                          float pack_ocv_slope_v_per_soc, float capacity_ah) {
    if (cells < 3 || cells > kMaxCells) return;  // a median needs at least two others
    if (status_.cell_count != cells) {
        reset();
        status_.cell_count = static_cast<uint8_t>(cells);
    }
    // Resistance: pair with the newest sample at least `lag` old.
    const uint64_t lag_us = static_cast<uint64_t>(config_.lag_s * 1.0e6f);
    const int pick = pick_lagged(t_us_, head_, count_, kHistory, time_us, lag_us);
    if (pick >= 0) {
        const float di = current_a - i_[pick];
        if (fabsf(di) >= config_.min_step_a) {
            sxx_ += di * di;
            n_r_ += 1.0f;
            for (int c = 0; c < cells; ++c) {
                const float dv = cell_v[c] - v_[pick][c];
                sxy_[c] += di * dv;
                syy_[c] += dv * dv;
            }
        }
    }
    t_us_[head_] = time_us;
    i_[head_] = current_a;
    for (int c = 0; c < cells; ++c) v_[head_][c] = cell_v[c];
    head_ = (head_ + 1) % kHistory;
    if (count_ < kHistory) ++count_;

    const bool r_ready = sxx_ >= config_.min_excitation_a2 && n_r_ >= config_.min_pairs;
    float sigma_r[kMaxCells] = {};
    if (r_ready) {
        for (int c = 0; c < cells; ++c) {
            status_.resistance_ohm[c] = -sxy_[c] / sxx_;
            const float rss = maxf(0.0f, syy_[c] - sxy_[c] * sxy_[c] / sxx_);
            sigma_r[c] = sqrtf(rss / maxf(1.0f, n_r_ - 1.0f) / sxx_);
        }
    }

    // Drift of each cell's compensated voltage from the cells' mean, against charge drawn.
    if (r_ready) {
        float comp[kMaxCells];
        float mean = 0.0f;
        for (int c = 0; c < cells; ++c) {
            comp[c] = cell_v[c] + status_.resistance_ohm[c] * current_a;
            mean += comp[c];
        }
        mean /= static_cast<float>(cells);
        n_ += 1.0f;
        sq_ += charge_ah;
        sqq_ += charge_ah * charge_ah;
        for (int c = 0; c < cells; ++c) {
            const float d = comp[c] - mean;
            sd_[c] += d;
            sqd_[c] += charge_ah * d;
            sdd_[c] += d * d;
        }
    }

    // Verdicts.
    status_.flagged_cell = -1;
    status_.finding = kNone;
    float worst = 0.0f;
    const int lead_cell = config_.last_cell_includes_lead ? cells - 1 : -1;
    // A resistance verdict needs at least two other cells to take a median of: against a
    // single other cell, ordinary cell-to-cell spread reads as an outlier.
    const int compared = cells - 1 - (lead_cell >= 0 ? 1 : 0);
    if (r_ready && compared >= 2) {
        for (int c = 0; c < cells; ++c) {
            if (c == lead_cell) continue;
            const float med = median_excluding(status_.resistance_ohm, cells, c, lead_cell);
            if (!(med > 0.0f)) continue;
            const float excess = status_.resistance_ohm[c] / med - 1.0f;
            if (excess > config_.resistance_ratio - 1.0f &&
                status_.resistance_ohm[c] - med > config_.significance_sigmas * sigma_r[c] && excess > worst) {
                worst = excess;
                status_.flagged_cell = static_cast<int8_t>(c);
                status_.finding = kHighResistance;
            }
        }
    }
    const float var_q = n_ > 1.0f ? sqq_ / n_ - (sq_ / n_) * (sq_ / n_) : 0.0f;
    const float span_ah = sqrtf(maxf(0.0f, var_q)) * 3.4641f;  // a uniform spread's full width
    const float cell_slope = maxf(pack_ocv_slope_v_per_soc / static_cast<float>(cells), config_.min_cell_ocv_slope_v);
    if (span_ah >= config_.min_charge_ah && cell_slope > 0.0f && capacity_ah > 0.0f) {
        for (int c = 0; c < cells; ++c) {
            const float cov = sqd_[c] / n_ - (sq_ / n_) * (sd_[c] / n_);
            const float slope = cov / var_q;  // V per Ah, negative = falling behind
            const float var_d = maxf(0.0f, sdd_[c] / n_ - (sd_[c] / n_) * (sd_[c] / n_) - slope * cov);
            // Samples are strongly correlated; count one independent point per 10.
            const float se = sqrtf(var_d / maxf(1.0f, n_ / 10.0f - 2.0f) / var_q);
            // A cell with a fraction f less capacity drops f·OCV' per unit of pack SOC faster.
            // (Measured against the mean of all cells, itself included: × N/(N−1).)
            const float deficit = -slope * capacity_ah / cell_slope * static_cast<float>(cells) /
                                  static_cast<float>(cells - 1);
            status_.capacity_deficit[c] = deficit;
            if (c == lead_cell) continue;
            if (deficit > config_.capacity_deficit && -slope > config_.significance_sigmas * se &&
                deficit > worst) {
                worst = deficit;
                status_.flagged_cell = static_cast<int8_t>(c);
                status_.finding = kLowCapacity;
            }
        }
    }
}

}  // namespace core
}  // namespace battsim
