// The truth plant: a series pack of cells, each an OCV(SOC) source behind an ohmic
// resistance and two RC polarisation branches, all resistances following Arrhenius in
// the pack temperature (and R0 rising near empty); one lumped thermal mass heated by the
// losses and cooled by convection to ambient. Deliberately not the Tremblay model the
// monitor runs: an estimator must not win by sharing the plant's equations.
//
// The load is a constant power at the pack terminals; each step solves the current from
// P = (E − R·I)·I, so the current rises as the voltage sags. Doubles throughout; only
// correctly rounded operations and det_exp are used, so results are bit-identical on
// every platform.
#pragma once
#include "core/sample.h"
#include "host/sim/ocv.h"

namespace battsim {
namespace host {
namespace sim {

constexpr int kMaxCells = core::kMaxCells;

struct CellParams {
    double capacity_ah = 1.55;
    double r0_ohm = 0.004;   // ohmic, at the reference temperature
    double r1_ohm = 0.001;   // fast polarisation branch
    double tau1_s = 1.5;
    double r2_ohm = 0.0015;  // slow (diffusion) branch
    double tau2_s = 40.0;
};

struct PlantParams {
    int cells = 4;
    CellParams cell[kMaxCells];
    const OcvCurve* ocv = &OcvCurve::generic_lipo();
    double activation_energy_j_per_mol = 20000.0;  // Arrhenius: R ∝ exp(Ea/Rg·(1/T − 1/Tref))
    double reference_temperature_c = 25.0;
    // R0 grows near empty: × (1 + rise·exp(−soc/scale)).
    double low_soc_resistance_rise = 0.5;
    double low_soc_resistance_scale = 0.1;
    double heat_capacity_j_per_k = 190.0;
    double conductance_ground_w_per_k = 0.4;  // still air
    double conductance_flight_w_per_k = 1.6;  // prop wash
    double ambient_c = 20.0;
};

struct PlantState {
    double soc[kMaxCells] = {};
    double v1_v[kMaxCells] = {};  // RC branch voltages
    double v2_v[kMaxCells] = {};
    double temperature_c = 20.0;
    double charge_ah = 0.0;      // drawn from the pack since the start
    double energy_wh = 0.0;      // delivered at the terminals since the start
    double heat_j = 0.0;
};

struct PlantOutput {
    double current_a = 0.0;
    double voltage_v = 0.0;
    double power_w = 0.0;
    double cell_v[kMaxCells] = {};
    bool brownout = false;  // the demanded power exceeds what the pack can deliver
};

class Plant {
public:
    void configure(const PlantParams& params, double initial_soc, double initial_temperature_c);
    // Draws `power_w` for dt_s: the current is solved from the state at the start of the
    // step and held over it. Returns the terminal values during the step.
    PlantOutput step_power(double power_w, double dt_s, bool airborne);
    // Terminal values for a given current without advancing.
    PlantOutput evaluate_current(double current_a) const;

    // Temperature factor of every resistance at the present pack temperature.
    double temperature_factor() const;
    double temperature_factor_at(double temperature_c) const;
    // Pack ohmic resistance now (temperature and state of charge included).
    double pack_r0_ohm() const;
    // Pack ohmic resistance at the reference temperature and full charge.
    double pack_r0_reference_ohm() const;
    double min_soc() const;

    const PlantParams& params() const { return params_; }
    const PlantState& state() const { return state_; }
    void set_state(const PlantState& s) { state_ = s; }

private:
    double cell_r0(int c, double temp_factor) const;
    void refresh_decay(double dt_s);

    PlantParams params_;
    PlantState state_;
    double decay_dt_s_ = -1.0;
    double decay1_[kMaxCells] = {};
    double decay2_[kMaxCells] = {};
};

}  // namespace sim
}  // namespace host
}  // namespace battsim
