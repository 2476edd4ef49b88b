// Time to the cutoff voltage at a constant power demand: steps the pack down its OCV
// curve, solving at each step the current that delivers the power through the total
// resistance (P = (OCV − R·I)·I, closed form), until the loaded voltage reaches the
// minimum. Work is spread over calls (`advance`) so no monitor update runs long.
#pragma once

#include "core/model/ocv.h"

namespace battsim {
namespace core {

class PowerTimeSolver {
public:
    struct Result {
        float time_s = 0.0f;
        float charge_ah = 0.0f;
        float energy_wh = 0.0f;
        bool cutoff = false;  // the minimum voltage (or the power limit) was reached
    };

    // weak_cell_share: 1/(cells in series) for a pack with one weak cell holding
    // weak_cell_ratio of the others' capacity (0 = none): the pack's OCV is then the
    // others' share of the curve plus the weak cell's, further down its own curve (and
    // past its empty end, continued at the curve's bottom slope), so the loaded voltage
    // reaches the cutoff as the weak cell collapses, not when the average cell is empty.
    void start(float soc_from, float capacity_ah, float resistance_ohm, float power_w, float min_voltage_v,
               int steps, float weak_cell_share = 0.0f, float weak_cell_ratio = 1.0f);
    // Time the flight goes on at the power after the loaded voltage reaches the minimum
    // (a failsafe's filter or hold time; 0 = the crossing ends it). Kept across starts.
    void set_cutoff_delay_s(float delay_s) { cutoff_delay_s_ = delay_s > 0.0f ? delay_s : 0.0f; }
    // Drops a solve under way: the next advance() returns at once and a new start() is due.
    void stop() { done_ = true; }
    // Runs up to `max_steps` steps; returns true when the result is complete.
    bool advance(const OcvCurve& ocv, int max_steps);
    bool done() const { return done_; }
    const Result& result() const { return result_; }

private:
    float loaded_voltage(const OcvCurve& ocv, float soc, float& current_a, bool& feasible) const;
    float soc_from_ = 0.0f, capacity_ah_ = 0.0f, resistance_ohm_ = 0.0f, power_w_ = 0.0f, min_v_ = 0.0f;
    float weak_share_ = 0.0f, weak_ratio_ = 1.0f;
    float cutoff_delay_s_ = 0.0f;
    int steps_ = 0, step_ = 0;
    float prev_v_ = 0.0f, prev_i_ = 0.0f;
    bool done_ = true;
    Result result_;
};

}  // namespace core
}  // namespace battsim
