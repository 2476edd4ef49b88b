// The newer estimator's parts against hand-computed values, and the whole of it against
// a pack with injected truth. The plant here is an equivalent circuit (OCV table, series
// resistance, one RC branch), not the Tremblay model the reference monitor runs.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/estimate/capacity_ekf.h"
#include "core/estimate/difference_resistance.h"
#include "core/estimate/joint_estimator.h"
#include "core/estimate/power_time_solver.h"
#include "core/model/ocv.h"
#include "core/numeric.h"
#include "ecm_plant.h"

using namespace battsim::core;

namespace {

using testplant::Lcg;
using testplant::lipo_table;
using testplant::Plant;

// The joint estimator with default settings on the LiPo table, for a 4S pack rated `rated`
// (health = false: the tracking filter alone, as before the health filter; correct =
// false: the health filter's SOC not corrected on the first measured R0).
JointEstimator table_estimator(const TremblayParams& rated, bool health = true, bool correct = true,
                               bool from_takeoff = true, float health_time_share = JointEstimator::Config{}.health_time_share,
                               float max_sample_gap_s = JointEstimator::Config{}.max_sample_gap_s, bool verdict = true) {
    JointEstimator::Config jc;
    jc.verdict.enabled = verdict;
    jc.ocv = lipo_table();
    jc.health_time_share = health_time_share;
    jc.max_sample_gap_s = max_sample_gap_s;
    jc.health.enabled = health;
    jc.health.first_resistance_soc_correction = correct;
    jc.health.solves_from_takeoff_soc = from_takeoff;
    JointEstimator e;
    e.configure(jc, rated, 4);
    return e;
}

// table_estimator for a 1.5 Ah, 25 mΩ pack, started from rest at 16.68 V.
JointEstimator started_estimator() {
    TremblayParams rated;
    rated.capacity_ah = 1.5f;
    rated.internal_resistance_ohm = 0.025f;
    JointEstimator e = table_estimator(rated);
    e.start(16.68f, 0.0f);
    return e;
}

// A racing-style power profile: bursts and cruise, constant power per phase.
float demand_w(float t_s) {
    const int phase = static_cast<int>(t_s / 3.0f) % 5;
    const float p[5] = {250.0f, 420.0f, 180.0f, 520.0f, 300.0f};
    return p[phase];
}

}  // namespace

TEST_CASE("OCV table interpolates and inverts", "[joint]") {
    OcvCurve c;
    c.configure(lipo_table(), 4, TremblayParams{});
    CHECK(c.voltage_v(1.0f) == Approx(16.68f));
    CHECK(c.voltage_v(0.0f) == Approx(13.2f));
    CHECK(c.voltage_v(0.55f) == Approx(4.0f * (3.81f + 0.5f * (3.86f - 3.81f))));
    CHECK(c.slope_v_per_soc(0.55f) == Approx(4.0f * 0.05f / 0.1f).epsilon(1e-3));
    CHECK(c.soc_at_voltage(4.0f * 3.835f) == Approx(0.55f).margin(1e-4));
    CHECK(c.soc_at_voltage(20.0f) == 1.0f);
    CHECK(c.soc_at_voltage(1.0f) == 0.0f);
    OcvCurve m;  // without a table: the model's no-load curve
    m.configure(OcvTable{}, 4, TremblayParams{});
    CHECK_FALSE(m.from_table());
    CHECK(m.voltage_v(1.0f) == Approx(16.94f).margin(1e-3));
}

TEST_CASE("Difference resistance: one step by hand, then recovery under noise", "[joint][truth]") {
    DifferenceResistanceEstimator r;
    DifferenceResistanceEstimator::Config cfg;
    cfg.lag_s = 0.13f;
    cfg.min_excitation_a2 = 0.0f;
    r.configure(cfg);
    // Samples every 67 ms: 10 A, 10 A, then 30 A. The third pairs with the first
    // (134 ms ≥ 130 ms): ΔI = 20 A, ΔV = −0.6 V → 0.03 ohm once three pairs exist.
    uint64_t t = 0;
    const float i_seq[6] = {10, 10, 30, 30, 10, 10};
    for (int k = 0; k < 6; ++k, t += 67000) r.update(t, 16.0f - 0.03f * i_seq[k], i_seq[k]);
    CHECK(r.status().valid);
    CHECK(r.status().resistance_ohm == Approx(0.03f).epsilon(1e-4));
    CHECK(r.status().sigma_ohm == Approx(0.0f).margin(1e-4));

    // Truth: 0.045 ohm, an RC branch of 0.015 ohm / 8 s, OCV sagging, 10 mV quantisation.
    Plant p{OcvCurve{}, 1.5f, 0.045f, 0.015f, 8.0f};
    p.ocv.configure(lipo_table(), 4, TremblayParams{});
    DifferenceResistanceEstimator e;
    e.configure(DifferenceResistanceEstimator::Config{});
    Lcg rng;
    t = 0;
    for (int k = 0; k < 1500; ++k, t += 67000) {
        const float i = 10.0f + 30.0f * static_cast<float>((k / 9) % 3) + 2.0f * rng.next();
        const float v = std::round(p.step(i, 0.067f) * 100.0f) / 100.0f;
        e.update(t, v, i);
    }
    // The lag lets ~1.6 % of the RC branch in (1 − e^(−0.134/8)); well inside 5 %.
    CHECK(e.status().resistance_ohm == Approx(0.045f).epsilon(0.05));
    CHECK(e.status().sigma_ohm < 0.002f);
}

TEST_CASE("Difference resistance: a wrong first estimate is not locked in by the garbled-reading gate", "[joint][truth]") {
    // A take-off whose pairs read 10 mΩ, then a 20 mΩ pack whose only steps are a 30 A climb
    // every 90 s: each climb's pair outweighs the forgetting window and sits far from 10 mΩ.
    // A gate judging by a window that had forgotten everything kept 10 mΩ for good; the gate
    // judges only while the window holds its bar (min_excitation_a2), so the climbs count.
    DifferenceResistanceEstimator::Config c;
    c.trend_sigma_per_s = 0.002f;
    DifferenceResistanceEstimator e;
    e.configure(c);
    Lcg rng;
    for (int k = 0; k < 18000; ++k) {  // 30 min at 10 Hz
        const double t = 0.1 * k;
        double i, r = 0.020;
        if (t < 10.0) {
            i = t < 0.5 ? 100.0 * t : 50.0;
            r = 0.010;
        } else {
            i = std::fmod(t - 2.0, 90.0) >= 87.0 ? 80.0 : 50.0;
        }
        const double v = 16.0 - r * i + 0.002 * rng.next();
        e.update(static_cast<uint64_t>(std::llround(t * 1e6)), static_cast<float>(v), static_cast<float>(i));
        if (k == 50) {
            INFO("after the take-off: " << e.status().resistance_ohm);
            CHECK(e.status().resistance_ohm == Approx(0.010).epsilon(0.1));
        }
    }
    CHECK(e.status().resistance_ohm == Approx(0.020).epsilon(0.05));
}

TEST_CASE("Difference resistance: a garbled reading in a busy racing window is skipped", "[joint][truth]") {
    // Racing throttle moves the current every sample (steps of a few amperes around 30 A), so
    // a minute's window holds ΣΔI² far above one 170 A glitch's pair: the pair does not
    // outweigh the window, but it is far more than a hundred of its mean pairs. Without that
    // bar the glitch's two pairs (no sag for 170 A) pulled the 20 mΩ estimate to 11.2 mΩ,
    // still 13.8 mΩ 30 s later.
    DifferenceResistanceEstimator::Config c;
    DifferenceResistanceEstimator e, clean;
    e.configure(c);
    clean.configure(c);
    Lcg rng;
    float sxx_a2 = 0.0f;
    float previous_a = 30.0f;
    for (int k = 0; k < 1200; ++k) {  // 120 s at 10 Hz; the glitch at 90 s
        const double t = 0.1 * k;
        const double i = 30.0 + 8.0 * std::sin(0.7 * t) + 15.0 * rng.next();
        const double v = 16.0 - 0.020 * i + 0.002 * rng.next();
        const uint64_t t_us = static_cast<uint64_t>(std::llround(t * 1e6));
        clean.update(t_us, static_cast<float>(v), static_cast<float>(i));
        const bool glitch = k == 900;
        e.update(t_us, static_cast<float>(v), glitch ? 200.0f : static_cast<float>(i));
        const float di_a = static_cast<float>(i) - previous_a;  // the window as the estimator forgets it
        if (k < 900) sxx_a2 = sxx_a2 * (1.0f - 0.1f / c.memory_s) + (std::fabs(di_a) >= c.min_step_a ? di_a * di_a : 0.0f);
        previous_a = static_cast<float>(i);
        if (k == 905) {
            INFO("R0 after the glitch " << e.status().resistance_ohm << ", clean " << clean.status().resistance_ohm);
            CHECK(e.status().resistance_ohm == Approx(clean.status().resistance_ohm).epsilon(0.01));
        }
    }
    // The case the bar is for: the glitch's ΔI² (≈ 170²) is below the window's ΣΔI².
    INFO("window sum " << sxx_a2 << " A²");
    CHECK(sxx_a2 > 1.5f * 170.0f * 170.0f);
    CHECK(e.status().resistance_ohm == Approx(0.020).epsilon(0.03));
}

