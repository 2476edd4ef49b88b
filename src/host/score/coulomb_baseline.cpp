#include "host/score/coulomb_baseline.h"

namespace battsim {
namespace host {
namespace score {

void CoulombBaseline::configure(const Config& config) {
    config_ = config;
    status_ = Status{};
    consumed_mah_.reset(0.0f);
    started_ = false;
    status_.remaining_mah = config_.rated_capacity_ah * config_.usable_fraction * 1000.0f;
}

void CoulombBaseline::update(float current_a, float dt_s) {
    if (!core::finitef(current_a) || !core::finitef(dt_s) || dt_s < 0.0f) return;
    consumed_mah_.add(current_a * dt_s * (1000.0f / 3600.0f));
    if (!started_) {
        status_.average_current_a = current_a;  // the first sample seeds the average
        started_ = true;
    } else {
        const float alpha = config_.average_time_s > 0.0f ? core::clampf(dt_s / config_.average_time_s, 0.0f, 1.0f) : 1.0f;
        status_.average_current_a += alpha * (current_a - status_.average_current_a);
    }
    const float usable_mah = config_.rated_capacity_ah * config_.usable_fraction * 1000.0f;
    status_.consumed_mah = consumed_mah_.value();
    status_.remaining_mah = core::maxf(usable_mah - status_.consumed_mah, 0.0f);
    status_.soc = config_.rated_capacity_ah > 0.0f ? status_.remaining_mah / (config_.rated_capacity_ah * 1000.0f) : 0.0f;
    status_.time_valid = status_.average_current_a >= config_.min_average_current_a;
    status_.remaining_time_s =
        status_.time_valid ? status_.remaining_mah * 3.6f / status_.average_current_a : 0.0f;
}

}  // namespace score
}  // namespace host
}  // namespace battsim
