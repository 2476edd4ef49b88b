// The newer estimator: resistance from short-lag differences, state of charge, capacity
// and polarisation from an EKF on the resistance-compensated voltage, and flight time
// solved forward at the flight's mean power (current rises as the voltage sags). It also
// decides whether the flight will be markedly shorter than a healthy pack's, and why.
#pragma once
#include <stdint.h>

#include "core/estimate/capacity_ekf.h"
#include "core/estimate/difference_resistance.h"
#include "core/estimate/low_pass.h"
#include "core/estimate/power_time_solver.h"
#include "core/model/ocv.h"
#include "core/model/tremblay.h"

namespace battsim {
namespace core {

class JointEstimator {
public:
    // The health filter's noise settings (a random search on the simulated tuning suite,
    // checked on the held-out one; docs/estimator.md): it trusts the early voltage more
    // (tighter capacity prior, less SOC process noise) and the OCV table less pointwise.
    // The tracking filter's noise settings: a random search on the tuning suite with OCV
    // tables read off a simulated C/5 discharge (scripts/suite-ocv-tables.py), chosen among
    // the best on reseeded copies of that suite (scripts/joint-search.py --validate), then
    // checked on the held-out one (docs/estimator.md, eleventh session).
    static constexpr CapacityEkf::Config tracking_ekf_defaults() {
        CapacityEkf::Config c{};
        c.voltage_sigma_v = 0.014f;
        c.soc_sigma0 = 0.016f;
        c.capacity_sigma0_fraction = 0.1f;
        c.polarisation_initial_ohm = 0.0053f;
        c.polarisation_sigma0_ohm = 0.022f;
        c.soc_process_per_sqrt_s = 7.7e-5f;
        c.capacity_process_fraction_per_sqrt_s = 1.6e-5f;
        c.polarisation_process_ohm_per_sqrt_s = 2.6e-4f;
        c.ocv_soc_sigma = 0.02f;
        return c;
    }
    static constexpr CapacityEkf::Config health_ekf_defaults() {
        CapacityEkf::Config c{};
        c.voltage_sigma_v = 0.04f;
        c.soc_sigma0 = 0.035f;
        c.capacity_sigma0_fraction = 0.1f;
        c.polarisation_initial_ohm = 0.0045f;
        c.polarisation_sigma0_ohm = 0.013f;
        c.soc_process_per_sqrt_s = 7.0e-5f;
        c.capacity_process_fraction_per_sqrt_s = 6.0e-6f;
        c.polarisation_process_ohm_per_sqrt_s = 1.4e-4f;
        c.ocv_soc_sigma = 0.009f;
        return c;
    }
    struct Config {
        // The short-lag estimate, reporting its trend carried to now (0.2 %/s prior σ: a
        // cold pack's R0 can halve in a few minutes of flight).
        DifferenceResistanceEstimator::Config resistance{0.05f, 60.0f, 0.5f, 400.0f, 0.02f, 0.002f};
        // Used while `resistance` has too little excitation (a steady hover): a lower bar,
        // smaller steps, a two-sample lag (slow gusts step the current by a few tenths of an
        // ampere over it), and fed on the ground too, so the take-off step itself counts.
        // Fed only in flight it missed the step (the monitor confirms a take-off 0.5 s late)
        // and learnt from the settling after it, where the current falls while the
        // polarisation still builds: 4S hovers read R0 about 20 % low, then drifted up, and
        // the filter took the rising compensated voltage for charge. A 0.3 s lag read the
        // take-off step 5–9 % high (fast polarisation).
        DifferenceResistanceEstimator::Config hover_resistance{0.13f, 60.0f, 0.2f, 10.0f, 0.02f};
        CapacityEkf::Config ekf = tracking_ekf_defaults();
        // A second filter on the same compensated voltage, tuned for the pack's health
        // rather than for tracking: the capacity it reports, and the flight-time solves the
        // short-flight verdict compares, come from it; the state of charge, remaining time
        // and energy stay with `ekf`. One polarisation state cannot follow both the
        // plant's fast and slow parts, so every single tuning trades the early capacity
        // against mid-flight remaining time (none of 490 settings searched was better on
        // both: docs/estimator.md); two filters take each side of the trade where it
        // matters. Its polarisation follows R0 as the pack warms (on the real flights a
        // fixed one read the warming as charge: aged packs above new ones); the tracking
        // filter's does not (there it cost remaining time on the simulated suite).
        struct HealthFilter {
            bool enabled = true;
            CapacityEkf::Config ekf = health_ekf_defaults();
            float polarisation_time_s = 3.0f;
            float polarisation_slow_time_s = 30.0f;
            float polarisation_slow_share = 0.2f;
            bool polarisation_follows_resistance = true;
            bool first_resistance_soc_correction = true;  // see the key of that name below
            // The verdict's solves and the remaining energy start from the state of charge
            // this filter held at take-off, read off the resting pack, rather than from the
            // present one carried back by the charge since: in flight the present one also
            // carries the polarisation and R0 errors, which only the SOC at rest is free of
            // (on a healthy hover it sat 0.008 below the truth by mid-flight). Only after
            // `takeoff_soc_min_ground_s` on the ground before the take-off (not when the
            // monitor started in the air).
            bool solves_from_takeoff_soc = true;
            float takeoff_soc_min_ground_s = 5.0f;
        };
        HealthFilter health;
        // A third filter of the same kind for the short-flight verdict alone (its four
        // solves). Its slow polarisation part (150 s) builds far slower than the plant's
        // (40 s), so early in a flight it reads that build-up as charge drawn: a capacity
        // leaning low, which brings a real shortfall's warning forward. The health filter
        // keeps the capacity and energy it reports honest; the verdict keeps its 20 %
        // margin on undegraded packs (docs/estimator.md, twenty-first session). The take-off
        // state-of-charge keys are the health filter's. Disabled: the verdict reads `health`.
        HealthFilter verdict = [] {
            HealthFilter v{};
            v.polarisation_slow_time_s = 150.0f;
            return v;
        }();
        OcvTable ocv;                       // optional; else the model's no-load curve
        float resistance_prior_fraction = 0.5f;  // σ of the configured resistance, as a fraction
        float polarisation_time_s = 3.0f;   // i_p time constant: fast enough that i_p follows the throttle and cannot mimic the SOC trend
        // A second, slow part of the polarisation sharing the one resistance state: i_p is
        // (1 − share)·(fast low-pass) + share·(slow low-pass). One state keeps the filter
        // well conditioned (two free, nearly collinear branches diverged in float); the
        // shape comes from a fit of the pack (battsim fit's RC branches). 0 = off. The
        // share is 0.3 since the solves carry the cutoff delay (0.4 had made up for the
        // missing delay; chosen on reseeded suites: docs/estimator.md, twelfth session).
        float polarisation_slow_time_s = 30.0f;
        float polarisation_slow_share = 0.3f;
        float min_voltage_v = 13.3f;        // loaded cutoff
        // How long the loaded voltage may stay below min_voltage_v before the flight is
        // over: a failsafe judges a filtered voltage (a first-order filter crosses its
        // threshold one time constant after a falling ramp does) or waits out a hold
        // timer (ArduPilot's BATT_LOW_TIMER). The solves fly on that long past the
        // crossing, at the power then. Without it the solves stop a filter's lag early:
        // fed the true pack they read the simulated suite's remaining energy at 20 % of
        // the flight 2.2 % low (median), with it 0.8 % high (docs/estimator.md, twelfth session).
        float cutoff_delay_s = 0.0f;
        // Early in a flight the published remaining time leans on the health filter's solve
        // from take-off (its flight time less the time flown), which reads a lost capacity
        // sooner than the tracking filter; the lean fades linearly to none once
        // health_time_fade_fraction of the rated capacity is drawn, where the tracking
        // filter is the better (docs/estimator.md, fourteenth session). 0 = tracking only.
        float health_time_share = 0.5f;
        float health_time_fade_fraction = 0.5f;
        int solver_steps = 32;
        // A round of the six solves (five without a verdict filter) takes, per solve,
        // solver_steps / solver_steps_per_update updates rounded up: 11 steps per update
        // (3 updates a solve) refresh the remaining time and the verdict every 1.22 s at
        // the reference logger's 68 ms (docs/benchmarks.md for the cost). A fresher verdict
        // warned more short flights in time (docs/estimator.md, twentieth and twenty-first
        // sessions).
        int solver_steps_per_update = 11;
        float short_flight_fraction = 0.8f;  // warn below this × a healthy pack's flight time
        float cause_fraction = 0.9f;         // a cause alone must cost ≥ 10 % of the time
        float min_flight_s = 8.0f;           // before any verdict
        // Consecutive short verdicts before a warning: with the round above, a verdict must
        // hold 2.4 s (three verdicts 1.22 s apart). Shorter holds added false warnings on
        // degraded packs that were not 20 % short (twentieth session).
        int persistence = 3;
        // A longer gap between samples is a sensor (logging) fault; so is one over three of the
        // log's own usual intervals, when these are longer (a log of the battery at 1 Hz).
        float max_sample_gap_s = 0.75f;
        // Over such a gap the current is unknown: its charge is counted at the mean of the
        // currents either side, and both filters' state of charge takes the variance of a
        // charge error of this fraction × the larger of them × the gap (0: none added). The
        // true charge scatters about that mean by 0.19 of it (RMS) over the suite's 1–3 s
        // dropouts; 0.25 leans cautious (docs/estimator.md, fifteenth session).
        float gap_charge_sigma_fraction = 0.25f;
        float gap_hold_s = 5.0f;  // no capacity or polarisation learning this long after a gap
        float min_flying_current_a = 1.0f;   // the monitor's take-off current (set by the monitor), on the offset-corrected current
        float landed_hold_s = 1.0f;          // the monitor's landing hold (set by the monitor): how long below that current is a landing
        float offset_fault_a = 0.5f;         // a learnt current offset beyond this (and 3 σ) is a sensor fault
        bool learn_offset_in_flight = false;  // in flight polarisation and capacity errors would drive it
        float ground_soc_process_scale = 0.2f;  // SOC process noise on the ground, × the in-flight value
        float resistance_settle_s = 40.0f;  // learn capacity on the prior R after this long without a measured R0
        float offset_learn_max_current_a = 3.0f;  // the offset is learnt while the measured current is below this (on the ground)
        // Polarisation resistance scaled with the ohmic resistance (R0 now / R0 when learning
        // began): both fall as the pack warms in flight (the same Arrhenius behaviour), and a
        // fixed Rp would read that recovery of the voltage as charge the pack still holds.
        bool polarisation_follows_resistance = false;  // off: on the simulated suite it cost a false warning (docs/estimator.md)
        // Until R0 is measured the filters compensate with the configured value, and an
        // aged or cold pack's extra sag is read as charge drawn. When the first measured R0
        // arrives, the state of charge is moved by what that R0 would have changed from
        // take-off (to first order, through the filter's own gains). On the health filter
        // it lowers the capacity error on both suites and moves nothing else; on the
        // tracking filter it trades remaining time for remaining energy (docs/estimator.md).
        bool first_resistance_soc_correction = false;
        // Capacity from two rests: the charge counted since the first resting voltage over
        // the fall in SOC the OCV curve reads between it and a rest after landing. The
        // filter cannot use the landing rest (it learns capacity only in flight, where the
        // state of charge moves); a rest after a flight is the cleanest reading a monitor
        // gets. The voltage is still recovering after tens of seconds, so the value reads a
        // little low; it is refreshed while the rest lasts.
        float rest_capacity_min_rest_s = 30.0f;
        float rest_capacity_max_current_a = 1.0f;
        float rest_capacity_min_soc_drop = 0.25f;  // below this the curve's error dominates
        // The reported capacity's standard error adds, in quadrature, this × the charge drawn
        // since start: the health filter's own error shrinks as charge flows, while the OCV
        // table's and the polarisation shape's errors do not average away and grow as the
        // pack runs deeper. The filter's alone had 32 % of the landing errors within one σ
        // (median 2.35 σ); with 0.08, 68 % and 95 % within two at the landing and at 20 % of
        // the flight alike (docs/estimator.md, twenty-sixth session). 0: the filter's alone.
        float capacity_sigma_fraction_of_charge = 0.08f;
    };
    enum Cause : uint8_t { kCauseNone = 0, kCauseCapacity = 1, kCauseResistance = 2 };
    struct Status {
        bool started = false;
        float soc = 0.0f;
        float capacity_ah = 0.0f;
        float sigma_capacity_ah = 0.0f;    // the health filter's standard error, scaled as capacity_ah, and the systematic part
        float resistance_ohm = 0.0f;       // ohmic (short-lag) resistance now, the prior folded in
        float effective_resistance_ohm = 0.0f;  // the window mean the filter and the solves use
        float measured_resistance_ohm = 0.0f;  // from the differences alone (0 until valid)
        float measured_resistance_sigma_ohm = 0.0f;
        bool resistance_measured = false;  // the two above are valid (else resistance_ohm is the prior's)
        float polarisation_ohm = 0.0f;
        float polarisation_current_a = 0.0f;  // the low-passed current the polarisation sees
        float mean_power_w = 0.0f;         // since take-off
        float remaining_time_s = 0.0f;
        float remaining_energy_wh = 0.0f;  // the health filter's, to the cutoff at the mean power
        float total_time_s = 0.0f;         // estimated flight time from take-off
        float expected_time_s = 0.0f;      // a healthy pack's, from the same take-off charge
        bool time_valid = false;
        bool short_flight = false;
        uint8_t cause = kCauseNone;        // Cause bits
        bool flying = false;               // in a flight: from a take-off on the offset-corrected current to a landing held landed_hold_s
        bool loaded = false;               // flying and this sample above the take-off current: what the fits learn from
        float current_offset_a = 0.0f;     // learnt current-sensor offset
        float sigma_current_offset_a = 0.0f;
        bool current_offset_fault = false;
        bool sample_gap = false;  // this sample ends a logging gap (a sensor fault)
        float rest_capacity_ah = 0.0f;     // after a flight and a rest (0 = none yet)
        float innovation_v = 0.0f;         // the tracking filter's: this sample's voltage less what it predicted
    };