TEST_CASE("Difference resistance: a garbled reading before the window holds its bar is judged by the configured R", "[joint][truth]") {
    // A take-off to 40 A and throttle steps of ±10 A on a 20 mΩ pack configured at 20 mΩ; one
    // reading garbled to 100 A a second after the take-off, the voltage untouched.
    // The window is still below its bar (400 A²), so there is no estimate to judge by: the
    // configured R is the reference, one-sided. Without that bar R0 read 1.7 mΩ at 8 s and
    // 6.5 mΩ at 20 s (clean 20.0 mΩ at both).
    auto fly = [](double r_ohm, double configured_ohm, int glitch_k) {
        DifferenceResistanceEstimator::Config c;
        c.initial_resistance_ohm = static_cast<float>(configured_ohm);
        DifferenceResistanceEstimator e;
        e.configure(c);
        Lcg rng;
        std::vector<float> r_at;
        for (int k = 0; k < 300; ++k) {  // 30 s at 10 Hz; take-off at 2 s
            const double t = 0.1 * k;
            // A take-off ramp over 3 s (steps of 1.3 A: the window stays below its bar), then
            // throttle steps of 20 A every second.
            const double flown_a = t < 2.0 ? 0.5 : t < 5.0 ? 0.5 + 13.0 * (t - 2.0) : 40.0 + (std::fmod(t, 2.0) < 1.0 ? 10.0 : -10.0);
            const double i = k == glitch_k ? 100.0 : flown_a + 0.2 * rng.next();
            const double v = 16.0 - r_ohm * flown_a + 0.002 * rng.next();
            e.update(static_cast<uint64_t>(std::llround(t * 1e6)), static_cast<float>(v), static_cast<float>(i));
            if (k == 80 || k == 200) r_at.push_back(e.status().resistance_ohm);
        }
        return r_at;
    };
    const std::vector<float> clean = fly(0.020, 0.020, -1), glitched = fly(0.020, 0.020, 30);
    INFO("R0 at 8 s and 20 s: glitched " << glitched[0] << ", " << glitched[1] << "; clean " << clean[0] << ", " << clean[1]);
    CHECK(glitched[0] == Approx(clean[0]).epsilon(0.02));
    CHECK(glitched[1] == Approx(clean[1]).epsilon(0.02));
    // One-sided: a pack at twice its rating is measured from the take-off's first pair, as
    // without the bar, and one at half its rating as well (it sags 2.5 times the bar's fifth).
    const std::vector<float> aged = fly(0.040, 0.020, -1), better = fly(0.010, 0.020, -1);
    INFO("aged " << aged[0] << ", better " << better[0]);
    CHECK(aged[0] == Approx(0.040).epsilon(0.03));
    CHECK(better[0] == Approx(0.010).epsilon(0.03));
}

TEST_CASE("Difference resistance: current-sensor noise does not let the garbled-reading gate lock the estimate low", "[joint][truth]") {
    // A 10 mΩ pack in a 20 A hover at 10 Hz, with ±1.5 A of current-sensor noise the voltage
    // does not share (it biases the fit low, as errors in a regressor do), and a 30 A climb
    // for 3 s every minute. A two-sided gate (the thirty-sixth session's band with the
    // mean-pair bar) skipped the climbs once the noise had pulled R under half the truth, and
    // the noise pairs alone then took R to 0.01 mΩ by 180 s; one-sided, the climbs (which sag
    // more than R says) always count. Also at 5 Hz.
    for (double rate_hz : {10.0, 5.0}) {
        DifferenceResistanceEstimator::Config c;
        c.initial_resistance_ohm = 0.010f;
        DifferenceResistanceEstimator e;
        e.configure(c);
        Lcg rng;
        float lowest_after_120_ohm = 1.0f;
        for (int k = 0; k < static_cast<int>(600.0 * rate_hz); ++k) {
            const double t = k / rate_hz;
            const double flown_a = std::fmod(t, 60.0) >= 57.0 ? 50.0 : 20.0;
            const double v = 16.0 - 0.010 * flown_a + 0.002 * rng.next();
            const double i = flown_a + 1.5 * rng.next();
            e.update(static_cast<uint64_t>(std::llround(t * 1e6)), static_cast<float>(v), static_cast<float>(i));
            if (t > 120.0 && e.status().valid) lowest_after_120_ohm = std::min(lowest_after_120_ohm, e.status().resistance_ohm);
        }
        INFO(rate_hz << " Hz: lowest R0 after 120 s " << lowest_after_120_ohm << ", at 600 s " << e.status().resistance_ohm);
        CHECK(lowest_after_120_ohm > 0.004f);
        CHECK(e.status().resistance_ohm > 0.005f);
    }
}

TEST_CASE("Difference resistance: a climb's first pairs are judged by the configured R until the fit stands", "[joint][truth]") {
    // The hover estimator's settings (lag 0.13 s, 0.2 A steps, a 10 A² bar) on a 20 mΩ pack
    // configured at 60 mΩ: a steady 20 A hover with a 45 A climb every 30 s. The climb's first
    // pair alone passes the bar; judged then against half of R, which is still the configured
    // 60 mΩ, every climb's pairs (20 mΩ) were skipped, and R stayed at 60 mΩ for about 300 s.
    // Until the fit stands on three pairs the configured R's 0.15 is the floor.
    const DifferenceResistanceEstimator::Config hover = JointEstimator::Config{}.hover_resistance;
    for (double rate_hz : {10.0, 5.0}) {
        DifferenceResistanceEstimator::Config c = hover;
        c.initial_resistance_ohm = 0.060f;
        DifferenceResistanceEstimator e;
        e.configure(c);
        Lcg rng;
        for (int k = 0; k <= static_cast<int>(90.0 * rate_hz); ++k) {
            const double t = k / rate_hz;
            const double i = std::fmod(t, 30.0) >= 25.0 ? 45.0 : 20.0;
            const double v = 16.0 - 0.020 * i + 0.002 * rng.next();
            e.update(static_cast<uint64_t>(std::llround(t * 1e6)), static_cast<float>(v), static_cast<float>(i));
        }
        INFO(rate_hz << " Hz: R0 after 90 s " << e.status().resistance_ohm);
        CHECK(e.status().resistance_ohm == Approx(0.020).epsilon(0.05));
    }
}

TEST_CASE("Difference resistance: a warming pack's falling resistance, window mean and trend", "[joint][truth]") {
    // R0 falls linearly from 0.020 to 0.014 ohm over 120 s of racing (a pack warming from
    // cold). The 60 s window's mean lags by tens of seconds; the trend fit reads now.
    Plant p{OcvCurve{}, 1.5f, 0.020f, 0.004f, 1.5f};
    p.ocv.configure(lipo_table(), 4, TremblayParams{});
    DifferenceResistanceEstimator plain, trend;
    DifferenceResistanceEstimator::Config cfg;
    plain.configure(cfg);
    cfg.trend_sigma_per_s = 0.002f;
    trend.configure(cfg);
    Lcg rng;
    uint64_t t_us = 0;
    const float dt = 0.067f;
    float r_true = 0.0f;
    for (int k = 0; k * dt < 120.0f; ++k, t_us += 67000) {
        r_true = 0.020f - 0.006f * (k * dt) / 120.0f;
        p.r0_ohm = r_true;
        const float i = 12.0f + 25.0f * static_cast<float>((k / 15) % 3) + 1.5f * rng.next();
        const float v = std::round(p.step(i, dt) * 100.0f) / 100.0f;
        plain.update(t_us, v, i);
        trend.update(t_us, v, i);
    }
    INFO("true " << r_true << " window " << plain.status().resistance_ohm << " now " << trend.status().resistance_now_ohm);
    CHECK(plain.status().resistance_now_ohm == plain.status().resistance_ohm);  // no trend: now = the window's
    CHECK(plain.status().resistance_ohm > 1.08f * r_true);                      // the window lags
    CHECK(trend.status().resistance_now_ohm == Approx(r_true).epsilon(0.04));
    CHECK(trend.status().resistance_ohm == plain.status().resistance_ohm);     // the window mean is kept
    CHECK(trend.status().sigma_now_ohm > trend.status().sigma_ohm);             // extrapolating costs precision
}

TEST_CASE("Power-time solver against closed forms", "[joint]") {
    // Flat OCV of 16 V, R 0.05 ohm, 400 W: I solves 0.05·I² − 16·I + 400 = 0 → I = 26.79 A
    // (smaller root); 1 Ah from SOC 1 to 0 takes 1·3600/26.79 = 134.4 s; the loaded voltage
    // 14.66 V never reaches a 13 V minimum.
    OcvTable flat;
    flat.points = 2;
    flat.cell_voltage_v[0] = flat.cell_voltage_v[1] = 4.0f;
    OcvCurve c;
    c.configure(flat, 4, TremblayParams{});
    PowerTimeSolver s;
    s.start(1.0f, 1.0f, 0.05f, 400.0f, 13.0f, 50);
    int calls = 0;
    while (!s.advance(c, 7)) ++calls;
    CHECK(calls == 7);  // 50 steps at 7 per call: done in the eighth call
    const double i = (16.0 - std::sqrt(256.0 - 4 * 0.05 * 400)) / 0.1;
    CHECK(s.result().time_s == Approx(3600.0 / i).epsilon(1e-4));
    CHECK(s.result().energy_wh == Approx(400.0 / i).epsilon(1e-4));
    CHECK_FALSE(s.result().cutoff);
    // Linear OCV 12→16.8 V over SOC, no resistance, 100 W, minimum 14.4 V: the cutoff is at
    // SOC 0.5; the time is ∫ Q·3600/(P/V) dsoc = 3600·Q/P·∫V dsoc over [0.5, 1].
    OcvTable lin;
    lin.points = 2;
    lin.cell_voltage_v[0] = 3.0f;
    lin.cell_voltage_v[1] = 4.2f;
    c.configure(lin, 4, TremblayParams{});
    s.start(1.0f, 2.0f, 0.0f, 100.0f, 14.4f, 100);
    while (!s.advance(c, 100)) {
    }
    CHECK(s.result().cutoff);
    CHECK(s.result().charge_ah == Approx(1.0f).epsilon(1e-3));
    CHECK(s.result().time_s == Approx(3600.0 * 2.0 / 100.0 * 0.5 * (16.8 + 14.4) / 2.0).epsilon(2e-3));
    const PowerTimeSolver::Result no_delay = s.result();
    // A 5 s failsafe delay: the same crossing, then 5 s more at 100 W (0.1389 Wh) and at
    // the crossing's current, 100 W / 14.4 V = 6.94 A (9.65 mAh); kept across starts.
    s.set_cutoff_delay_s(5.0f);
    s.start(1.0f, 2.0f, 0.0f, 100.0f, 14.4f, 100);
    while (!s.advance(c, 100)) {
    }
    CHECK(s.result().time_s == Approx(no_delay.time_s + 5.0f).epsilon(1e-6));
    CHECK(s.result().energy_wh == Approx(no_delay.energy_wh + 100.0 * 5.0 / 3600.0).epsilon(1e-5));
    CHECK(s.result().charge_ah == Approx(no_delay.charge_ah + 100.0 / 14.4 * 5.0 / 3600.0).epsilon(2e-4));
    // Where the power can no longer be met (R 0.5 ohm, 100 W: below E = 14.14 V), the flight
    // goes on at the last current that met it: 4 steps over the same linear curve put E at
    // 14.4 V (I = (14.4 − √(14.4² − 200))/1 = 11.69 A) and then 13.2 V (infeasible).
    s.set_cutoff_delay_s(0.0f);
    s.start(1.0f, 2.0f, 0.5f, 100.0f, 1.0f, 4);
    while (!s.advance(c, 4)) {
    }
    const PowerTimeSolver::Result collapse = s.result();
    CHECK(collapse.cutoff);
    s.set_cutoff_delay_s(5.0f);
    s.start(1.0f, 2.0f, 0.5f, 100.0f, 1.0f, 4);
    while (!s.advance(c, 4)) {
    }
    const double i_last = 14.4 - std::sqrt(14.4 * 14.4 - 200.0);
    CHECK(s.result().charge_ah - collapse.charge_ah == Approx(i_last * 5.0 / 3600.0).epsilon(1e-3));
    CHECK(s.result().time_s == Approx(collapse.time_s + 5.0f).epsilon(1e-6));
    // No crossing, no delay: the flat pack above ran out of charge, not voltage.
    s.start(1.0f, 1.0f, 0.05f, 400.0f, 13.0f, 50);
    c.configure(flat, 4, TremblayParams{});
    while (!s.advance(c, 50)) {
    }
    CHECK(s.result().time_s == Approx(3600.0 / i).epsilon(1e-4));
}

