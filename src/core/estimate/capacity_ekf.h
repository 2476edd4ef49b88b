// Joint state/parameter extended Kalman filter over state of charge, capacity, a
// polarisation resistance and the current sensor's offset. The measurement is the
// resistance-compensated voltage y = V + R0·(I_m − b) (I_m the measured current, b the
// offset: true current = I_m − b), modelled as OCV(soc) − Rp·(i_p − b), where i_p is the
// measured current low-passed with the polarisation time constant. Capacity is learnt
// through the coupling between the charge counted out and the state of charge the OCV
// curve reveals; the offset through charge counted while nothing flows (a pack at rest
// whose voltage does not fall has not delivered the charge an offset sensor reports).
// Four states, written out by hand in float: no matrix library, no heap.
#pragma once
#include <stdint.h>

#include "core/model/ocv.h"

namespace battsim {
namespace core {

class CapacityEkf {
public:
    struct Config {
        float voltage_sigma_v = 0.02f;              // measurement and model error (tuned on the scenario suite)
        float soc_sigma0 = 0.03f;                   // after the initial state at rest
        float capacity_sigma0_fraction = 0.15f;     // of rated (0.25 before issue 7 part 4: it over-reacted early)
        float polarisation_initial_ohm = 0.005f;
        float polarisation_sigma0_ohm = 0.02f;
        float soc_process_per_sqrt_s = 2.0e-4f;
        float capacity_process_fraction_per_sqrt_s = 2.0e-5f;
        float polarisation_process_ohm_per_sqrt_s = 1.0e-4f;
        // The OCV table's own error, as an error in state of charge: adds (dOCV/dSOC·σ)² to
        // the measurement variance, so steep stretches (near full) do not over-drive capacity.
        float ocv_soc_sigma = 0.02f;
        float offset_sigma0_a = 1.0f;               // prior on the current sensor's offset
        float offset_process_a_per_sqrt_s = 1.0e-3f;
        float gate_sigmas = 8.0f;                   // innovations beyond this are rejected
        float min_capacity_fraction = 0.3f;
        float max_capacity_fraction = 2.0f;
    };
    struct Status {
        float soc = 1.0f;
        float capacity_ah = 0.0f;
        float polarisation_ohm = 0.0f;
        float offset_a = 0.0f;  // current sensor offset: true current = measured − offset
        float sigma_soc = 0.0f;
        float sigma_capacity_ah = 0.0f;
        float sigma_polarisation_ohm = 0.0f;
        float sigma_offset_a = 0.0f;
        float innovation_v = 0.0f;
        float ocv_slope_v_per_soc = 0.0f;  // dOCV/dSOC at the last correction's prior SOC
        float soc_gain_per_v = 0.0f;       // the last correction's state-of-charge gain (0: none made)
        uint32_t rejected = 0;
    };

    void configure(const Config& config, float rated_capacity_ah);
    void start(float soc);
    // State of charge from a resting voltage, continuing the curve's top slope above it
    // (up to 1.05).
    static float soc_at_rest_voltage(const OcvCurve& ocv, float voltage_v);
    // current_a: as measured (the offset state is subtracted here).
    // ground = true: the pack is on the ground (a small current). The state of charge's
    // process noise is scaled by ground_process_scale (the voltage is a clean OCV reading
    // there), and the capacity's uncertainty is not coupled into the state of charge: the
    // charge drawn on the ground is small once the offset is out of it, and coupling it
    // through the raw (offset) current would make the offset look unobservable.
    // extra_soc_var: variance added to the state of charge (charge counted with an error
    // of its own, as over a logging gap).
    void predict(float current_a, float dt_s, bool ground = false, float ground_process_scale = 1.0f,
                 float extra_soc_var = 0.0f);
    // y: V + R0·(I_m − offset); ip: polarisation current (measured, low-passed);
    // extra_var_v2: variance added by the R0 error. learn_parameters = false holds capacity
    // and polarisation as "consider" states (at rest nothing flows that could tell them
    // apart); learn_offset = false holds the offset likewise.
    // polarisation_scale: the polarisation state is the pack's polarisation resistance at
    // its rated ohmic resistance; the voltage sees it times this factor (the measured ohmic
    // resistance over the rated one), so the polarisation follows the pack as it warms.
    void correct(float y_v, float ip_a, float extra_var_v2, const OcvCurve& ocv,
                 bool learn_parameters = true, bool learn_offset = true, float polarisation_scale = 1.0f);
    // Moves the state of charge alone (a correction worked out outside the filter).
    void shift_soc(float dsoc);
    const Status& status() const { return status_; }

private:
    void publish();
    Config config_;
    Status status_;
    float rated_ah_ = 1.0f;
    static constexpr int kN = 4;
    float x_[kN] = {1.0f, 1.0f, 0.0f, 0.0f};  // soc, capacity_ah, polarisation_ohm, offset_a
    float p_[kN][kN] = {};
};

}  // namespace core
}  // namespace battsim
