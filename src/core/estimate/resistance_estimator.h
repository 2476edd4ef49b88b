// Online internal-resistance estimate in the style of ArduPilot's battery monitor
// (written from its published description): compare each sample against slowly
// low-passed voltage and current; a current step gives R = −ΔV/ΔI, blended in with a
// weight that grows with the size of the step, and capped by the largest sag seen
// from the highest-voltage point.
#pragma once

namespace battsim {
namespace core {

class ResistanceEstimator {
public:
    struct Config {
        float filter_time_constant_s = 0.5f;  // alpha = dt/(dt + tc)
        float max_filter_alpha = 0.5f;
        float blend_gain = 0.1f;              // weight = min(1, gain·|ΔI|/I_max)
        float initial_resistance_ohm = 0.0f;  // ArduPilot starts from zero
        float min_current_a = 1.1920929e-7f;  // "positive" current (float epsilon)
    };
    struct Status {
        float resistance_ohm = 0.0f;
        float voltage_filtered_v = 0.0f;
        float current_filtered_a = 0.0f;
        float resting_voltage_v = 0.0f;  // voltage + I·R: the pack without its sag
        unsigned long updates = 0;       // accepted positive estimates blended in
    };

    void configure(const Config& config);
    void update(float voltage_v, float current_a, float dt_s);
    const Status& status() const { return status_; }

private:
    Config config_;
    Status status_;
    float current_max_a_ = 0.0f;
    float voltage_ref_v_ = 0.0f;
    float current_ref_a_ = 0.0f;
    bool started_ = false;
};

}  // namespace core
}  // namespace battsim
