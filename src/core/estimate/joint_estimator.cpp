#include "core/estimate/joint_estimator.h"

#include "core/numeric.h"

namespace battsim {
namespace core {
namespace {
// A resting pack's voltage this far per cell from the tracking filter's prediction means the
// filter has lost it (a healthy filter rests within about 5 mV per cell of the measurement).
constexpr float kLostAtRestVPerCell = 0.05f;
}  // namespace

void JointEstimator::configure_branch(Branch& b, const Config::HealthFilter& c, float capacity_ah) {
    b = Branch{};
    b.ekf.configure(c.ekf, capacity_ah);
    b.current.configure({c.polarisation_time_s});
    b.slow_current.configure({c.polarisation_slow_time_s});
}

void JointEstimator::start_branch(Branch& b, float soc, float current_a) {
    b.ekf.start(soc);
    b.current.reset(current_a);
    b.slow_current.reset(current_a);
}

void JointEstimator::configure(const Config& config, const TremblayParams& rated, int cells_in_series) {
    config_ = config;
    rated_ = rated;
    cells_ = cells_in_series > 0 ? cells_in_series : 1;
    follow_r0_.configure({60.0f});
    ocv_.configure(config.ocv, cells_in_series, rated);
    solver_.set_cutoff_delay_s(config.cutoff_delay_s);
    // A monitor configured again (a new pack without a restart) starts as a new one: a solve
    // left under way and finished on the new pack had its remaining time off by up to 107 s
    // after the take-off and by 7.6 s a minute later (logs/example-4s.csv twice; test_monitor.cpp).
    solver_.stop();
    for (float& r : results_) r = 0.0f;
    DifferenceResistanceEstimator::Config rc = config.resistance;
    rc.initial_resistance_ohm = rated.internal_resistance_ohm;
    resistance_.configure(rc);
    DifferenceResistanceEstimator::Config hc = config.hover_resistance;
    hc.initial_resistance_ohm = rated.internal_resistance_ohm;
    hover_resistance_.configure(hc);
    // The tracking filter's settings sit in `joint` itself.
    Config::HealthFilter& tc = tracking_settings_;
    tc.ekf = config.ekf;
    tc.polarisation_time_s = config.polarisation_time_s;
    tc.polarisation_slow_time_s = config.polarisation_slow_time_s;
    tc.polarisation_slow_share = config.polarisation_slow_share;
    tc.polarisation_follows_resistance = config.polarisation_follows_resistance;
    tc.first_resistance_soc_correction = config.first_resistance_soc_correction;
    configure_branch(tracking_, tc, rated.capacity_ah);
    configure_branch(health_, config.health, rated.capacity_ah);
    configure_branch(verdict_, config.verdict, rated.capacity_ah);
    status_ = Status{};
    status_.capacity_ah = rated.capacity_ah;
    status_.resistance_ohm = status_.effective_resistance_ohm = rated.internal_resistance_ohm;
    solve_ = kSolveRemaining;
    flying_s_ = flying_energy_j_ = charge_since_takeoff_ah_ = solve_started_s_ = 0.0f;
    end_s_ = health_end_s_ = total_wh_ = 0.0f;
    short_count_ = 0;
    was_flying_ = false;
    below_takeoff_s_ = 0.0f;
    polarisation_ref_ohm_ = 0.0f;
    start_soc_ = 1.0f;
    takeoff_soc_valid_ = false;
    charge_total_ah_ = rest_s_ = ground_s_ = gap_hold_s_ = 0.0f;
    has_flown_ = false;
    landing_soc_ = 1.0f;
    taken_off_ = false;
    rest_reads_ = 0;
    last_voltage_v_ = 0.0f;
    last_current_a_ = 0.0f;
    usual_dt_s_ = 0.0f;
}

void JointEstimator::start(float voltage_v, float current_a) {
    const float soc = CapacityEkf::soc_at_rest_voltage(ocv_, voltage_v + current_a * rated_.internal_resistance_ohm);
    start_soc_ = soc;
    start_branch(tracking_, soc, current_a);
    start_branch(health_, soc, current_a);
    start_branch(verdict_, soc, current_a);
    status_.started = true;
    status_.soc = clampf(soc, 0.0f, 1.0f);
}

void JointEstimator::update(uint64_t time_us, float voltage_v, float current_a, float dt_s, bool flying) {
    if (!status_.started) start(voltage_v, current_a);
    // Flying on the offset-corrected current: a sensor reading 1.5 A high on the ground must
    // not start the flight (and its mean power) before take-off.
    const float offset_a = tracking_.ekf.status().offset_a;
    const float true_a = current_a - offset_a;
    // A logging gap: its charge at the mean of the currents either side (the sample's own
    // current alone had counted a dropout across a burst's end 65 As short, on a 1.5 Ah pack
    // 1 % of charge: early in a flight, 10 % of capacity), and the filters told how unsure it
    // is. The low-passed polarisation currents do not know what flowed in the gap either, so
    // capacity and polarisation are not learnt for gap_hold_s after it.
    float charge_a = current_a;
    float gap_var_soc = 0.0f;
    if (!(usual_dt_s_ > 0.0f)) usual_dt_s_ = dt_s;  // the first interval seeds it
    status_.sample_gap = dt_s > maxf(config_.max_sample_gap_s, 3.0f * usual_dt_s_);
    if (status_.sample_gap) {
        charge_a = 0.5f * (current_a + last_current_a_);
        const float sd_soc = config_.gap_charge_sigma_fraction * maxf(fabsf(current_a), fabsf(last_current_a_)) * dt_s /
                             (3600.0f * rated_.capacity_ah);
        gap_var_soc = sd_soc * sd_soc;
        gap_hold_s_ = config_.gap_hold_s;
    } else {
        gap_hold_s_ -= dt_s;  // below zero: no gap in the last gap_hold_s
        usual_dt_s_ += 0.05f * (dt_s - usual_dt_s_);
    }
    last_current_a_ = current_a;
    const float true_charge_a = charge_a - offset_a;
    // The take-off threshold carries the offset's own uncertainty (3 σ), so a half-learnt
    // offset cannot keep a pack on the ground "flying"; at or above the offset-learning
    // current the pack counts as flying whatever the offset.
    const float takeoff_a = config_.min_flying_current_a + 3.0f * tracking_.ekf.status().sigma_offset_a;
    const bool above = true_a >= takeoff_a || current_a >= config_.offset_learn_max_current_a;
    // The threshold starts a flight at once, but ends one only after the monitor's landing
    // hold: a single sample below it in the air (a descent, a throttle cut) had ended the
    // flight and restarted its accumulators, publishing 0 s remaining until the solves came
    // round again and judging the rest as a new flight (CMU M100 flight 24, at 38 s; the
    // dissertation's flight 32 at 187 s). What the estimators learn from stays with the
    // loaded samples alone (`flying` below): a landing's second of recovering voltages read
    // as a weak cell on a hover.
    below_takeoff_s_ = was_flying_ && !above ? below_takeoff_s_ + dt_s : 0.0f;
    const bool airborne = flying && (above || (was_flying_ && below_takeoff_s_ <= config_.landed_hold_s + 1.0e-4f));
    flying = flying && above;
    if (airborne && !was_flying_) {
        // A take-off: the flight's accumulators start again. What the last flight's solves left
        // carries on from the new flight's start: zeroed, it had published 0 s left (a critical
        // beep) until the next round was in.
        end_s_ = status_.remaining_time_s;
        total_wh_ = status_.remaining_energy_wh;
        flying_s_ = flying_energy_j_ = charge_since_takeoff_ah_ = solve_started_s_ = health_end_s_ = 0.0f;
        short_count_ = 0;
        // ground_s_ still holds the time on the ground that ended here (cleared below).
        // Each filter keeps its own, so a disabled one's stand-in (health → tracking,
        // verdict → health) brings its own take-off charge.
        tracking_.takeoff_soc = tracking_.ekf.status().soc;
        health_.takeoff_soc = health_.ekf.status().soc;
        verdict_.takeoff_soc = verdict_.ekf.status().soc;
        takeoff_soc_valid_ = config_.health.solves_from_takeoff_soc && ground_s_ >= config_.health.takeoff_soc_min_ground_s;
    }
    was_flying_ = airborne;
    status_.flying = airborne;
    status_.loaded = flying;
    // The short-lag estimate runs in flight only: fed on the ground as well (the take-off
    // ramp's pairs), the suite's median R0 error at 20 % of the flight rose from 4 to 5.4 %.
    if (flying) {
        resistance_.update(time_us, voltage_v, current_a);
    } else {
        resistance_.break_history();
    }
    hover_resistance_.update(time_us, voltage_v, current_a);
    // The hover estimate stands in only after resistance_settle_s of flight without the
    // short-lag one: in a racing flight's first seconds its small steps within the bursts
    // read polarisation (letting it stand in as soon as it was valid cost 1.3 points of
    // remaining time at 20 % on the suite).
    const bool settled = flying_s_ >= config_.resistance_settle_s;
    const DifferenceResistanceEstimator::Status& rs =
        resistance_.status().valid || !settled ? resistance_.status() : hover_resistance_.status();
    float r_sigma = 0.0f;
    const float r0 = fuse_with_prior(rs.valid, rs.resistance_ohm, rs.sigma_ohm, &r_sigma);
    // Reported: the resistance now, the pack's warming trend carried through. The filter
    // and the flight-time solves keep the window mean r0: with the single polarisation
    // state, the lag of r0 carries part of the slow polarisation, and switching them to
    // the trend-corrected value cost remaining time and energy (docs/estimator.md).
    status_.resistance_ohm = fuse_with_prior(rs.valid, rs.resistance_now_ohm, rs.sigma_now_ohm, nullptr);
    status_.effective_resistance_ohm = r0;

    // Capacity and polarisation are learnt only once R0 is measured (or, with too little
    // excitation to measure it, after resistance_settle_s of flight on the prior): an R0
    // error at take-off (0.8 V at 50 A on a pack 60 % above its configured resistance)
    // would otherwise be read as charge and polarisation.
    // Below the offset-learning current the pack is on the ground: what the voltage shows
    // there is the offset, never capacity or polarisation.
    const bool ground = current_a < config_.offset_learn_max_current_a;
    // The offset is learnt on the ground before the first take-off only: after a flight the
    // pack's voltage recovers for minutes as its polarisation relaxes, which the filter
    // would read as charge the sensor counted but the pack never gave (a false offset, and a
    // sensor-fault warning after every landing).
    taken_off_ = taken_off_ || flying;
    // On the ground the voltage is used as it is: R0 times a ground current is a few mV and
    // constant, while compensating with the offset-corrected current would move y as the
    // offset is learnt and slow that learning down (the offset reaches y only through the
    // state of charge; see CapacityEkf).
    const float compensated_v = ground ? voltage_v : voltage_v + r0 * true_a;
    const bool learn = flying && !ground && (resistance_.status().valid || settled) && gap_hold_s_ < 0.0f;
    // The polarisation state is held at the ohmic resistance when learning began; from
    // then on the polarisation the voltage sees moves in proportion with R0.
    // Learning starts on the first measured R0 (or the prior, settled): each filter's state
    // of charge takes what R0 would have moved it by from take-off.
    const bool first_r0 = learn && !(polarisation_ref_ohm_ > 0.0f);
    if (first_r0) polarisation_ref_ohm_ = r0;
    const float dr_ohm = r0 - rated_.internal_resistance_ohm;
    const bool before_learning = flying && !ground && !learn;
    if (first_r0) follow_r0_.reset(r0);
    const float follow = polarisation_ref_ohm_ > 0.0f ? follow_r0_.update(r0, dt_s) / polarisation_ref_ohm_ : 1.0f;
    const float r0_var_v2 = (r_sigma * true_a) * (r_sigma * true_a);
    const bool learn_offset = (ground && !taken_off_) || (flying && config_.learn_offset_in_flight);
    // The tracking, health and verdict filters: one step, each on its own settings.
    Branch* const branches[3] = {&tracking_, &health_, &verdict_};
    const Config::HealthFilter* const settings[3] = {&tracking_settings_, &config_.health, &config_.verdict};
    for (int k = 0; k < 3; ++k) {
        Branch& b = *branches[k];
        const Config::HealthFilter& c = *settings[k];
        if (!c.enabled) continue;
        if (first_r0 && c.first_resistance_soc_correction) b.ekf.shift_soc(b.soc_per_ohm * dr_ohm);
        const float w = c.polarisation_slow_share;
        float ip = b.current.update(current_a, dt_s);
        if (w > 0.0f) ip = (1.0f - w) * ip + w * b.slow_current.update(current_a, dt_s);
        b.polarisation_current_a = ip;
        b.ekf.predict(charge_a, dt_s, ground, config_.ground_soc_process_scale, gap_var_soc);
        b.scale = c.polarisation_follows_resistance ? follow : 1.0f;
        b.ekf.correct(compensated_v, ip, r0_var_v2, ocv_, learn, learn_offset, b.scale);
        if (before_learning) b.soc_per_ohm = soc_per_ohm(b.ekf.status(), b.soc_per_ohm, true_a);
    }
    const CapacityEkf::Status& es = tracking_.ekf.status();
    status_.current_offset_a = es.offset_a;
    status_.innovation_v = es.innovation_v;
    status_.sigma_current_offset_a = es.sigma_offset_a;
    status_.current_offset_fault =
        fabsf(es.offset_a) > config_.offset_fault_a && fabsf(es.offset_a) > 3.0f * es.sigma_offset_a;

    charge_total_ah_ += true_charge_a * dt_s / 3600.0f;
    if (airborne) {
        has_flown_ = has_flown_ || flying_s_ > config_.min_flight_s;
        rest_s_ = ground_s_ = 0.0f;
    } else {
        // A step in the voltage is no rest (a logger's power-off sample reads 1 V low).
        const bool steady = fabsf(voltage_v - last_voltage_v_) <= 0.05f;
        rest_s_ = fabsf(true_a) <= config_.rest_capacity_max_current_a && steady ? rest_s_ + dt_s : 0.0f;
        ground_s_ += dt_s;
    }
    last_voltage_v_ = voltage_v;
    // Read about once a second (an inversion of the curve: bisection).
    if (has_flown_ && rest_s_ >= config_.rest_capacity_min_rest_s && (++rest_reads_ & 15u) == 0u) {
        const float soc_rest = CapacityEkf::soc_at_rest_voltage(ocv_, voltage_v + true_a * r0);
        const float drop = start_soc_ - soc_rest;
        // The curve reads the mean cell; like capacity_ah, report what the weakest holds.
        if (drop >= config_.rest_capacity_min_soc_drop) status_.rest_capacity_ah = weakest_cell_ah(charge_total_ah_ / drop);
        // A filter whose prediction stays far from a resting pack has lost it: its
        // polarisation held an ohmic drop its R0 never measured (a log sampled once a
        // second), so the landing's step read as charge and the gate then refused every
        // resting sample (an ArduPilot 3S pack resting at 3.50 V per cell read 53 % full for
        // minutes). At rest the voltage is the state of charge: each filter is set to it,
        // its capacity and polarisation kept.
        if (fabsf(tracking_.ekf.status().innovation_v) > kLostAtRestVPerCell * static_cast<float>(cells_)) {
            for (Branch* b : branches) b->ekf.shift_soc(soc_rest - b->ekf.status().soc);
            landing_soc_ = 2.0f;  // what the rest reads is shown, whichever way it moved
        }
    }
    if (airborne) {
        flying_s_ += dt_s;
        flying_energy_j_ += voltage_v * true_charge_a * dt_s;
        charge_since_takeoff_ah_ += true_charge_a * dt_s / 3600.0f;
    }
    // A pack gains no charge on the ground: after a landing the state of charge shown stays
    // at most the last loaded sample's (the samples a landing is held through already see
    // the step) until a rest has set the filters (a 3S pack had gone from 32 % to 64 % in the
    // sample after its failsafe landing, and MAVLink sent it).
    float soc = es.soc;
    if (flying) landing_soc_ = soc;
    if (has_flown_ && soc > landing_soc_) soc = landing_soc_;
    status_.soc = clampf(soc, 0.0f, 1.0f);
    status_.capacity_ah = weakest_cell_ah(health().capacity_ah);
    // Scaled as the capacity is (the weak cell's deficit taken as known), and the systematic
    // part that grows with the charge drawn (Config); held on the ground after a flight,
    // where the capacity is not learnt either.
    if (airborne || !has_flown_) {
        const float filter_sigma_ah = weakest_cell_ah(health().sigma_capacity_ah);
        const float systematic_ah = config_.capacity_sigma_fraction_of_charge * charge_total_ah_;
        status_.sigma_capacity_ah = sqrtf(filter_sigma_ah * filter_sigma_ah + systematic_ah * systematic_ah);
    }
    status_.measured_resistance_ohm = rs.valid ? rs.resistance_now_ohm : 0.0f;
    status_.measured_resistance_sigma_ohm = rs.valid ? rs.sigma_now_ohm : 0.0f;
    status_.resistance_measured = rs.valid;
    status_.polarisation_ohm = es.polarisation_ohm * tracking_.scale;
    status_.polarisation_current_a = tracking_.polarisation_current_a;
    status_.mean_power_w = flying_s_ > 0.0f ? flying_energy_j_ / flying_s_ : 0.0f;

    // Flight-time solves, round robin, a bounded number of steps per update.
    if (status_.mean_power_w > 0.0f && flying_s_ > 1.0f) {
        if (solver_.done()) start_solve();
        // A log slower than 8 Hz works a whole solve an update, so that a round of solves
        // takes no longer than at the reference logger's 68 ms (11 steps an update, a round
        // every 1.22 s): at 5 Hz a round had taken 3.6 s and a warning, three rounds, 11 s
        // (docs/estimator.md, thirty-eighth session).
        const int steps = usual_dt_s_ >= 0.125f ? config_.solver_steps : config_.solver_steps_per_update;
        if (solver_.advance(ocv_, steps)) finish_solve();
    }
    if (status_.time_valid) {
        // Between refreshes the remaining time runs down with the clock.
        status_.remaining_time_s = maxf(0.0f, end_s_ - flying_s_);
        status_.remaining_energy_wh = maxf(0.0f, total_wh_ - flying_energy_j_ / 3600.0f);
    }
}

float JointEstimator::other_cells_ah(float mean_cell_ah) const {
    // The pack voltage shows the mean cell, which already holds the weak cell's share: the
    // others hold mean / (1 − d/N), the weak one (1 − d) times that (d: its deficit against
    // the others). Scaling the mean by (1 − d) alone had counted the weak cell twice.
    return mean_cell_ah / (1.0f - weakest_deficit_ / static_cast<float>(cells_));
}

float JointEstimator::weakest_cell_ah(float mean_cell_ah) const {
    return other_cells_ah(mean_cell_ah) * (1.0f - weakest_deficit_);
}

float JointEstimator::fuse_with_prior(bool valid, float measured_ohm, float sigma_ohm, float* sigma_out) const {
    // Inverse-variance combination with the configured value: a steady hover excites too
    // little to trust the differences alone. sigma_out may be null.
    const float prior_ohm = rated_.internal_resistance_ohm;
    const float prior_sigma = config_.resistance_prior_fraction * prior_ohm;
    // The squares compared, not the sigmas: a configured R of 1e-19 Ω squares to 0 or to a
    // weight past float's range, and an infinite weight made R0 NaN (an OCV table index).
    const float prior_var = prior_sigma * prior_sigma;
    const float measured_var = sigma_ohm * sigma_ohm;
    constexpr float kMinVar = 1e-30f;
    if (valid && measured_var > kMinVar && prior_var > kMinVar) {
        const float wp = 1.0f / prior_var;
        const float we = 1.0f / measured_var;
        if (sigma_out) *sigma_out = sqrtf(1.0f / (wp + we));
        return (wp * prior_ohm + we * measured_ohm) / (wp + we);
    }
    if (sigma_out) *sigma_out = valid ? sigma_ohm : prior_sigma;
    return valid ? measured_ohm : prior_ohm;
}

void JointEstimator::start_solve() {
    // The remaining time follows the tracking filter, the verdict's four solves the verdict
    // filter, the energy the health one.
    const Branch& b = solve_ == kSolveRemaining ? tracking_ : solve_ == kSolveHealth ? health_branch() : verdict_branch();
    const CapacityEkf::Status& es = b.ekf.status();
    // The filter sees the mean cell; with a weak cell named, the solver steps the others
    // down and the weak one, a fraction (1 − deficit) of them, beside them.
    const float share = weakest_deficit_ > 0.0f ? 1.0f / static_cast<float>(cells_) : 0.0f;
    const float q = other_cells_ah(es.capacity_ah);
    const float ratio = 1.0f - weakest_deficit_;
    const float r_total = status_.effective_resistance_ohm + es.polarisation_ohm * b.scale;
    // A healthy pack: rated resistance, and the polarisation the state holds at it.
    const float r_rated = rated_.internal_resistance_ohm + es.polarisation_ohm;
    // The charge at take-off: as the filter read it then, at rest, or as the present
    // estimate sees it.
    const float soc_takeoff = takeoff_soc_valid_ ? b.takeoff_soc
                                                 : clampf(es.soc + charge_since_takeoff_ah_ / es.capacity_ah, 0.0f, 1.0f);
    if (solve_ == kSolveRemaining) {
        solve_power_w_ = status_.mean_power_w;
        solve_started_s_ = flying_s_;
    }
    const float p = solve_power_w_;
    const float v_min = config_.min_voltage_v;
    const int n = config_.solver_steps;
    // One call with the arguments chosen (five calls of eight arguments had cost flash).
    float soc = soc_takeoff, capacity_ah = q, r = r_total, cell_share = share, cell_ratio = ratio;
    switch (solve_) {
        case kSolveRemaining: soc = clampf(es.soc, 0.0f, 1.0f); break;
        case kSolveTotal:
        case kSolveHealth: break;
        case kSolveExpected:
            capacity_ah = rated_.capacity_ah;
            r = r_rated;
            cell_share = 0.0f;  // a healthy pack: no weak cell
            cell_ratio = 1.0f;
            break;
        case kSolveCapacityOnly: r = r_rated; break;
        default:
            capacity_ah = rated_.capacity_ah;
            cell_share = 0.0f;
            cell_ratio = 1.0f;
            break;
    }
    solver_.start(soc, capacity_ah, r, p, v_min, n, cell_share, cell_ratio);
}

void JointEstimator::finish_solve() {
    const PowerTimeSolver::Result& r = solver_.result();
    results_[solve_] = r.time_s;
    if (solve_ == kSolveRemaining) {
        // The result is the time left when the solve began: it runs down from then, and the
        // previous result keeps its own start until this one replaces it.
        end_s_ = solve_started_s_ + r.time_s;
        const float fade_ah = config_.health_time_fade_fraction * rated_.capacity_ah;
        if (health_end_s_ > 0.0f && fade_ah > 0.0f) {
            const float w = config_.health_time_share * maxf(0.0f, 1.0f - charge_since_takeoff_ah_ / fade_ah);
            end_s_ += w * (health_end_s_ - end_s_);
        }
    }
    // The energy from the health filter's solve from take-off: the remaining energy is that
    // less what has flowed since. Energy is mostly capacity × state of charge, which the
    // health filter reads better early; the remaining time follows the tracking filter and
    // leans on this solve only early in a flight (docs/estimator.md, ninth and fourteenth sessions).
    // Without a verdict filter the verdict's total is the health filter's own solve.
    const bool shared = !config_.verdict.enabled;
    if (solve_ == kSolveHealth || (shared && solve_ == kSolveTotal)) {
        total_wh_ = r.energy_wh;
        health_end_s_ = r.time_s;
    }
    solve_ = static_cast<uint8_t>(solve_ + 1);
    if (shared && solve_ == kSolveHealth) solve_ = kSolveCount;
    if (solve_ < kSolveCount) return;
    solve_ = kSolveRemaining;

    // A full round is in: publish, then judge.
    status_.time_valid = true;
    status_.total_time_s = results_[kSolveTotal];
    status_.expected_time_s = results_[kSolveExpected];
    const float expected = results_[kSolveExpected];
    if (flying_s_ < config_.min_flight_s || !(expected > 0.0f)) return;
    const bool is_short = results_[kSolveTotal] < config_.short_flight_fraction * expected;
    short_count_ = is_short ? short_count_ + 1 : 0;
    if (short_count_ >= config_.persistence) {
        status_.short_flight = true;
        uint8_t cause = kCauseNone;
        if (results_[kSolveCapacityOnly] < config_.cause_fraction * expected) cause |= kCauseCapacity;
        if (results_[kSolveResistanceOnly] < config_.cause_fraction * expected) cause |= kCauseResistance;
        if (cause == kCauseNone) {
            cause = results_[kSolveCapacityOnly] <= results_[kSolveResistanceOnly] ? kCauseCapacity : kCauseResistance;
        }
        status_.cause = cause;
    } else if (short_count_ == 0) {
        status_.short_flight = false;
        status_.cause = kCauseNone;
    }
}

}  // namespace core
}  // namespace battsim