TEST_CASE("Capacity EKF recovers an injected capacity from the OCV", "[joint][truth]") {
    for (float factor : {0.75f, 1.0f, 1.15f}) {
        Plant p{OcvCurve{}, 1.5f * factor, 0.03f, 0.0f, 5.0f};
        p.ocv.configure(lipo_table(), 4, TremblayParams{});
        CapacityEkf ekf;
        ekf.configure(CapacityEkf::Config{}, 1.5f);
        ekf.start(1.0f);
        Lcg rng;
        for (int k = 0; k < 3000; ++k) {  // 200 s at ~20 A: ~1.1 Ah
            const float i = 20.0f + 10.0f * rng.next();
            const float v = p.step(i, 0.067f) + 0.01f * rng.next();
            ekf.predict(i, 0.067f);
            ekf.correct(v + 0.03f * i, 0.0f, 0.0f, p.ocv);
            if (p.soc < 0.15f) break;
        }
        INFO("true capacity " << 1.5f * factor);
        CHECK(ekf.status().capacity_ah == Approx(1.5f * factor).epsilon(0.03));
        CHECK(ekf.status().soc == Approx(p.soc).margin(0.03));
    }
}

namespace {
struct FlightResult {
    JointEstimator::Status at20;
    JointEstimator::Status end;
    float true_total_s = 0;
    float true_energy_after20_wh = 0;  // delivered from 20 % of the flight to the cutoff
    bool warned = false;
    uint8_t cause = 0;
    float first_warning_s = -1.0f;  // flight time of the first short-flight warning (−1: none)
};

// The pack and the flight: rp_ohm, tau_s are the plant's one RC branch at resistance
// factor 1; hover_w > 0 flies a hover at that power with gusts of ±9 % (2.5 rad/s) and
// ±3 % (0.47 rad/s) instead of the racing profile.
struct Flight {
    float capacity_factor = 1.0f;
    float resistance_factor = 1.0f;
    bool health = true;
    float rp_ohm = 0.008f;
    float tau_s = 6.0f;
    float hover_w = 0.0f;
    bool first_resistance_correction = true;
    float configured_resistance_factor = 1.0f;  // the estimator's rated R0: × 25 mΩ
    float rest_before_s = 0.0f;        // on the ground at 0.3 A before the take-off
    bool solves_from_takeoff_soc = true;
    float health_time_share = JointEstimator::Config{}.health_time_share;
    bool verdict = true;  // the verdict's own filter
    float glitch_at_s = -1.0f;  // one current reading of 100 A at this flight time (a garbled read)
};

// Flies the plant at the demand profile until the loaded voltage reaches 13.3 V and
// records the estimator at 20 % of that (true) flight time.
FlightResult fly(const Flight& f) {
    const float capacity_factor = f.capacity_factor, resistance_factor = f.resistance_factor;
    const float rp_ohm = f.rp_ohm, tau_s = f.tau_s;
    auto demand = [&f](float t_s) {
        if (!(f.hover_w > 0.0f)) return demand_w(t_s);
        return f.hover_w * (1.0f + 0.09f * std::sin(2.5f * t_s) + 0.03f * std::sin(0.47f * t_s));
    };
    const float dt = 0.067f;
    TremblayParams plant_rated;
    plant_rated.capacity_ah = 1.5f;
    plant_rated.internal_resistance_ohm = 0.025f;
    TremblayParams rated = plant_rated;
    rated.internal_resistance_ohm *= f.configured_resistance_factor;
    auto make_plant = [&]() {
        Plant p{OcvCurve{}, 1.5f * capacity_factor, 0.025f * resistance_factor, rp_ohm * resistance_factor, tau_s};
        p.ocv.configure(lipo_table(), 4, plant_rated);
        return p;
    };
    // First pass: the true flight time, and the energy delivered up to each step.
    Plant truth = make_plant();
    for (float tt = 0.0f; tt < f.rest_before_s; tt += dt) truth.step(0.3f, dt);  // as in the second pass
    float t = 0.0f, i = 20.0f;
    std::vector<double> energy_wh;
    double e_wh = 0.0;
    while (t < 2000.0f) {
        const float v = truth.step(i, dt);
        if (v < 13.3f) break;
        e_wh += static_cast<double>(v) * i * dt / 3600.0;
        energy_wh.push_back(e_wh);
        i = demand(t) / v;
        t += dt;
    }
    FlightResult out;
    out.true_total_s = t;
    const size_t at20 = static_cast<size_t>(0.2 * static_cast<double>(energy_wh.size()));
    out.true_energy_after20_wh = static_cast<float>(e_wh - energy_wh[at20]);
    // Second pass: the estimator rides along.
    Plant p = make_plant();
    JointEstimator e =
        table_estimator(rated, f.health, f.first_resistance_correction, f.solves_from_takeoff_soc, f.health_time_share,
                        JointEstimator::Config{}.max_sample_gap_s, f.verdict);
    e.start(p.ocv.voltage_v(1.0f), 0.0f);
    Lcg rng;
    float v = p.ocv.voltage_v(1.0f);
    uint64_t t_us = 0;
    // The ground before the take-off, where the pack rests (the first pass rested too).
    for (float tt = 0.0f; tt < f.rest_before_s; tt += dt, t_us += 67000) {
        v = p.step(0.3f, dt);
        const float vm = std::round((v + 0.005f * rng.next()) * 100.0f) / 100.0f;
        e.update(t_us, vm, 0.3f + 0.05f * rng.next(), dt, false);
    }
    i = demand(0.0f) / v;
    bool recorded = false;
    for (float tt = 0.0f; tt < out.true_total_s; tt += dt, t_us += 67000) {
        v = p.step(i, dt);
        const float vm = std::round((v + 0.005f * rng.next()) * 100.0f) / 100.0f;
        const bool glitch = f.glitch_at_s >= 0.0f && tt >= f.glitch_at_s && tt < f.glitch_at_s + dt;
        e.update(t_us, vm, glitch ? 100.0f : i + 0.05f * rng.next(), dt, true);
        if (out.first_warning_s < 0.0f && e.status().short_flight) out.first_warning_s = tt;
        if (!recorded && tt >= 0.2f * out.true_total_s) {
            out.at20 = e.status();
            recorded = true;
        }
        i = demand(tt) / v;
    }
    out.end = e.status();
    out.warned = out.at20.short_flight;
    out.cause = out.at20.cause;
    return out;
}
}  // namespace

