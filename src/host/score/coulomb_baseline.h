// The baseline most flight controllers give today (ArduPilot and PX4 style): count the
// charge drawn from a pack assumed full at connection, take the rated capacity as what
// there is, and divide what is left by a 50 s average of the current. No model, no
// resistance, no health warnings: the floor any better estimator has to clear.
// A ruler's comparator like the oracle, so it lives with the scoreboard: the monitor never
// runs it, and the firmware's flash does not carry it. Written to the core's rules all the
// same (float, no heap), as a flight controller would run it.
#pragma once
#include "core/numeric.h"

namespace battsim {
namespace host {
namespace score {

class CoulombBaseline {
public:
    struct Config {
        float rated_capacity_ah = 1.55f;
        float usable_fraction = 1.0f;      // of the rated capacity counted as usable
        float average_time_s = 50.0f;      // time constant of the current average
        float min_average_current_a = 0.1f;  // below this no remaining time is given
    };
    struct Status {
        float consumed_mah = 0.0f;
        float remaining_mah = 0.0f;
        float average_current_a = 0.0f;
        float remaining_time_s = 0.0f;
        float soc = 1.0f;  // remaining / rated
        bool time_valid = false;
    };

    void configure(const Config& config);
    void update(float current_a, float dt_s);
    const Status& status() const { return status_; }

private:
    Config config_;
    Status status_;
    core::CompensatedSum consumed_mah_;
    bool started_ = false;
};

}  // namespace score
}  // namespace host
}  // namespace battsim
