// Remaining flight time of the reference monitor: the usable capacity is where the
// adapted model, drawing the average power's current at the minimum voltage, reaches
// the minimum flight voltage (tracked by nudging it one step per flying sample, which
// costs one model evaluation); usable energy = usable capacity × nominal voltage.
#pragma once
#include "core/model/tremblay.h"

namespace battsim {
namespace core {

class FlightTimeEstimator {
public:
    struct Config {
        float min_flight_voltage_v = 13.3f;
        float nominal_voltage_v = 14.8f;
        float step_fraction = 0.01f;
        float max_capacity_factor = 3.0f;  // bound on the usable capacity, × the model's Q
    };
    struct Status {
        float usable_capacity_ah = 0.0f;
        float usable_energy_wh = 0.0f;
        float remaining_time_s = 0.0f;
        float total_time_s = 0.0f;
        bool valid = false;  // false until an average power is known
    };

    void configure(const Config& config, float initial_capacity_ah);
    // Called every flying sample: moves the usable capacity one step.
    void track(const TremblayModel& model, float average_power_w);
    // Recomputes the times from the usable energy, the energy used and the average power.
    void compute(float used_energy_wh, float average_power_w);
    const Status& status() const { return status_; }

private:
    Config config_;
    Status status_;
};

}  // namespace core
}  // namespace battsim
