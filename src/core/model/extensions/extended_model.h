// Optional extensions of the Tremblay–Dessaint model, configured per pack and each off
// by default (all-zero config = the plain TremblayModel, bit for bit):
//   * RC polarisation branches: fast voltage relaxation after current steps;
//   * temperature dependence (Arrhenius-type R and K, linear Q and E0 in temperature),
//     driven by the measured temperature or, without one, by a lumped I²R thermal state;
//   * one-state hysteresis, an OCV-shape correction table over the charge drawn;
//   * current-sensor gain/offset and a current-to-voltage timing skew.
// Same rules as the rest of the core: float, fixed size, no heap, time only from dt.
#pragma once
#include <stdint.h>

#include "core/model/tremblay.h"

namespace battsim {
namespace core {

constexpr int kMaxRcBranches = 3;
constexpr int kMaxOcvPoints = 16;

// One RC pair in series with the cell: its voltage relaxes to R·i with time constant tau.
struct RcBranch {
    float resistance_ohm = 0.0f;
    float time_constant_s = 1.0f;
};

// Tremblay's temperature extension: X(T) = X_ref·exp(activation·(1/T − 1/T_ref)) for the
// internal resistance and for the polarisation (K and the RC resistances); capacity and
// E0 move linearly. T in kelvin inside, °C outside.
struct TemperatureDependence {
    bool enabled = false;
    float reference_c = 25.0f;
    float resistance_activation_k = 0.0f;
    float polarisation_activation_k = 0.0f;
    float capacity_ah_per_c = 0.0f;
    float e0_v_per_c = 0.0f;
};

// Lumped thermal state used when a sample carries no temperature: the pack heats with its
// losses (I²R plus the RC branches) towards ambient + R_th·P with time constant tau.
struct LumpedThermal {
    bool enabled = false;
    float ambient_c = 25.0f;
    float thermal_resistance_k_per_w = 1.0f;
    float time_constant_s = 600.0f;
};

// Voltage hysteresis that moves towards −magnitude while discharging and +magnitude while
// charging, at `rate_per_ah` per ampere-hour through the cell.
struct Hysteresis {
    float magnitude_v = 0.0f;  // 0 = off
    float rate_per_ah = 10.0f;
};

// Additive open-circuit-voltage correction, piecewise linear over the charge drawn: point j
// sits at j·span/(count − 1); beyond the ends the end values hold.
struct OcvCorrection {
    uint8_t count = 0;  // 0 = off; otherwise 2..kMaxOcvPoints
    float span_ah = 1.0f;
    float delta_v[kMaxOcvPoints] = {};
};

// Corrections of the current measurement. gain/offset apply to the raw sample current before
// anything uses it (filter, counter, model); lead_s > 0 means the current was sampled that
// long before the voltage, so the model extrapolates the current forward by lead_s.
struct CurrentSensorCorrection {
    float gain = 1.0f;
    float offset_a = 0.0f;
    float lead_s = 0.0f;
};

struct ModelExtensions {
    uint8_t rc_count = 0;
    RcBranch rc[kMaxRcBranches];
    TemperatureDependence temperature;
    LumpedThermal thermal;
    Hysteresis hysteresis;
    OcvCorrection ocv;
    CurrentSensorCorrection current_sensor;
};

// True if any extension changes the model voltage or the current (all-zero = plain model).
bool extensions_active(const ModelExtensions& e);

class ExtendedModel {
public:
    struct Status {
        float temperature_c = 25.0f;
        bool temperature_measured = false;  // false: thermal state or ambient
        float rc_voltage_v[kMaxRcBranches] = {};
        float hysteresis_v = 0.0f;
        float resistance_ohm = 0.0f;  // at the present temperature
        float capacity_ah = 0.0f;     // at the present temperature
        float heat_w = 0.0f;          // losses of the last update
    };

    void configure(const TremblayParams& params, const ModelExtensions& extensions);
    // Back to rest: RC branches and hysteresis at zero, temperature at ambient.
    void reset();

    // The sample current as the model and the counters should see it (gain and offset).
    float corrected_current_a(float raw_current_a) const {
        return ext_.current_sensor.gain * raw_current_a + ext_.current_sensor.offset_a;
    }
    // Advances the states over dt with this sample's (corrected) current; the temperature
    // is used when has_temperature is set, else the thermal state runs (if enabled).
    void update(float current_a, float dt_s, bool has_temperature, float temperature_c);
    // Terminal voltage with the states of the last update.
    float voltage_v(float used_ah, float current_a, float filtered_current_a) const;
    // Charge drawn at which voltage_v(·, i, i) gives `voltage_v` with the present states
    // (bisection over the model's range), for the monitor's initial state.
    float used_ah_at_voltage(float voltage_v, float current_a) const;

    bool active() const { return active_; }
    const TremblayModel& base() const { return base_; }
    const ModelExtensions& extensions() const { return ext_; }
    const Status& status() const { return status_; }

private:
    void apply_temperature(float temperature_c);
    float ocv_correction_v(float used_ah) const;

    TremblayModel base_;
    ModelExtensions ext_;
    Status status_;
    // Temperature-adjusted base quantities (equal to the base model's when disabled).
    float e0_v_ = 0.0f, r_ohm_ = 0.0f, k_v_ = 0.0f, q_ah_ = 0.0f;
    float polarisation_factor_ = 1.0f;
    float previous_current_a_ = 0.0f;
    float current_slope_a_per_s_ = 0.0f;
    bool have_current_ = false;
    bool active_ = false;
};

}  // namespace core
}  // namespace battsim