    void configure(const Config& config, const TremblayParams& rated, int cells_in_series);
    // Settles the initial state of charge from a resting voltage.
    void start(float voltage_v, float current_a);
    void update(uint64_t time_us, float voltage_v, float current_a, float dt_s, bool flying);
    // The weakest cell's capacity shortfall (fraction, from the cell check): a series pack
    // delivers only what its weakest cell holds.
    void set_weakest_cell_deficit(float fraction) { weakest_deficit_ = fraction > 0.0f && fraction < 0.9f ? fraction : 0.0f; }
    const Status& status() const { return status_; }
    const OcvCurve& ocv() const { return ocv_; }

private:
    // The verdict's four solves, then the health filter's from take-off (its energy and
    // time), skipped when the verdict reads the health filter.
    enum Solve : uint8_t {
        kSolveRemaining = 0, kSolveTotal, kSolveExpected, kSolveCapacityOnly, kSolveResistanceOnly, kSolveHealth,
        kSolveCount
    };
    // A filter of the health kind, with its own polarisation currents.
    struct Branch {
        CapacityEkf ekf;
        LowPassFilter current, slow_current;
        float scale = 1.0f;        // its polarisation's R0 now / R0 when learning began
        float soc_per_ohm = 0.0f;  // its SOC per ohm of prior R0 (before learning)
        float takeoff_soc = 1.0f;  // at the last take-off
        float polarisation_current_a = 0.0f;  // the low-passed current its polarisation saw last
    };
    static void configure_branch(Branch& b, const Config::HealthFilter& c, float capacity_ah);
    static void start_branch(Branch& b, float soc, float current_a);
    void start_solve();
    // The filter the capacity and the energy read: the health filter when enabled.
    const Branch& health_branch() const { return config_.health.enabled ? health_ : tracking_; }
    const CapacityEkf::Status& health() const { return health_branch().ekf.status(); }
    // ... and the one the verdict reads: its own, or as above.
    const Branch& verdict_branch() const { return config_.verdict.enabled ? verdict_ : health_branch(); }
    float fuse_with_prior(bool valid, float measured_ohm, float sigma_ohm, float* sigma_out) const;
    float other_cells_ah(float mean_cell_ah) const;
    float weakest_cell_ah(float mean_cell_ah) const;
    void finish_solve();
    // What a filter's state of charge has moved per ohm of the resistance it compensated
    // with before learning: s ← (1 − k·h)·s + k·I per correction (k its SOC gain, h the
    // OCV slope; y = V + R0·I moves by I per ohm).
    static float soc_per_ohm(const CapacityEkf::Status& s, float sensitivity, float current_a) {
        const float k = s.soc_gain_per_v;
        return (1.0f - k * s.ocv_slope_v_per_soc) * sensitivity + k * current_a;
    }

