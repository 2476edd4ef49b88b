#include "core/cells/piao.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void PiaoCellScorer::reset() {
    status_ = Status{};
    for (int c = 0; c < kMaxCells; ++c) running_[c] = 0.0f;
}

void PiaoCellScorer::update(const float* v, int n) {
    if (n < 2 || n > kMaxCells) return;
    if (status_.cell_count != n) {  // a different pack layout starts afresh
        reset();
        status_.cell_count = static_cast<uint8_t>(n);
    }
    float mean = 0.0f;
    for (int c = 0; c < n; ++c) mean += v[c];
    mean /= static_cast<float>(n);
    float var = 0.0f;
    for (int c = 0; c < n; ++c) var += (v[c] - mean) * (v[c] - mean);
    const float sd = sqrtf(var / static_cast<float>(n));
    if (!(sd > config_.min_std_v)) return;

    float z[kMaxCells];
    float outlier[kMaxCells];
    for (int c = 0; c < n; ++c) z[c] = (v[c] - mean) / sd;
    float sum = 0.0f;
    int imax = 0;
    int imin = 0;
    for (int c = 0; c < n; ++c) {
        float o = 0.0f;
        for (int d = 0; d < n; ++d) o += fabsf(z[c] - z[d]);
        outlier[c] = o;
        sum += o;
        if (o > outlier[imax]) imax = c;
        if (o < outlier[imin]) imin = c;
    }
    const float range = sum / static_cast<float>(n);  // abnormality range
    if (!(outlier[imax] - outlier[imin] > range)) return;

    bool any = false;
    for (int c = 0; c < n; ++c) {
        const bool is_outlier = fabsf(outlier[c] - outlier[imax]) < fabsf(outlier[c] - outlier[imin]) || c == imax;
        if (!is_outlier) continue;
        running_[c] += z[c] < 0.0f ? -outlier[c] : outlier[c];
        any = true;
    }
    if (any) ++status_.outlier_samples;

    float total = 0.0f;
    for (int c = 0; c < n; ++c) total += fabsf(running_[c]);
    status_.worst_cell = -1;
    float worst = 0.0f;
    for (int c = 0; c < n; ++c) {
        status_.score[c] = total > 0.0f ? running_[c] / total : 0.0f;
        if (fabsf(status_.score[c]) > worst) {
            worst = fabsf(status_.score[c]);
            status_.worst_cell = static_cast<int8_t>(c);
        }
    }
}

}  // namespace core
}  // namespace battsim