TEST_CASE("Joint estimator on injected packs: capacity, resistance, warnings by 20 %", "[joint][truth]") {
    // This plant's one 6 s branch is neither filter's shape: the health filter (3 s and a
    // 30 s share) reads the healthy pack 7 % low at 20 % where the tracking filter alone read
    // 4 % low. A pack 1.5 × as resistive reads 17 % low, the same as with its true R0
    // configured from take-off (until the first-R0 correction it read 7.5 % low: the R0
    // error before the first measurement had offset the shape's); the tracking filter
    // alone reads it 8 % low with its shape since the eleventh session (3 s and a 0.4 share
    // at 30 s; 24 % low with the earlier single 5 s one), both for want of the first-R0
    // correction and with this plant's branch between its two.
    const FlightResult healthy = fly({});
    CHECK(healthy.at20.capacity_ah == Approx(1.5f).epsilon(0.08));
    const FlightResult warmer = fly({1.0f, 1.5f});
    CHECK(warmer.at20.capacity_ah == Approx(1.5f).epsilon(0.2));
    Flight known;
    known.resistance_factor = known.configured_resistance_factor = 1.5f;
    const float known_ah = fly(known).at20.capacity_ah;
    INFO("1.5 × resistance: capacity at 20 % " << warmer.at20.capacity_ah << " Ah, " << known_ah << " with R0 known");
    CHECK(warmer.at20.capacity_ah == Approx(known_ah).epsilon(0.01));
    const FlightResult warmer_tracking = fly({1.0f, 1.5f, false});
    CHECK(warmer_tracking.at20.capacity_ah == Approx(1.5f).epsilon(0.12));  // the tracking filter alone
    CHECK(warmer_tracking.at20.remaining_time_s > 0.0f);
    CHECK(healthy.at20.resistance_ohm == Approx(0.025f).epsilon(0.06));
    CHECK_FALSE(healthy.warned);
    // Remaining time at 20 %, as a share of the true flight; remaining energy (the health
    // filter's, at the mean power) against what the plant delivers from there to the cutoff.
    CHECK(std::fabs(healthy.at20.remaining_time_s - 0.8f * healthy.true_total_s) < 0.06f * healthy.true_total_s);
    INFO("energy after 20 %: estimated " << healthy.at20.remaining_energy_wh << " Wh, true " << healthy.true_energy_after20_wh);
    CHECK(healthy.at20.remaining_energy_wh == Approx(healthy.true_energy_after20_wh).epsilon(0.05));

    const FlightResult weak = fly({0.7f, 1.0f});
    CHECK(weak.at20.capacity_ah == Approx(1.05f).epsilon(0.10));  // at 20 %: still converging; accuracy is scored by `battsim score`
    INFO("weak pack, energy after 20 %: estimated " << weak.at20.remaining_energy_wh << " Wh, true " << weak.true_energy_after20_wh);
    CHECK(weak.at20.remaining_energy_wh == Approx(weak.true_energy_after20_wh).epsilon(0.05));
    CHECK(weak.warned);
    CHECK((weak.cause & JointEstimator::kCauseCapacity) != 0);
    CHECK((weak.cause & JointEstimator::kCauseResistance) == 0);

    const FlightResult resistive = fly({1.0f, 2.2f});
    CHECK(resistive.at20.resistance_ohm == Approx(0.055f).epsilon(0.06));
    INFO("resistive: total " << resistive.at20.total_time_s << " expected " << resistive.at20.expected_time_s);
    CHECK(resistive.warned == (resistive.at20.total_time_s < 0.8f * resistive.at20.expected_time_s));
    // A check of its cause here never ran: this racing profile's bursts take a resistive pack
    // to the cutoff at once (2.2 ×: 55 s against 206 s), before a verdict (8 s of flight and
    // `persistence` rounds) is made by 20 % of it (11 s). A hover 2.5 × as
    // resistive flies 0.68 of a healthy hover (204 s against 300 s) and must be warned for its
    // resistance. Not by 20 % of the flight: the hover's R0 stands in only after
    // resistance_settle_s (40 s), and the verdict then needs `persistence` rounds (first
    // warned at about 60 s, for a 41 s deadline; docs/estimator.md, thirty-fifth session).
    Flight hover;
    hover.hover_w = 250.0f;
    hover.rest_before_s = 10.0f;
    const FlightResult hover_healthy = fly(hover);
    hover.resistance_factor = 2.5f;
    const FlightResult hover_resistive = fly(hover);
    INFO("hover: true " << hover_resistive.true_total_s << " s against " << hover_healthy.true_total_s
                        << " s healthy; first warned at " << hover_resistive.first_warning_s << " s");
    REQUIRE(hover_resistive.true_total_s < 0.75f * hover_healthy.true_total_s);
    CHECK_FALSE(hover_healthy.end.short_flight);
    CHECK(hover_resistive.at20.resistance_ohm == Approx(0.0625f).epsilon(0.06));
    CHECK(hover_resistive.first_warning_s > 0.0f);
    CHECK(hover_resistive.first_warning_s < 0.4f * hover_resistive.true_total_s);
    CHECK(hover_resistive.end.short_flight);
    CHECK((hover_resistive.end.cause & JointEstimator::kCauseResistance) != 0);
    CHECK((hover_resistive.end.cause & JointEstimator::kCauseCapacity) == 0);
}


TEST_CASE("Joint estimator: one garbled current reading of 100 A moves neither the resistance nor the capacity", "[joint][truth]") {
    // A register read garbled to 100 A with no sag to match pairs, on each side, a large
    // current step with no voltage step: weighted by ΔI² they had pulled R0 to a sixth and
    // the capacity to half, with a short-flight warning to the landing (glitch at 120 s).
    Flight hover;
    hover.hover_w = 250.0f;
    hover.rest_before_s = 10.0f;
    const FlightResult clean = fly(hover);
    for (float at_s : {30.0f, 120.0f}) {
        hover.glitch_at_s = at_s;
        const FlightResult glitched = fly(hover);
        INFO("glitch at " << at_s << " s: end R0 " << glitched.end.resistance_ohm << " Ω (clean " << clean.end.resistance_ohm
                          << "), capacity " << glitched.end.capacity_ah << " Ah (clean " << clean.end.capacity_ah << ")");
        CHECK(glitched.end.resistance_ohm == Approx(clean.end.resistance_ohm).epsilon(0.05));
        CHECK(glitched.end.capacity_ah == Approx(clean.end.capacity_ah).epsilon(0.05));
        CHECK_FALSE(glitched.end.short_flight);
        CHECK(glitched.first_warning_s < 0.0f);
    }
    // The racing profile's bursts fill the window with large steps: there the glitch's pair
    // is no larger than the window and counts, but it moves little.
    Flight racing;
    const FlightResult racing_clean = fly(racing);
    racing.glitch_at_s = 30.0f;
    const FlightResult racing_glitched = fly(racing);
    INFO("racing: end R0 " << racing_glitched.end.resistance_ohm << " Ω (clean " << racing_clean.end.resistance_ohm
                           << "), capacity " << racing_glitched.end.capacity_ah << " Ah (clean " << racing_clean.end.capacity_ah << ")");
    CHECK(racing_glitched.end.resistance_ohm == Approx(racing_clean.end.resistance_ohm).epsilon(0.05));
    CHECK(racing_glitched.end.capacity_ah == Approx(racing_clean.end.capacity_ah).epsilon(0.05));
    CHECK(racing_glitched.warned == racing_clean.warned);
}

TEST_CASE("Joint estimator: early in a flight the remaining time leans on the health filter", "[joint][truth]") {
    // A pack at 70 % of its rated capacity: at 20 % of the flight the tracking filter still
    // holds part of the rated capacity; the health filter's solve from take-off reads the
    // loss sooner, and half of it (fading with the charge drawn) brings the remaining time
    // closer to what the plant flies.
    Flight weak;
    weak.capacity_factor = 0.7f;
    const FlightResult blended = fly(weak);
    weak.health_time_share = 0.0f;
    const FlightResult tracking = fly(weak);
    const float truth_s = 0.8f * blended.true_total_s;
    INFO("remaining at 20 %: blended " << blended.at20.remaining_time_s << " s, tracking " << tracking.at20.remaining_time_s
                                       << " s, true " << truth_s << " s");
    CHECK(std::fabs(blended.at20.remaining_time_s - truth_s) < std::fabs(tracking.at20.remaining_time_s - truth_s));
    // Between the two filters' readings: the health filter's solve from take-off less the
    // time flown (the published total is one refresh behind the blend, hence the margin).
    const float health_s = blended.at20.total_time_s - 0.2f * blended.true_total_s;
    CHECK(blended.at20.remaining_time_s < tracking.at20.remaining_time_s);
    CHECK(blended.at20.remaining_time_s > health_s - 2.0f);
    // The lean has faded by the end (over half the rated capacity drawn): both agree there.
    CHECK(blended.end.remaining_time_s == Approx(tracking.end.remaining_time_s).margin(0.5f));
    // The verdict and the energy do not read the published remaining time.
    CHECK(blended.at20.total_time_s == tracking.at20.total_time_s);
    CHECK(blended.at20.remaining_energy_wh == tracking.at20.remaining_energy_wh);
}

TEST_CASE("Joint estimator: the verdict is refreshed once a round and warns after `persistence` short ones", "[joint]") {
    // A pack at 40 % of its rated capacity flown at a steady 300 W: every verdict reads short
    // once there is one. A round is the six solves (five without the verdict filter), each
    // solver_steps / solver_steps_per_update updates rounded up at most (a solve that meets
    // the cutoff before the table's end stops there), so the first warning comes
    // (persistence − 1) rounds after the first short verdict: by hand, at most
    // 2 × 6 × ceil(32 / 11) = 36 updates for persistence 3 against 1 at 11 steps per update
    // (a round of 1.22 s at 68 ms), and 2 × 5 × 32 / 8 = 40 without the verdict filter at 8
    // (the twentieth session's 1.35 s). On this pack the solves from take-off run into the
    // cutoff, so a round is a little shorter.
    const auto first_warning_update = [](int steps_per_update, int persistence, bool verdict) {
        TremblayParams rated;
        rated.capacity_ah = 1.5f;
        rated.internal_resistance_ohm = 0.025f;
        JointEstimator::Config jc;
        jc.ocv = lipo_table();
        jc.solver_steps = 32;
        jc.solver_steps_per_update = steps_per_update;
        jc.persistence = persistence;
        jc.verdict.enabled = verdict;
        JointEstimator e;
        e.configure(jc, rated, 4);
        Plant p{OcvCurve{}, 0.6f, 0.025f, 0.008f, 6.0f};
        p.ocv.configure(lipo_table(), 4, rated);
        e.start(p.ocv.voltage_v(1.0f), 0.0f);
        float v = p.ocv.voltage_v(1.0f);
        for (int k = 0; k < 3000; ++k) {
            const float i = 300.0f / v;
            v = p.step(i, 0.067f);
            e.update(static_cast<uint64_t>(k) * 67000u, std::round(v * 100.0f) / 100.0f, i, 0.067f, true);
            if (e.status().short_flight) return k;
        }
        return -1;
    };
    const int p1 = first_warning_update(11, 1, true), p3 = first_warning_update(11, 3, true);
    const int old1 = first_warning_update(8, 1, false), old3 = first_warning_update(8, 3, false);
    INFO("11 steps per update, verdict filter: first short verdict at update " << p1 << ", warning at " << p3
         << "; 8 steps, none: " << old1 << ", " << old3);
    REQUIRE(p1 > 0);
    REQUIRE(old1 > 0);
    CHECK(p3 - p1 <= 36);
    CHECK(p3 - p1 >= 28);
    CHECK(old3 - old1 <= 40);
    CHECK(old3 - old1 >= 32);
    // The defaults are the first pair: 11 steps per update, three verdicts, a verdict filter.
    CHECK(JointEstimator::Config{}.solver_steps_per_update == 11);
    CHECK(JointEstimator::Config{}.persistence == 3);
    CHECK(JointEstimator::Config{}.verdict.enabled);
}

