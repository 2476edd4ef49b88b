// State of charge at connection: wait until the pack has rested (current below the
// resting limit for the stabilisation time), then read the charge already drawn off the
// model at that voltage and current, and the energy that goes with it.
#pragma once
#include "core/model/tremblay.h"

namespace battsim {
namespace core {

class InitialState {
public:
    struct Config {
        float max_resting_current_a = 1.0f;
        float stabilisation_time_s = 5.0f;
    };
    struct Status {
        bool done = false;
        bool forced = false;  // set from a loaded sample because the flight began first
        float used_ah = 0.0f;
        float used_wh = 0.0f;
        float voltage_v = 0.0f;
        float current_a = 0.0f;
    };

    void configure(const Config& config) {
        config_ = config;
        status_ = Status{};
        rested_s_ = 0.0f;
        rest_voltage_v_ = 0.0f;
    }
    // Returns true on the sample that settles the initial state.
    bool update(const TremblayModel& model, float voltage_v, float current_a, float dt_s);
    // Settle now (the flight began before the pack had rested long enough): from the last
    // sample at rest, however short the rest, else from this loaded one. A log that starts
    // at arming rests for a second or two, and its voltage then is the pack's open-circuit
    // one; a loaded sample's leaves out the polarisation (an octocopter's 1.76 Ah pack read
    // 10 % emptier from 9 A than from its 1.7 s at rest).
    void force(const TremblayModel& model, float voltage_v, float current_a);
    const Status& status() const { return status_; }

private:
    void settle(const TremblayModel& model, float voltage_v, float current_a);
    Config config_;
    Status status_;
    float rested_s_ = 0.0f;
    float rest_voltage_v_ = 0.0f;  // the last sample at rest (0 = none yet)
    float rest_current_a_ = 0.0f;
};

}  // namespace core
}  // namespace battsim
