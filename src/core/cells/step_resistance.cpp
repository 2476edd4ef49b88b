#include "core/cells/step_resistance.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void CellStepResistance::reset() {
    status_ = Status{};
    cells_ = 0;
    head_ = count_ = 0;
    sum_a_ = 0.0f;
    moving_ = false;
    waited_ = 0;
    before_ = Window{};
    sxx_ = 0.0f;
    for (int c = 0; c < kMaxCells; ++c) sxy_[c] = svar_[c] = 0.0f;
}

float CellStepResistance::band_a(float mean_a) const {
    return maxf(config_.steady_band_a, config_.steady_band_fraction * fabsf(mean_a));
}

bool CellStepResistance::ring_steady() const {
    if (count_ < kWindow) return false;
    const float mean = sum_a_ / static_cast<float>(kWindow);
    const float band = band_a(mean);
    for (int k = 0; k < kWindow; ++k)
        if (fabsf(current_a_[k] - mean) > band) return false;
    return true;
}

void CellStepResistance::summarise(Window* w) const {
    const float n = static_cast<float>(kWindow);
    float sum_a = 0.0f;
    for (int k = 0; k < kWindow; ++k) sum_a += current_a_[k];
    w->current_a = sum_a / n;
    const float floor_v2 = config_.noise_floor_v * config_.noise_floor_v;
    for (int c = 0; c < cells_; ++c) {
        float sum_v = 0.0f;
        for (int k = 0; k < kWindow; ++k) sum_v += cell_v_[k][c];
        const float mean = sum_v / n;
        float ss = 0.0f;
        for (int k = 0; k < kWindow; ++k) ss += (cell_v_[k][c] - mean) * (cell_v_[k][c] - mean);
        w->voltage_v[c] = mean;
        w->variance_v2[c] = maxf(floor_v2, ss / (n - 1.0f)) / n;
    }
}

void CellStepResistance::update(const float* cell_v, int cells, float current_a) {
    if (!(config_.min_step_a > 0.0f) || cells < 1 || cells > kMaxCells) return;
    if (cells != cells_) {
        reset();
        cells_ = cells;
    }
    // The current leaves a steady window: that window is the step's "before". (The mean
    // test first: the window's own check is the loop.)
    const float mean_a = sum_a_ / static_cast<float>(kWindow);
    if (!moving_ && count_ == kWindow && fabsf(current_a - mean_a) > band_a(mean_a) && ring_steady()) {
        summarise(&before_);
        moving_ = true;
        waited_ = 0;
        count_ = 0;
    }
    if (count_ < kWindow) {
        ++count_;
        if (count_ == 1) sum_a_ = 0.0f;
    } else {
        sum_a_ -= current_a_[head_];
    }
    sum_a_ += current_a;
    current_a_[head_] = current_a;
    for (int c = 0; c < cells; ++c) cell_v_[head_][c] = cell_v[c];
    head_ = head_ + 1 < kWindow ? head_ + 1 : 0;
    if (!moving_) return;
    ++waited_;
    // The newest sample near the mean first: a current still moving rarely passes it.
    const float settled_mean_a = sum_a_ / static_cast<float>(kWindow);
    if (count_ == kWindow && fabsf(current_a - settled_mean_a) <= band_a(settled_mean_a) && ring_steady()) {
        moving_ = false;  // settled: this window is the "after" (and the next step's "before")
        Window after;
        summarise(&after);
        const float di = after.current_a - before_.current_a;
        if (fabsf(di) < config_.min_step_a) return;
        sxx_ += di * di;
        for (int c = 0; c < cells; ++c) {
            sxy_[c] += di * (after.voltage_v[c] - before_.voltage_v[c]);
            svar_[c] += di * di * (after.variance_v2[c] + before_.variance_v2[c]);
        }
        if (status_.steps < 0xFFFFu) ++status_.steps;
        for (int c = 0; c < cells; ++c) {
            status_.resistance_ohm[c] = -sxy_[c] / sxx_;
            status_.sigma_ohm[c] = sqrtf(svar_[c]) / sxx_;
        }
    } else if (waited_ > config_.max_wait_samples) {
        moving_ = false;  // never settled: no step; the ring slides on as usual
    }
}

}  // namespace core
}  // namespace battsim