TEST_CASE("Joint estimator: the verdict's own filter leans short and changes nothing it reports", "[joint][truth]") {
    // On a plant whose polarisation builds over 40 s (the simulator's slow branch), the
    // verdict filter's slow part (150 s) builds slower still, so early in the flight it
    // reads part of that sag as charge drawn: the verdict's flight time from take-off comes
    // out shorter than the health filter's. That lean is what warns a short pack sooner on
    // the simulated suites (docs/estimator.md, twenty-first session); on this plant both
    // warn a 70 % pack at the first verdicts after learning begins. The capacity and state
    // of charge come from the health and tracking filters, the same with or without it; the
    // energy from the health filter's own solve, refreshed on a longer round with it.
    for (const float capacity_factor : {1.0f, 0.7f}) {
        Flight f;
        f.capacity_factor = capacity_factor;
        f.tau_s = 40.0f;
        const FlightResult with = fly(f);
        f.verdict = false;
        const FlightResult without = fly(f);
        INFO("capacity × " << capacity_factor << ": total from take-off at 20 % " << with.at20.total_time_s
                           << " s with the verdict filter, " << without.at20.total_time_s << " s without; first warning "
                           << with.first_warning_s << " s, " << without.first_warning_s << " s; flight "
                           << with.true_total_s << " s");
        CHECK(with.at20.total_time_s < without.at20.total_time_s);
        CHECK(with.at20.capacity_ah == without.at20.capacity_ah);
        CHECK(with.at20.soc == without.at20.soc);
        CHECK(with.at20.remaining_energy_wh == Approx(without.at20.remaining_energy_wh).epsilon(0.02));
        CHECK(with.warned == (capacity_factor < 0.8f));
        CHECK(without.warned == (capacity_factor < 0.8f));
    }
    // An undegraded pack is not warned at any time, racing or hovering.
    CHECK(fly({}).first_warning_s < 0.0f);
    Flight hover;
    hover.hover_w = 170.0f;
    CHECK(fly(hover).first_warning_s < 0.0f);
}

TEST_CASE("Joint estimator: a disabled filter's stand-in brings its own take-off charge", "[joint]") {
    // A pack at 60 % rests 10 s, then flies at 300 W. With the health filter disabled (the
    // tracking filter stands in for the energy's solve) or the verdict filter disabled (the
    // health filter stands in for the verdict's), the solves from the take-off charge read the
    // stand-in's own: the energy and the flight time from take-off agree with the present
    // charge carried back within the polarisation's few % (a stand-in starting from a full
    // pack's charge read about 60 % more).
    for (int disabled = 0; disabled < 2; ++disabled) {
        const auto fly_partial = [disabled](bool from_takeoff) {
            TremblayParams rated;
            rated.capacity_ah = 1.5f;
            rated.internal_resistance_ohm = 0.025f;
            JointEstimator::Config jc;
            jc.ocv = lipo_table();
            jc.health.enabled = disabled != 0;
            jc.verdict.enabled = disabled != 1;
            jc.health.solves_from_takeoff_soc = from_takeoff;
            JointEstimator e;
            e.configure(jc, rated, 4);
            Plant p{OcvCurve{}, 1.5f, 0.025f, 0.008f, 6.0f};
            p.ocv.configure(lipo_table(), 4, rated);
            p.soc = 0.6f;
            float v = p.ocv.voltage_v(0.6f);
            e.start(v, 0.0f);
            uint64_t t_us = 0;
            for (int k = 0; k < 150; ++k, t_us += 67000u) {
                v = p.step(0.0f, 0.067f);
                e.update(t_us, std::round(v * 100.0f) / 100.0f, 0.0f, 0.067f, false);
            }
            for (int k = 0; k < 600; ++k, t_us += 67000u) {
                const float i = 300.0f / v;
                v = p.step(i, 0.067f);
                e.update(t_us, std::round(v * 100.0f) / 100.0f, i, 0.067f, true);
            }
            return e.status();
        };
        const JointEstimator::Status takeoff = fly_partial(true), present = fly_partial(false);
        INFO((disabled == 0 ? "health" : "verdict")
             << " filter disabled: energy " << takeoff.remaining_energy_wh << " Wh from the take-off charge, "
             << present.remaining_energy_wh << " Wh from the present one; total " << takeoff.total_time_s << " s, "
             << present.total_time_s << " s");
        REQUIRE(present.remaining_energy_wh > 0.0f);
        CHECK(takeoff.remaining_energy_wh == Approx(present.remaining_energy_wh).epsilon(0.12));
        CHECK(takeoff.total_time_s == Approx(present.total_time_s).epsilon(0.12));
    }
}

TEST_CASE("Joint estimator: a logging gap's charge at the mean of the currents either side; learning held after it", "[joint]") {
    // 45 s at 40 A and a steady 15.0 V (sampled every 67 ms), a 2.5 s gap, then 10 A. The
    // gap's charge is counted at (40 + 10) / 2 = 25 A, so the flight's mean power after it is
    // (600 W · 45.02 s + 15 V · 25 A · 2.5 s) / 47.52 s; the sample's own 10 A would give
    // 15 V · 10 A · 2.5 s for the gap instead.
    const auto run = [](float max_gap_s, float* capacity_after_gap, float* capacity_hold_end, float* capacity_later) {
        TremblayParams rated;
        rated.capacity_ah = 1.5f;
        rated.internal_resistance_ohm = 0.025f;
        JointEstimator e = table_estimator(rated, true, true, true, JointEstimator::Config{}.health_time_share, max_gap_s);
        e.start(16.68f, 0.0f);
        uint64_t t_us = 0;
        const int n = 672;  // 45.024 s: past resistance_settle_s, so capacity is being learnt
        for (int k = 0; k < n; ++k, t_us += 67000) e.update(t_us, 15.0f, 40.0f, 0.067f, true);
        t_us += 2500000;
        e.update(t_us, 15.0f, 10.0f, 2.5f, true);
        const float mean_w = e.status().mean_power_w;
        *capacity_after_gap = e.status().capacity_ah;
        for (int k = 0; k < 60; ++k) e.update(t_us += 67000, 15.0f, 10.0f, 0.067f, true);  // 4.0 s
        *capacity_hold_end = e.status().capacity_ah;
        for (int k = 0; k < 60; ++k) e.update(t_us += 67000, 15.0f, 10.0f, 0.067f, true);  // to 8.0 s
        *capacity_later = e.status().capacity_ah;
        return mean_w;
    };
    float c_gap = 0, c_hold = 0, c_later = 0;
    const float handled_w = run(JointEstimator::Config{}.max_sample_gap_s, &c_gap, &c_hold, &c_later);
    const double flown_s = 672 * 0.067 + 2.5;
    CHECK(handled_w == Approx((600.0 * 672 * 0.067 + 15.0 * 25.0 * 2.5) / flown_s).epsilon(1e-4));
    // Within gap_hold_s (5 s) of the gap capacity is not learnt; afterwards it is again.
    CHECK(c_hold == c_gap);
    CHECK(c_later != c_hold);
    float u_gap = 0, u_hold = 0, u_later = 0;
    const float unhandled_w = run(1.0e9f, &u_gap, &u_hold, &u_later);
    CHECK(unhandled_w == Approx((600.0 * 672 * 0.067 + 15.0 * 10.0 * 2.5) / flown_s).epsilon(1e-4));
    CHECK(u_hold != u_gap);  // nothing held without a recognised gap
}

TEST_CASE("Joint estimator: a log's own slow rate is no gap; a gap is long against it", "[joint]") {
    // An ArduPilot log may hold the battery once a second or slower: those intervals are the
    // log's, not missing samples (until the fifteenth session they raised a sensor fault on
    // every sample, and with the gap hold capacity would never have been learnt).
    JointEstimator e = started_estimator();
    uint64_t t_us = 0;
    bool any_gap = false;
    float capacity_50s = 0.0f;
    for (int k = 1; k <= 60; ++k) {
        e.update(t_us += 1000000, 15.0f, 40.0f, 1.0f, true);
        any_gap = any_gap || e.status().sample_gap;
        if (k == 50) capacity_50s = e.status().capacity_ah;
    }
    CHECK_FALSE(any_gap);
    CHECK(e.status().capacity_ah != capacity_50s);  // learning, not held
    // 2.5 s is within three of its 1 s intervals; 4 s is not.
    e.update(t_us += 2500000, 15.0f, 40.0f, 2.5f, true);
    CHECK_FALSE(e.status().sample_gap);
    e.update(t_us += 1000000, 15.0f, 40.0f, 1.0f, true);
    e.update(t_us += 4000000, 15.0f, 40.0f, 4.0f, true);
    CHECK(e.status().sample_gap);
    e.update(t_us += 1000000, 15.0f, 40.0f, 1.0f, true);
    CHECK_FALSE(e.status().sample_gap);
    // At the reference logger's 67 ms the fixed 0.75 s bar decides.
    JointEstimator fast = started_estimator();
    t_us = 0;
    for (int k = 0; k < 100; ++k) fast.update(t_us += 67000, 15.0f, 40.0f, 0.067f, true);
    fast.update(t_us += 700000, 15.0f, 40.0f, 0.7f, true);
    CHECK_FALSE(fast.status().sample_gap);
    fast.update(t_us += 800000, 15.0f, 40.0f, 0.8f, true);
    CHECK(fast.status().sample_gap);
}

