#include "host/sim/profile.h"

#include <cmath>

#include "host/sim/det_math.h"

namespace battsim {
namespace host {
namespace sim {

const char* to_string(FlightKind k) { return k == FlightKind::Hover ? "hover" : "racing"; }

Timeline make_timeline(const ProfileParams& p) {
    Timeline t;
    t.takeoff_s = p.idle_before_s + p.armed_s;
    t.planned_landing_s = t.takeoff_s + p.flight_s;
    t.log_end_s = t.planned_landing_s + p.idle_after_s;
    return t;
}

FlightPower::FlightPower(const ProfileParams& params, uint64_t seed) : p_(params), rng_(seed) {
    if (p_.kind != FlightKind::Racing) return;
    // The course: one lap of throttle segments, normalised to a time-weighted mean of 1.
    lap_count_ = p_.lap_segments < 1 ? 1 : (p_.lap_segments > kMaxSegments ? kMaxSegments : p_.lap_segments);
    double weighted = 0.0, total = 0.0;
    for (int i = 0; i < lap_count_; ++i) {
        double level = det_exp(p_.level_sd * rng_.normal() - 0.5 * p_.level_sd * p_.level_sd);
        if (level > p_.level_max_ratio) level = p_.level_max_ratio;
        lap_level_[i] = level;
        lap_duration_s_[i] = rng_.uniform(p_.min_segment_s, p_.max_segment_s);
        weighted += level * lap_duration_s_[i];
        total += lap_duration_s_[i];
    }
    const double mean = weighted / total;
    for (int i = 0; i < lap_count_; ++i) lap_level_[i] /= mean;
}

void FlightPower::new_segment() {
    segment_ = (segment_ + 1) % lap_count_;
    const double j = p_.lap_jitter;
    target_w_ = p_.mean_power_w * lap_level_[segment_] * rng_.uniform(1.0 - j, 1.0 + j);
    segment_left_s_ += lap_duration_s_[segment_] * rng_.uniform(1.0 - 1.5 * j, 1.0 + 1.5 * j);
}

double FlightPower::next(double dt_s) {
    if (!started_) {
        started_ = true;
        actual_w_ = 0.0;
        target_w_ = p_.kind == FlightKind::Racing ? 2.0 * p_.mean_power_w : 1.4 * p_.mean_power_w;
        segment_left_s_ = p_.takeoff_boost_s;
    }
    elapsed_s_ += dt_s;
    if (p_.kind == FlightKind::Racing) {
        segment_left_s_ -= dt_s;
        while (segment_left_s_ <= 0.0) new_segment();
    } else {
        segment_left_s_ -= dt_s;
        // Gusts change slowly: update the random walk every 0.1 s.
        gust_clock_s_ += dt_s;
        while (gust_clock_s_ >= 0.1) {
            gust_clock_s_ -= 0.1;
            const double a = 0.1 / p_.gust_time_s;
            gust_ += -a * gust_ + p_.gust_sd * std::sqrt(2.0 * a) * rng_.normal();
        }
        const double base = segment_left_s_ > 0.0 ? 1.4 * p_.mean_power_w : p_.mean_power_w;
        target_w_ = base * (1.0 + gust_);
    }
    if (dt_s != alpha_dt_s_) {
        alpha_ = p_.response_s > 0.0 ? 1.0 - det_exp(-dt_s / p_.response_s) : 1.0;
        alpha_dt_s_ = dt_s;
    }
    actual_w_ += alpha_ * (target_w_ - actual_w_);
    return actual_w_ > 0.0 ? actual_w_ : 0.0;
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
