// Joint state/parameter extended Kalman filter over state of charge, capacity and a
// polarisation resistance. The measurement is the resistance-compensated voltage
// y = V + R0·I, modelled as OCV(soc) − Rp·i_p, where i_p is the current low-passed with
// the polarisation time constant. Capacity is learnt through the coupling between the
// charge counted out and the state of charge the OCV curve reveals. Three states, written
// out by hand in float: no matrix library, no heap.
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
        float capacity_sigma0_fraction = 0.25f;     // of rated
        float polarisation_initial_ohm = 0.005f;
        float polarisation_sigma0_ohm = 0.02f;
        float soc_process_per_sqrt_s = 2.0e-4f;
        float capacity_process_fraction_per_sqrt_s = 2.0e-5f;
        float polarisation_process_ohm_per_sqrt_s = 1.0e-4f;
        float gate_sigmas = 8.0f;                   // innovations beyond this are rejected
        float min_capacity_fraction = 0.3f;
        float max_capacity_fraction = 2.0f;
    };
    struct Status {
        float soc = 1.0f;
        float capacity_ah = 0.0f;
        float polarisation_ohm = 0.0f;
        float sigma_soc = 0.0f;
        float sigma_capacity_ah = 0.0f;
        float sigma_polarisation_ohm = 0.0f;
        float innovation_v = 0.0f;
        uint32_t rejected = 0;
    };

    void configure(const Config& config, float rated_capacity_ah);
    void start(float soc);
    void predict(float current_a, float dt_s);
    // y: V + R0·I; ip: polarisation current; extra_var_v2: variance added by the R0 error.
    // learn_parameters = false updates the state of charge only (capacity and polarisation
    // are held as "consider" states): at rest nothing flows that could tell them apart.
    void correct(float y_v, float ip_a, float extra_var_v2, const OcvCurve& ocv, bool learn_parameters = true);
    const Status& status() const { return status_; }

private:
    void publish();
    Config config_;
    Status status_;
    float rated_ah_ = 1.0f;
    float x_[3] = {1.0f, 1.0f, 0.0f};  // soc, capacity_ah, polarisation_ohm
    float p_[3][3] = {};
};

}  // namespace core
}  // namespace battsim