TEST_CASE("Joint estimator: one low sample in the air is no landing; a held one is", "[joint]") {
    // The monitor holds a flight through a throttle dip (landed_hold_s); the estimator's own
    // offset-corrected take-off threshold had ended the flight on a single sample below it,
    // restarting the flight's clock, mean power and solves (the dissertation's flight 32 at
    // 186.8 s; CMU M100 flight 24 at 38 s, which then read 0 s remaining for 6 s).
    JointEstimator e = started_estimator();
    uint64_t t_us = 0;
    for (int k = 0; k < 300; ++k) e.update(t_us += 67000, 15.0f, 20.0f, 0.067f, true);  // 20.1 s at 300 W
    REQUIRE(e.status().time_valid);
    const float remaining_s = e.status().remaining_time_s;
    REQUIRE(remaining_s > 0.0f);
    // One sample at 0.5 A (the monitor still flying), then 20 A again.
    e.update(t_us += 67000, 15.5f, 0.5f, 0.067f, true);
    CHECK(e.status().flying);
    CHECK_FALSE(e.status().loaded);  // the fits do not learn from it
    e.update(t_us += 67000, 15.0f, 20.0f, 0.067f, true);
    CHECK(e.status().flying);
    CHECK(e.status().time_valid);
    // The clock ran on: the remaining time fell by the two samples' 0.134 s at most
    // (a refreshed solve may move it a little), and the mean power counts the dip.
    CHECK(e.status().remaining_time_s == Approx(remaining_s - 0.134f).margin(2.0));
    CHECK(e.status().mean_power_w == Approx((300.0 * 301 + 15.5 * 0.5) / 302).epsilon(1e-3));
    // Below the threshold for longer than the hold (1 s, the monitor's default): landed, even
    // while the monitor (its own threshold on the measured current) still says flying.
    for (int k = 0; k < 14; ++k) e.update(t_us += 67000, 15.6f, 0.3f, 0.067f, true);  // 0.938 s
    CHECK(e.status().flying);
    e.update(t_us += 67000, 15.6f, 0.3f, 0.067f, true);  // 1.005 s
    CHECK_FALSE(e.status().flying);
    // A new take-off after it starts a new flight: its mean power is its own. Until this
    // flight's first round of solves is in, the last flight's remaining time and energy carry
    // on (they had been zeroed: 0 s left, a critical beep, for 1-2 s after every re-take-off).
    const float before_s = e.status().remaining_time_s, before_wh = e.status().remaining_energy_wh;
    REQUIRE(before_s > 60.0f);
    REQUIRE(before_wh > 5.0f);
    float lowest_s = before_s, lowest_wh = before_wh;
    for (int k = 0; k < 30; ++k) {
        e.update(t_us += 67000, 15.0f, 30.0f, 0.067f, true);
        REQUIRE(e.status().time_valid);
        lowest_s = std::fmin(lowest_s, e.status().remaining_time_s);
        lowest_wh = std::fmin(lowest_wh, e.status().remaining_energy_wh);
    }
    CHECK(e.status().flying);
    CHECK(e.status().mean_power_w == Approx(450.0f).epsilon(1e-3));
    CHECK(lowest_s > 0.5f * before_s);
    CHECK(lowest_wh > 0.5f * before_wh);
}

TEST_CASE("Capacity EKF: predict adds the given state-of-charge variance", "[joint]") {
    // P00 ← F P Fᵀ + q² dt + extra: two predicts that differ only in the extra variance
    // differ by exactly that in σ²(soc), and not at all in the state.
    CapacityEkf::Config cfg;
    CapacityEkf a, b;
    a.configure(cfg, 1.5f);
    b.configure(cfg, 1.5f);
    a.start(0.8f);
    b.start(0.8f);
    a.predict(30.0f, 2.5f);
    b.predict(30.0f, 2.5f, false, 1.0f, 4.0e-4f);
    const float va = a.status().sigma_soc * a.status().sigma_soc;
    const float vb = b.status().sigma_soc * b.status().sigma_soc;
    CHECK(vb - va == Approx(4.0e-4f).epsilon(1e-3));
    CHECK(b.status().soc == a.status().soc);
    CHECK(b.status().capacity_ah == a.status().capacity_ah);
}

TEST_CASE("Joint estimator: a hover on a pack more resistive than configured, SOC corrected on the first R0", "[joint][truth]") {
    // 1.8 × the configured resistance, hovering at 150 W: the gusts are too small for the
    // short-lag estimate, so R0 is measured only after 40 s, and until then the filters
    // compensate with 25 mΩ where the pack has 45 and read the extra ~0.2 V of sag as
    // charge drawn.
    // The correction is first order in the filter's gains, so the reading should be the one
    // an estimator configured with the true R0 gets (1.421 against 1.423 Ah here); without
    // it the pack reads 32 % high.
    for (float rf : {1.0f, 1.8f}) {
        Flight f;
        f.resistance_factor = rf;
        f.hover_w = 150.0f;
        const FlightResult with = fly(f);
        f.first_resistance_correction = false;
        const FlightResult without = fly(f);
        f.configured_resistance_factor = rf;
        const FlightResult known = fly(f);
        INFO("resistance × " << rf << ": capacity at 20 % " << with.at20.capacity_ah << " Ah with the correction, "
                             << without.at20.capacity_ah << " without, " << known.at20.capacity_ah << " with R0 known");
        CHECK(with.at20.capacity_ah == Approx(1.5f).epsilon(0.06));
        CHECK(with.at20.capacity_ah == Approx(known.at20.capacity_ah).epsilon(0.015));
        if (rf > 1.5f) CHECK(without.at20.capacity_ah > 1.25f * 1.5f);
        CHECK_FALSE(with.warned);
    }
}

// Not run by default (hidden tag): capacity error at 20 % of the flight on one-branch
// plants of other shapes than either filter's, tracking filter alone against the health
// filter; docs/estimator.md quotes it. Run: build/tests/unit_tests "[survey]" -s
TEST_CASE("Survey: capacity at 20 % on one-branch plants", "[.][survey]") {
    const float packs[5][2] = {{1.0f, 1.0f}, {0.7f, 1.0f}, {0.8f, 1.0f}, {1.0f, 1.5f}, {0.8f, 1.5f}};
    for (float tau_s : {2.0f, 6.0f, 20.0f}) {
        for (float rp_ohm : {0.004f, 0.008f, 0.016f}) {
            for (bool health : {false, true}) {
                std::string row;
                for (const auto& pk : packs) {
                    const FlightResult r = fly({pk[0], pk[1], health, rp_ohm, tau_s});
                    char cell[32];
                    std::snprintf(cell, sizeof cell, " %+6.1f", 100.0f * (r.at20.capacity_ah / (1.5f * pk[0]) - 1.0f));
                    row += cell;
                }
                WARN("tau " << tau_s << " s, Rp " << rp_ohm << " ohm, " << (health ? "health " : "tracking") << row);
            }
        }
    }
}

TEST_CASE("OCV continued past full for a resting voltage above the table", "[joint]") {
    OcvCurve c;
    c.configure(lipo_table(), 4, TremblayParams{});
    // Top segment: (4.17 − 4.07) V per cell over 0.1 SOC; the slope at 1.0 is the central
    // difference over [0.99, 1.0]: 1 V per cell per unit SOC, 4 V for the pack.
    CHECK(CapacityEkf::soc_at_rest_voltage(c, 16.72f) == Approx(1.0f + (16.72f - 16.68f) / 4.0f).epsilon(1e-4));
    CHECK(CapacityEkf::soc_at_rest_voltage(c, 17.5f) == Approx(1.05f));  // capped
    CHECK(CapacityEkf::soc_at_rest_voltage(c, 4.0f * 3.835f) == Approx(0.55f).margin(1e-4));
}

namespace {
// The pack at rest on the ground for `seconds` drawing `true_a` while the sensor reads
// `offset_a` more; the EKF sees only the ground (offset learning, nothing else).
CapacityEkf::Status rest_with_offset(float start_soc, float true_a, float offset_a, float seconds) {
    OcvCurve ocv;
    ocv.configure(lipo_table(), 4, TremblayParams{});
    CapacityEkf ekf;
    ekf.configure(CapacityEkf::Config{}, 1.5f);
    ekf.start(start_soc + 0.003f);  // the resting voltage's own error
    Lcg rng;
    float soc = start_soc;
    const float dt = 0.067f;
    for (float t = 0.0f; t < seconds; t += dt) {
        soc -= true_a * dt / (3600.0f * 1.5f);
        const float v = std::round((ocv.voltage_v(soc) - 0.025f * true_a + 0.004f * rng.next()) * 1000.0f) / 1000.0f;
        const float measured = true_a + offset_a;
        ekf.predict(measured, dt, true, 0.2f);
        ekf.correct(v, measured, 0.0f, ocv, false, true);  // as the joint estimator does on the ground
    }
    return ekf.status();
}
}  // namespace

TEST_CASE("Capacity EKF learns a current-sensor offset from a pack at rest", "[joint][truth]") {
    // 90 s at 0.3 A on the steep top of the curve (4 V/SOC for the pack): 1.5 A more
    // would lower the pack 0.1 V, which the voltage does not show.
    const CapacityEkf::Status faulty = rest_with_offset(0.97f, 0.3f, 1.5f, 90.0f);
    INFO("offset " << faulty.offset_a << " ± " << faulty.sigma_offset_a);
    CHECK(faulty.offset_a == Approx(1.5f).margin(0.3f));
    CHECK(faulty.offset_a > 3.0f * faulty.sigma_offset_a);
    // A clean sensor: the idle draw is real current, not offset.
    const CapacityEkf::Status clean = rest_with_offset(0.97f, 0.3f, 0.0f, 90.0f);
    INFO("offset " << clean.offset_a << " ± " << clean.sigma_offset_a);
    CHECK(std::fabs(clean.offset_a) < 0.3f);
    // A negative offset (the sensor reads low) is found just as well.
    const CapacityEkf::Status low = rest_with_offset(0.97f, 1.0f, -0.8f, 90.0f);
    CHECK(low.offset_a == Approx(-0.8f).margin(0.3f));
}

namespace {
struct GroundFlight {
    JointEstimator::Status on_ground;  // just before take-off
    JointEstimator::Status at20;
    float true_total_s = 0.0f;
    bool flew_on_ground = false;
};
// 60 s on the ground at 0.3 A, then the racing demand until the cutoff; the sensor reads
// `offset_a` high throughout. The monitor's own take-off flag (≥ 1 A measured) is what the
// estimator is handed, as in the Monitor.
GroundFlight fly_with_offset(float offset_a) {
    const float dt = 0.067f;
    TremblayParams rated;
    rated.capacity_ah = 1.5f;
    rated.internal_resistance_ohm = 0.025f;
    auto make_plant = [&]() {
        Plant p{OcvCurve{}, 1.5f, 0.025f, 0.008f, 6.0f};
        p.ocv.configure(lipo_table(), 4, rated);
        return p;
    };
    GroundFlight out;
    Plant truth = make_plant();
    float t = 0.0f, i = 0.3f;
    for (; t < 60.0f; t += dt) truth.step(0.3f, dt);
    float flight_s = 0.0f;
    i = demand_w(0.0f) / truth.ocv.voltage_v(truth.soc);
    while (flight_s < 2000.0f) {
        const float v = truth.step(i, dt);
        if (v < 13.3f) break;
        i = demand_w(flight_s) / v;
        flight_s += dt;
    }
    out.true_total_s = flight_s;

    Plant p = make_plant();
    JointEstimator e = table_estimator(rated);
    Lcg rng;
    uint64_t t_us = 0;
    float v = p.ocv.voltage_v(1.0f);
    for (float tt = 0.0f; tt < 60.0f; tt += dt, t_us += 67000) {
        v = p.step(0.3f, dt);
        const float vm = std::round((v + 0.003f * rng.next()) * 1000.0f) / 1000.0f;
        e.update(t_us, vm, 0.3f + offset_a, dt, 0.3f + offset_a >= 1.0f);
        if (tt > 45.0f && e.status().flying) out.flew_on_ground = true;
    }
    out.on_ground = e.status();
    i = demand_w(0.0f) / v;
    bool recorded = false;
    for (float tt = 0.0f; tt < out.true_total_s; tt += dt, t_us += 67000) {
        v = p.step(i, dt);
        const float vm = std::round((v + 0.003f * rng.next()) * 1000.0f) / 1000.0f;
        e.update(t_us, vm, i + offset_a + 0.05f * rng.next(), dt, true);
        if (!recorded && tt >= 0.2f * out.true_total_s) {
            out.at20 = e.status();
            recorded = true;
        }
        i = demand_w(tt) / v;
    }
    return out;
}
}  // namespace

