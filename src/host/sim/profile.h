// Power demand of one flight at the pack terminals: ground idle (electronics only), a
// few seconds armed, the flight, then idle again after landing. The in-flight demand is
// a seeded random process (racing: bursts, cruise and throttle cuts; hover: steady with
// slow gusts) that can run on past the planned landing, which is how the truth learns
// when the pack would have reached its cutoff.
#pragma once
#include <cstdint>

#include "host/sim/rng.h"

namespace battsim {
namespace host {
namespace sim {

enum class FlightKind { Racing, Hover };
const char* to_string(FlightKind k);

struct ProfileParams {
    FlightKind kind = FlightKind::Racing;
    double idle_before_s = 60.0;   // on the ground, powered, not armed
    double armed_s = 3.0;          // motors spinning at idle before take-off
    double flight_s = 200.0;       // planned flight; ends earlier if the pack reaches cutoff
    double idle_after_s = 15.0;    // on the ground after landing, until the log ends
    double idle_power_w = 5.0;
    double armed_power_w = 15.0;
    double mean_power_w = 360.0;   // the flight's long-run average demand
    // Racing: laps of a fixed course. One lap is a sequence of throttle segments whose
    // levels are log-normal multiples of the mean (so most of the time below it, with
    // bursts to a few times it), normalised so the lap averages the mean; every lap
    // repeats it with a little jitter in level and duration.
    int lap_segments = 14;
    double level_sd = 0.5;         // of log(level)
    double level_max_ratio = 3.0;  // bursts capped at this multiple of the mean
    double min_segment_s = 0.3;
    double max_segment_s = 2.0;
    double lap_jitter = 0.1;       // level × U(1 ± jitter), duration × U(1 ± 1.5·jitter)
    double takeoff_boost_s = 2.0;  // punch-out after take-off at 2 × the mean
    // Hover: slow gusts as a mean-reverting random walk (relative standard deviation).
    double gust_sd = 0.05;
    double gust_time_s = 4.0;
    double response_s = 0.08;      // motors and ESC: first-order lag of the power
};

// The in-flight demand, advanced step by step. Copyable: a copy taken at landing
// continues exactly as the flight would have.
class FlightPower {
public:
    FlightPower() = default;
    FlightPower(const ProfileParams& params, uint64_t seed);
    // Advances by dt_s and returns the demand over that step.
    double next(double dt_s);

private:
    void new_segment();

    static constexpr int kMaxSegments = 64;
    ProfileParams p_;
    Rng rng_;
    double lap_level_[kMaxSegments] = {};
    double lap_duration_s_[kMaxSegments] = {};
    int lap_count_ = 0;
    int segment_ = -1;
    double elapsed_s_ = 0.0;
    double segment_left_s_ = 0.0;
    double target_w_ = 0.0;
    double actual_w_ = 0.0;
    double gust_ = 0.0;
    double gust_clock_s_ = 0.0;
    double alpha_ = 1.0;
    double alpha_dt_s_ = -1.0;
    bool started_ = false;
};

// Whole-log phases in plant time (seconds since power-on).
struct Timeline {
    double takeoff_s = 0.0;
    double planned_landing_s = 0.0;
    double log_end_s = 0.0;  // planned; moves earlier when the pack hits cutoff in flight
};
Timeline make_timeline(const ProfileParams& p);

}  // namespace sim
}  // namespace host
}  // namespace battsim