    Config config_;
    Status status_;
    TremblayParams rated_;
    OcvCurve ocv_;
    bool takeoff_soc_valid_ = false;   // wanted, and the take-off came after takeoff_soc_min_ground_s on the ground
    DifferenceResistanceEstimator resistance_;
    DifferenceResistanceEstimator hover_resistance_;
    Config::HealthFilter tracking_settings_;  // the tracking filter's, gathered from `joint`
    Branch tracking_;
    Branch health_;
    Branch verdict_;
    PowerTimeSolver solver_;
    uint8_t solve_ = kSolveRemaining;
    float solve_power_w_ = 0.0f;
    float results_[kSolveCount] = {};
    float flying_s_ = 0.0f;
    float flying_energy_j_ = 0.0f;
    float charge_since_takeoff_ah_ = 0.0f;
    float solve_started_s_ = 0.0f;     // flight time when the remaining solve under way began
    float end_s_ = 0.0f;               // the published solve: flight time at the cutoff
    float health_end_s_ = 0.0f;        // the health filter's, from this flight's total solve (0: none yet)
    float total_wh_ = 0.0f;            // the health filter's: energy from take-off to the cutoff
    bool was_flying_ = false;
    float below_takeoff_s_ = 0.0f;  // in flight, below the take-off current (offset-corrected) since
    int short_count_ = 0;
    float weakest_deficit_ = 0.0f;
    int cells_ = 1;
    float polarisation_ref_ohm_ = 0.0f;  // R0 when capacity and polarisation learning began (0: not yet)
    // R0 as the polarisation follows it: a minute's mean. The pack's R0 moves with its
    // temperature, over minutes; what the estimate moves by in seconds is noise (a hover's
    // few steps read in 10 mV: a 4S 22 Ah pack's 1.4 mOhm jumped 6 % in 3 s, and its
    // capacity fell to the filter's floor).
    LowPassFilter follow_r0_;
    float start_soc_ = 1.0f;             // from the first resting voltage
    float charge_total_ah_ = 0.0f;       // offset-corrected, since start
    float ground_s_ = 0.0f;              // on the ground (not flying), since
    float rest_s_ = 0.0f;                // on the ground below the rest current, since
    bool has_flown_ = false;
    // The most state of charge shown on the ground after a flight: the last loaded sample's
    // until a rest sets the filters (see update: a landing must not read the pack fuller).
    float landing_soc_ = 1.0f;
    bool taken_off_ = false;  // the offset is learnt only before this
    float last_voltage_v_ = 0.0f;
    float last_current_a_ = 0.0f;  // the previous sample's, for a gap's charge
    float gap_hold_s_ = 0.0f;      // counts down after a gap: learning held
    float usual_dt_s_ = 0.0f;      // the log's usual sample interval (0: not seen one yet)
    uint32_t rest_reads_ = 0;
};

}  // namespace core
}  // namespace battsim