TEST_CASE("Joint estimator with an offset current sensor: flagged, corrected, no ground flight", "[joint][truth]") {
    const GroundFlight faulty = fly_with_offset(1.5f);
    INFO("offset " << faulty.on_ground.current_offset_a << " ± " << faulty.on_ground.sigma_current_offset_a);
    CHECK(faulty.on_ground.current_offset_fault);
    CHECK(faulty.on_ground.current_offset_a == Approx(1.5f).margin(0.35f));
    CHECK_FALSE(faulty.flew_on_ground);  // 1.8 A measured on the ground is not a take-off
    INFO("remaining at 20 %: " << faulty.at20.remaining_time_s << " of " << 0.8f * faulty.true_total_s);
    CHECK(std::fabs(faulty.at20.remaining_time_s - 0.8f * faulty.true_total_s) < 0.08f * faulty.true_total_s);
    CHECK_FALSE(faulty.at20.short_flight);

    const GroundFlight clean = fly_with_offset(0.0f);
    CHECK_FALSE(clean.on_ground.current_offset_fault);
    CHECK(std::fabs(clean.on_ground.current_offset_a) < 0.3f);
    CHECK(std::fabs(clean.at20.remaining_time_s - 0.8f * clean.true_total_s) < 0.08f * clean.true_total_s);
}

namespace {

// A 1.5 Ah 4S plant and a joint estimator rated 1.5 Ah / 0.025 ohm, started full.
struct HoverBench {
    Plant plant;
    JointEstimator estimator;
};
HoverBench hover_bench(float r0_ohm, float r1_ohm, float tau_s, float start_current_a) {
    TremblayParams rated;
    rated.capacity_ah = 1.5f;
    rated.internal_resistance_ohm = 0.025f;
    HoverBench b{Plant{OcvCurve{}, 1.5f, r0_ohm, r1_ohm, tau_s}, table_estimator(rated)};
    b.plant.ocv.configure(lipo_table(), 4, rated);
    b.estimator.start(b.plant.ocv.voltage_v(1.0f), start_current_a);
    return b;
}

}  // namespace

TEST_CASE("Hover resistance: slow gusts too small for the short lag, recovered by the long one", "[joint][truth]") {
    // A steady hover at ~9 A with 0.8 A gusts (2.5 rad/s): consecutive samples differ by
    // far less than the short-lag estimator's 0.5 A minimum step.
    for (float r_true : {0.02f, 0.04f}) {
        HoverBench b = hover_bench(r_true, 0.0f, 6.0f, 0.0f);
        Plant& p = b.plant;
        JointEstimator& e = b.estimator;
        uint64_t t_us = 0;
        const float dt = 0.067f;
        Lcg rng;
        for (float t = 0.0f; t < 90.0f; t += dt, t_us += 67000) {
            const float i = 9.0f + 0.8f * std::sin(t * 2.5f) + 0.3f * std::sin(t * 0.47f);
            const float v = p.step(i, dt);
            e.update(t_us, v + 0.0012f * rng.next(), i, dt, true);
        }
        INFO("true " << r_true << " measured " << e.status().measured_resistance_ohm << " used " << e.status().resistance_ohm);
        CHECK(e.status().measured_resistance_ohm == Approx(r_true).epsilon(0.05));
        CHECK(e.status().resistance_ohm == Approx(r_true).epsilon(0.10));
    }
}

TEST_CASE("Hover resistance: the take-off step counts, the settling after it does not mislead", "[joint][truth]") {
    // 30 s on the ground at 0.9 A, a 0.2 s take-off ramp to 12 A, 3 s settling to a 9 A
    // hover (the current falls while the polarisation still builds: those pairs alone read
    // R0 ~20 % low), then a hover whose gusts stay under the minimum step. The voltage is
    // logged in 10 mV steps as in the raw format. The monitor confirms a take-off 0.5 s
    // after the current crosses 1 A, so only an estimator fed on the ground sees the step.
    const float r_true = 0.018f;
    HoverBench b = hover_bench(r_true, 0.006f, 1.5f, 0.9f);
    Plant& p = b.plant;
    JointEstimator& e = b.estimator;
    uint64_t t_us = 0;
    const float dt = 0.067f;
    const float takeoff_s = 30.0f;
    for (float t = 0.0f; t < takeoff_s + 80.0f; t += dt, t_us += 67000) {
        const float since = t - takeoff_s;
        float i = 0.9f;
        if (since >= 0.0f && since < 0.2f) i = 0.9f + 11.1f * since / 0.2f;  // the motors spin up
        else if (since >= 0.2f) i = since < 3.2f ? 12.0f - (since - 0.2f) : 9.0f + 0.05f * std::sin(t * 0.7f);
        const float v = std::round(p.step(i, dt) * 100.0f) / 100.0f;
        e.update(t_us, v, i, dt, since >= 0.5f);
    }
    INFO("true " << r_true << " measured " << e.status().measured_resistance_ohm);
    CHECK(e.status().measured_resistance_ohm == Approx(r_true).epsilon(0.06));
}

TEST_CASE("Capacity EKF: the polarisation scale multiplies the modelled polarisation voltage", "[joint]") {
    OcvCurve ocv;
    ocv.configure(lipo_table(), 4, TremblayParams{});
    CapacityEkf::Config cfg;
    cfg.polarisation_initial_ohm = 0.005f;
    CapacityEkf ekf;
    ekf.configure(cfg, 1.5f);
    ekf.start(0.5f);
    // OCV(0.5) = 4 × 3.81 = 15.24 V; predicted y = 15.24 − 0.005 Ω × 2 × 10 A = 15.14 V.
    ekf.correct(15.00f, 10.0f, 0.0f, ocv, false, false, 2.0f);
    CHECK(ekf.status().innovation_v == Approx(15.00f - 15.14f).margin(1e-4));
    // Scale 1 (the default): 15.24 − 0.05 = 15.19 V, from the state the first update left.
    CapacityEkf plain;
    plain.configure(cfg, 1.5f);
    plain.start(0.5f);
    plain.correct(15.00f, 10.0f, 0.0f, ocv, false, false);
    CHECK(plain.status().innovation_v == Approx(15.00f - 15.19f).margin(1e-4));
}

TEST_CASE("Capacity EKF: the state-of-charge gain it reports, and a shift of the state", "[joint]") {
    OcvCurve ocv;
    ocv.configure(lipo_table(), 4, TremblayParams{});
    CapacityEkf::Config cfg;
    cfg.voltage_sigma_v = 0.02f;
    cfg.ocv_soc_sigma = 0.01f;
    cfg.soc_sigma0 = 0.03f;
    CapacityEkf ekf;
    ekf.configure(cfg, 1.5f);
    ekf.start(0.5f);
    CHECK(ekf.status().soc_gain_per_v == 0.0f);  // no correction yet
    // Parameters held: only the state of charge is in H, so the gain is the scalar one,
    // k = P·h / (h²·P + σv² + (h·σ_ocv)²), with P = 0.03², h the curve's slope at 0.5.
    ekf.correct(15.20f, 0.0f, 0.0f, ocv, false, false);
    const float h = ekf.status().ocv_slope_v_per_soc;
    REQUIRE(h > 0.0f);
    const float p0 = 0.03f * 0.03f;
    const float k = p0 * h / (h * h * p0 + 0.02f * 0.02f + (h * 0.01f) * (h * 0.01f));
    CHECK(ekf.status().soc_gain_per_v == Approx(k).epsilon(1e-4));
    CHECK(ekf.status().soc == Approx(0.5f + k * ekf.status().innovation_v).epsilon(1e-5));
    const float soc = ekf.status().soc;
    ekf.shift_soc(0.02f);
    CHECK(ekf.status().soc == Approx(soc + 0.02f).epsilon(1e-6));
    ekf.shift_soc(2.0f);
    CHECK(ekf.status().soc == 1.05f);  // clamped as every update is
}

TEST_CASE("Capacity EKF on a warming pack: polarisation scaled with R0 keeps capacity", "[joint][truth]") {
    // Ohmic and polarisation resistance both fall by 40 % over the flight (the pack warms);
    // the estimator is given the true R0, as the difference estimator would measure it.
    float err_scaled = 0.0f, err_fixed = 0.0f;
    for (bool scaled : {true, false}) {
        Plant p{OcvCurve{}, 1.5f, 0.05f, 0.05f, 5.0f};
        p.ocv.configure(lipo_table(), 4, TremblayParams{});
        CapacityEkf ekf;
        ekf.configure(CapacityEkf::Config{}, 1.5f);
        ekf.start(1.0f);
        Lcg rng;
        float ip = 20.0f;
        p.v1 = 20.0f * p.r1_ohm;  // in flight already
        const float dt = 0.067f;
        const float r_start = 0.05f;
        for (int k = 0; k < 3000; ++k) {  // 200 s at ~20 A: ~1.1 Ah
            const float t = static_cast<float>(k) * dt;
            const float warm = 1.0f - 0.4f * std::fmin(1.0f, t / 150.0f);
            p.r0_ohm = r_start * warm;
            p.r1_ohm = 0.05f * warm;
            const float i = 20.0f + 10.0f * rng.next();
            const float v = p.step(i, dt) + 0.01f * rng.next();
            ip += (i - ip) * (1.0f - std::exp(-dt / 5.0f));
            ekf.predict(i, dt);
            ekf.correct(v + p.r0_ohm * i, ip, 0.0f, p.ocv, true, false, scaled ? p.r0_ohm / r_start : 1.0f);
            if (p.soc < 0.15f) break;
        }
        const float err = ekf.status().capacity_ah / 1.5f - 1.0f;
        (scaled ? err_scaled : err_fixed) = err;
    }
    INFO("capacity error, scaled " << err_scaled << ", fixed " << err_fixed);
    CHECK(std::fabs(err_scaled) < 0.05f);
    CHECK(err_fixed > 0.10f);  // the fixed polarisation reads the recovery as charge (+15 %)
}

namespace {
// A 4S pack rated 1.5 Ah / 0.025 ohm on the LiPo table, with the joint estimator riding
// along from a resting start; step() flies or rests it one 67 ms sample.
struct RestBench {
    TremblayParams rated;
    Plant plant;
    JointEstimator est;
    float v = 0.0f;
    uint64_t t_us = 0;
    static constexpr float kDt = 0.067f;
    RestBench(float capacity_ah, float r1_ohm, float tau_s) : plant{OcvCurve{}, capacity_ah, 0.025f, r1_ohm, tau_s} {
        rated.capacity_ah = 1.5f;
        rated.internal_resistance_ohm = 0.025f;
        plant.ocv.configure(lipo_table(), 4, rated);
        est = table_estimator(rated);
        v = plant.ocv.voltage_v(1.0f);
        est.start(v, 0.0f);
    }
    // power_w while flying, else a ground current.
    void step(bool flying, float power_w, float ground_a) {
        const float i = flying ? power_w / v : ground_a;
        v = plant.step(i, kDt);
        est.update(t_us, v, i, kDt, flying);
        t_us += 67000;
    }
};
}  // namespace

TEST_CASE("Capacity from the rests before and after a flight; a power-off glitch is no rest", "[joint][truth]") {
    // A 1.2 Ah pack rated 1.5 Ah flies 300 s at 150 W (about 0.8 Ah, 0.7 of its charge),
    // lands and rests 90 s: the OCV read at rest gives the charge drawn as a fall in SOC, so
    // capacity = charge / (SOC before − SOC after). The plant's RC branch (6 s) has relaxed
    // by then, so the reading is within the table interpolation's error.
    RestBench b(1.2f, 0.008f, 6.0f);
    for (float t = 0.0f; t < 410.0f; t += RestBench::kDt) {
        b.step(t >= 20.0f && t < 320.0f, 150.0f, 0.2f);
        if (t < 349.0f) CHECK(b.est.status().rest_capacity_ah == 0.0f);  // not before 30 s of rest
    }
    const float rest_ah = b.est.status().rest_capacity_ah;
    CHECK(rest_ah == Approx(1.2f).epsilon(0.03));
    // The logger's last sample at power-off reads a volt low: no rest, the value stays.
    b.est.update(b.t_us, b.v - 1.0f, -0.4f, RestBench::kDt, false);
    CHECK(b.est.status().rest_capacity_ah == rest_ah);
}

TEST_CASE("The current offset is not learnt after landing, where the voltage recovers", "[joint][truth]") {
    // A clean sensor, a flight, then 3 minutes on the ground: the plant's polarisation relaxes
    // and the voltage rises, which the offset filter would read as a negative offset.
    RestBench b(1.5f, 0.03f, 40.0f);  // a large, slow branch: 0.6 V at 20 A
    float offset_at_takeoff = 0.0f;
    for (float t = 0.0f; t < 500.0f; t += RestBench::kDt) {
        b.step(t >= 60.0f && t < 300.0f, 300.0f, 0.3f);
        if (t < 60.0f) offset_at_takeoff = b.est.status().current_offset_a;
    }
    CHECK(std::fabs(offset_at_takeoff) < 0.2f);  // what 60 s at 0.3 A can tell
    CHECK(b.est.status().current_offset_a == offset_at_takeoff);
    CHECK_FALSE(b.est.status().current_offset_fault);
}

TEST_CASE("Joint estimator: the verdict's solves and the energy start from the SOC read at rest before take-off", "[joint][truth]") {
    // In flight the present state of charge also carries the polarisation the filter does
    // not model, and the solves from take-off carried that back; the SOC the filter read off
    // the resting pack does not. Measured here: remaining energy at 20 % −1.6 against −2.0 %
    // (racing) and −3.1 against −3.8 % (hover). A monitor started in the air (no rest before
    // the take-off) keeps the present SOC carried back: the two settings then agree exactly.
    for (float hover_w : {0.0f, 150.0f}) {
        Flight f;
        f.hover_w = hover_w;
        f.rest_before_s = 30.0f;
        const FlightResult from_takeoff = fly(f);
        f.solves_from_takeoff_soc = false;
        const FlightResult present = fly(f);
        const float truth_wh = from_takeoff.true_energy_after20_wh;
        const float err_takeoff = from_takeoff.at20.remaining_energy_wh / truth_wh - 1.0f;
        const float err_present = present.at20.remaining_energy_wh / truth_wh - 1.0f;
        INFO("hover " << hover_w << " W: energy error at 20 % " << 100.0f * err_takeoff << " % from the take-off SOC, "
                      << 100.0f * err_present << " % from the present one");
        CHECK(std::fabs(err_takeoff) < 0.04f);
        CHECK(std::fabs(err_takeoff) < std::fabs(err_present));
        CHECK_FALSE(from_takeoff.warned);

        f.rest_before_s = 3.0f;  // below takeoff_soc_min_ground_s
        const FlightResult short_rest = fly(f);
        f.solves_from_takeoff_soc = true;
        const FlightResult short_rest_on = fly(f);
        CHECK(short_rest_on.at20.remaining_energy_wh == short_rest.at20.remaining_energy_wh);
        CHECK(short_rest_on.at20.total_time_s == short_rest.at20.total_time_s);
    }
}

TEST_CASE("Capacity standard error: the filter's and a systematic part in proportion to the charge drawn", "[joint]") {
    // Twin estimators on the same samples, one reporting the health filter's error alone
    // (fraction 0) and one with 0.08 of the charge drawn added in quadrature. The charge is
    // counted here from the plant's current; the estimator counts it less the small offset it
    // learns on the ground (a few mA here), so the two agree to within a per cent.
    TremblayParams rated;
    rated.capacity_ah = 1.5f;
    rated.internal_resistance_ohm = 0.025f;
    JointEstimator::Config jc;
    jc.ocv = lipo_table();
    jc.capacity_sigma_fraction_of_charge = 0.0f;
    JointEstimator alone;
    alone.configure(jc, rated, 4);
    jc.capacity_sigma_fraction_of_charge = 0.08f;
    JointEstimator with;
    with.configure(jc, rated, 4);
    Plant plant{OcvCurve{}, 1.4f, 0.025f, 0.008f, 6.0f};
    plant.ocv.configure(lipo_table(), 4, rated);
    float v = plant.ocv.voltage_v(1.0f);
    alone.start(v, 0.0f);
    with.start(v, 0.0f);
    const float dt = 0.067f;
    uint64_t t_us = 0;
    double charge_ah = 0.0;
    float sigma_at_landing = 0.0f;
    for (float t = 0.0f; t < 260.0f; t += dt) {
        const bool flying = t >= 20.0f && t < 200.0f;
        const float i = flying ? 200.0f / v : 0.2f;
        v = plant.step(i, dt);
        alone.update(t_us, v, i, dt, flying);
        with.update(t_us, v, i, dt, flying);
        t_us += 67000;
        charge_ah += static_cast<double>(i) * dt / 3600.0;
        const float s0 = alone.status().sigma_capacity_ah;
        const float s = with.status().sigma_capacity_ah;
        REQUIRE(alone.status().capacity_ah == with.status().capacity_ah);  // the estimate itself is untouched
        if (t < 200.0f) {
            const double sys = 0.08 * charge_ah;
            CHECK(static_cast<double>(s) * s - static_cast<double>(s0) * s0 == Approx(sys * sys).epsilon(1e-2).margin(1e-7));
            sigma_at_landing = s;
        } else if (t > 205.0f) {
            CHECK(s == sigma_at_landing);  // held on the ground, where nothing is learnt
        }
    }
    CHECK(charge_ah > 0.5);  // the systematic part dominates by then: 0.08 × 0.6 Ah ≈ 0.05 Ah
    CHECK(sigma_at_landing > 0.04f);
}


TEST_CASE("Joint estimator: a configured resistance too small to square in float is no prior, and no crash", "[joint][truth]") {
    // A config's R of 1e-19 Ω and below (accepted: the range is 0 … 100) squared its prior's
    // σ to 0 or to a weight past float's range: R0 became NaN, then the state of charge, and
    // the OCV table was indexed with it (a crash, found by a sweep of every config key).
    for (float factor : {4e-18f, 4e-24f, 4e-37f}) {
        Flight f;
        f.configured_resistance_factor = factor;  // × 25 mΩ
        const FlightResult r = fly(f);
        INFO("configured R " << 0.025f * factor << " Ω: R0 " << r.end.resistance_ohm << " Ω, capacity "
                             << r.end.capacity_ah << " Ah");
        REQUIRE(std::isfinite(r.end.resistance_ohm));
        REQUIRE(std::isfinite(r.end.capacity_ah));
        CHECK(r.end.resistance_ohm == Approx(0.025).epsilon(0.15));  // measured alone
        CHECK(r.end.capacity_ah == Approx(1.5).epsilon(0.15));
    }
    // And a NaN clamped is the range's low end, never a NaN to cast to an index.
    CHECK(battsim::core::clampf(NAN, 0.0f, 1.0f) == 0.0f);
    CHECK(battsim::core::clampf(-0.0f, 0.0f, 1.0f) == 0.0f);
    CHECK(battsim::core::clampf(2.0f, 0.0f, 1.0f) == 1.0f);
    CHECK(battsim::core::clampf(0.25f, 0.0f, 1.0f) == 0.25f);
}
