// The fit: its simulation equals the monitor, its parameter encoding round-trips, the
// Levenberg–Marquardt solver and its covariance are right, and a fit recovers known
// parameters from a generated log.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "host/fit/fit.h"
#include "host/fit/fit_job.h"
#include "host/replay.h"
#include "host/report/summary.h"
#include "test_fit_synthetic.h"

using namespace battsim;
using namespace battsim::host;
using namespace battsim::host::fit;

namespace {
const std::string kFlights = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/";

LoadedConfig modified_config() { return load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json"); }
}  // namespace

TEST_CASE("The fit's simulation is the monitor's model, bit for bit", "[fit][data]") {
    const LoadedConfig config = modified_config();
    ReaderOptions reader;
    reader.shunt = config.monitor.shunt;
    for (const char* flight : {"30.csv", "34.csv"}) {
        INFO(flight);
        const Trace t = load_trace(kFlights + flight, reader, config);
        ModelSpec spec = spec_from_config(config);
        SimResult sim;
        simulate(t, spec, InitialMode::Monitor, 0.0f, sim);
        size_t compared = 0;
        for (size_t k = 0; k < t.points.size(); ++k) {
            const TracePoint& p = t.points[k];
            if (!p.valid || !p.initialised) {
                REQUIRE(std::isnan(sim.model_v[k]));
                continue;
            }
            REQUIRE(sim.model_v[k] == p.monitor_model_v);
            ++compared;
        }
        CHECK(compared > 3000);
        CHECK(sim.initial_ah == t.monitor_initial_ah);
        // And the flight window's MAE is the replay summary's.
        ReplayOptions ro;
        ro.reader = reader;
        ro.config = config;
        const nlohmann::json summary = replay_log(kFlights + flight, ro);
        const ErrorStats s = error_stats(t, sim.model_v, Window::Flight);
        CHECK(round_sig(s.mae_v) == summary["flight"]["voltage_error_v"]["model"]["mean_abs"].get<double>());
    }
}

TEST_CASE("The monitor runs a fitted config's extensions as the fit simulated them", "[fit][extension][data]") {
    // Flight 29's config carries a current-sensor correction, two RC branches and self-heating;
    // flight 30's two RC branches and self-heating.
    for (const char* name : {"29", "30"}) {
        INFO(name);
        const std::string cfg = std::string(BATTSIM_SOURCE_DIR) + "/configs/fitted/pbms-flight" + name +
                                (std::string(name) == "29" ? "-dinogy1.json" : "-cnhl5.json");
        const LoadedConfig config = load_config_file(cfg);
        REQUIRE(core::extensions_active(config.monitor.extensions));
        ReaderOptions reader;
        reader.shunt = config.monitor.shunt;
        const std::string log = kFlights + name + ".csv";
        const Trace t = load_trace(log, reader, config);
        SimResult sim;
        simulate(t, spec_from_config(config), InitialMode::Monitor, 0.0f, sim);
        ReplayOptions ro;
        ro.reader = reader;
        ro.config = config;
        std::vector<float> monitor_v;
        const nlohmann::json summary = replay_log(log, ro, [&](const core::Sample&, const core::MonitorStatus& st) {
            monitor_v.push_back(st.sample_valid && st.initialised ? st.model_voltage_v : NAN);
        });
        REQUIRE(monitor_v.size() == sim.model_v.size());
        size_t compared = 0;
        for (size_t k = 0; k < monitor_v.size(); ++k) {
            if (std::isnan(monitor_v[k]) || std::isnan(sim.model_v[k])) continue;
            REQUIRE(monitor_v[k] == sim.model_v[k]);
            ++compared;
        }
        CHECK(compared > 3000);
        // The trace's flight window is the plain monitor's; with a current-sensor correction the
        // monitor's own take-off and landing can move by a sample or two.
        const ErrorStats s = error_stats(t, sim.model_v, Window::Flight);
        CHECK(s.mae_v == Approx(summary["flight"]["voltage_error_v"]["model"]["mean_abs"].get<double>()).margin(1e-4));
        // The point of the fitted model: below 0.05 V in flight, where the hand-tuned one was 0.08–0.77 V.
        CHECK(s.mae_v < 0.05);
    }
}

TEST_CASE("Natural parameters and the config's curve points round-trip", "[fit]") {
    core::TremblayParams original;
    original.exponential_capacity_ah = 0.8f;
    original.nominal_zone_capacity_ah = 1.42f;
    original.internal_resistance_ohm = 0.0208f;
    original.curve_current_a = 0.0634f;
    for (const core::TremblayParams& p : {core::TremblayParams{}, original}) {
        const NaturalParams n = natural_from_params(p);
        const core::TremblayParams back = params_from_natural(n, p);
        core::TremblayModel a, b;
        a.configure(p);
        b.configure(back);
        CHECK(b.e0_v() == Approx(a.e0_v()).epsilon(1e-5));
        CHECK(b.k_v() == Approx(a.k_v()).epsilon(1e-4));
        CHECK(k_of(n) == Approx(a.k_v()).epsilon(1e-4));
        for (float used = 0.0f; used < 1.5f; used += 0.1f) CHECK(b.voltage_v(used, 20.0f, 15.0f) == Approx(a.voltage_v(used, 20.0f, 15.0f)).margin(2e-4));
    }
}

TEST_CASE("K follows the curve current the config can hold, and a parameter with no effect has no sigma", "[fit]") {
    // Flight 34's fit: kappa at its 1e-6 bound, but the curve current E0·kappa stands for is
    // capped where the exponential voltage reaches 0.1 V; the written config, and so the
    // model, has a larger kappa. K had been read off the uncapped one, 174 times too small.
    NaturalParams n;
    n.e0_v = 15.095;
    n.r_ohm = 0.0424;
    n.a_v = 8.66;
    n.b_per_ah = 48.7;
    n.q_ah = 1.139;
    n.kappa = 1e-6;
    const core::TremblayParams p = params_from_natural(n, core::TremblayParams{});
    CHECK(p.exponential_voltage_v == Approx(0.1).margin(1e-4));  // the cap binds
    core::TremblayModel m;
    m.configure(p);
    CHECK(k_of(n) == Approx(m.k_v()).epsilon(1e-3));
    NaturalParams smaller = n;
    smaller.kappa = 1e-5;  // below the cap as well: the same model, the same K
    CHECK(k_of(smaller) == Approx(k_of(n)).epsilon(1e-9));

    // In the covariance, a parameter whose Jacobian column is zero is not known at all.
    LmResult r;
    r.x = Eigen::Vector2d(1.0, 1.0);
    r.residuals = Eigen::VectorXd::Constant(10, 0.1);
    r.jacobian = Eigen::MatrixXd::Zero(10, 2);
    for (int i = 0; i < 10; ++i) r.jacobian(i, 0) = static_cast<double>(i);
    r.at_bound = {false, false};
    const Eigen::MatrixXd cov = covariance(r);
    CHECK(std::isfinite(cov(0, 0)));
    CHECK(cov(0, 0) > 0.0);
    CHECK(std::isinf(cov(1, 1)));  // it had read 0: "± 0.0"

    // Errors over no samples (a lab log has no flight) are none, not 0 V.
    const nlohmann::json none = error_stats_to_json(ErrorStats{});
    CHECK(none["n"] == 0);
    CHECK(none["mae_v"].is_null());
    CHECK(none["rmse_v"].is_null());
}

TEST_CASE("Levenberg-Marquardt: linear regression and its covariance", "[fit]") {
    // y = 2 + 3x + noise: the solution and s²(XᵀX)⁻¹ are known in closed form.
    std::mt19937 gen(7);
    std::normal_distribution<double> noise(0.0, 0.1);
    const int m = 200;
    Eigen::VectorXd x(m), y(m);
    for (int i = 0; i < m; ++i) {
        x[i] = i / 20.0;
        y[i] = 2 + 3 * x[i] + noise(gen);
    }
    LmProblem p;
    p.n_params = 2;
    p.group_sizes = {m};
    p.lower = Eigen::Vector2d(-100, -100);
    p.upper = Eigen::Vector2d(100, 100);
    p.typical = Eigen::Vector2d(1, 1);
    p.residuals = [&](const Eigen::VectorXd& b, int, double* r) {
        for (int i = 0; i < m; ++i) r[i] = y[i] - (b[0] + b[1] * x[i]);
    };
    const LmResult res = levenberg_marquardt(p, Eigen::Vector2d(0, 0), LmOptions{});
    Eigen::MatrixXd X(m, 2);
    X.col(0).setOnes();
    X.col(1) = x;
    const Eigen::Vector2d ols = (X.transpose() * X).ldlt().solve(X.transpose() * y);
    CHECK(res.x[0] == Approx(ols[0]).epsilon(1e-6));
    CHECK(res.x[1] == Approx(ols[1]).epsilon(1e-6));
    const double s2 = (y - X * ols).squaredNorm() / (m - 2);
    const Eigen::Matrix2d expected = s2 * (X.transpose() * X).inverse();
    const Eigen::MatrixXd cov = covariance(res);
    CHECK(cov(0, 0) == Approx(expected(0, 0)).epsilon(1e-4));
    CHECK(cov(1, 1) == Approx(expected(1, 1)).epsilon(1e-4));
    CHECK(cov(0, 1) == Approx(expected(0, 1)).epsilon(1e-4));

    // A bound that binds: the intercept may not go below 2.5.
    p.lower[0] = 2.5;
    const LmResult bounded = levenberg_marquardt(p, Eigen::Vector2d(3, 0), LmOptions{});
    CHECK(bounded.x[0] == 2.5);
    CHECK(bounded.at_bound[0]);
    CHECK_FALSE(bounded.at_bound[1]);

    // A third parameter the residuals do not depend on, started at its lower bound: the logs
    // leave it there (zero gradient). It is at its bound, not only "not moved" (a fit's kappa
    // had been listed so).
    LmProblem idle = p;
    idle.n_params = 3;
    idle.lower = Eigen::Vector3d(2.5, -100, 0);
    idle.upper = Eigen::Vector3d(100, 100, 1);
    idle.typical = Eigen::Vector3d(1, 1, 1);
    idle.residuals = [&](const Eigen::VectorXd& b, int, double* r) {
        for (int i = 0; i < m; ++i) r[i] = y[i] - (b[0] + b[1] * x[i]);
    };
    const LmResult left = levenberg_marquardt(idle, Eigen::Vector3d(3, 0, 0), LmOptions{});
    CHECK(left.x[2] == 0);
    CHECK(left.at_bound[2]);
    CHECK_FALSE(left.at_bound[1]);
    // Its started value away from the bound is not "at bound".
    const LmResult inside = levenberg_marquardt(idle, Eigen::Vector3d(3, 0, 0.5), LmOptions{});
    CHECK_FALSE(inside.at_bound[2]);
}

TEST_CASE("A fit recovers the parameters of a generated log, with honest uncertainty", "[fit]") {
    synth::Options o;
    o.params.internal_resistance_ohm = 0.03f;  // the "true" pack differs from the start config
    o.params.capacity_ah = 1.45f;
    o.params.full_voltage_v = 16.7f;
    o.noise_v = 0.005;
    o.quantum_v = 0;
    o.flight_s = 200;
    o.seed = 11;
    const std::string path = synth::write_log("fit-recover", o);
    const LoadedConfig config = default_config();
    const Trace t = load_trace(path, ReaderOptions{}, config);
    FitOptions fo;
    fo.params = default_parameters(spec_from_config(config));
    fo.lm.max_iterations = 300;
    const FitResult r = fit_model({t}, {spec_from_config(config)}, fo);
    std::remove(path.c_str());
    CHECK(r.rmse_v < 0.0056);  // the noise level: nothing systematic left
    const ParamEstimate* rr = nullptr;
    for (const ParamEstimate& p : r.params) {
        if (p.name == "r") rr = &p;
    }
    REQUIRE(rr != nullptr);
    CHECK(rr->value == Approx(0.03).epsilon(0.02));
    CHECK(std::fabs(rr->value - 0.03) < 4 * rr->sigma_ar1);
    CHECK(rr->sigma > 0);
    CHECK(r.logs[0].fit_all.rmse_v < 0.0056);
}

TEST_CASE("An RC branch is no faster than three sample intervals, so it cannot take over R", "[fit]") {
    // The Panasonic cell's 10 Hz fit had put its 31 mOhm into a 0.18 s branch and left R at 0.
    synth::Options o;
    o.params.internal_resistance_ohm = 0.03f;
    o.noise_v = 0.003;
    o.quantum_v = 0;
    o.flight_s = 200;
    o.seed = 21;  // dt 0.1 s
    const std::string path = synth::write_log("fit-fast-rc", o);
    const LoadedConfig config = default_config();
    const Trace t = load_trace(path, ReaderOptions{}, config);
    std::remove(path.c_str());
    ModelSpec start = spec_from_config(config);
    enable_extension(start, "rc:0.06");  // a start faster than the samples can show
    FitOptions fo;
    fo.params = default_parameters(start);
    fo.lm.max_iterations = 300;
    const FitResult r = fit_model({t}, {start}, fo);
    double tau_s = 0, r_ohm = 0;
    for (const ParamEstimate& p : r.params) {
        if (p.name == "rc1_tau") tau_s = p.value;
        if (p.name == "r") r_ohm = p.value;
    }
    INFO("tau " << tau_s << " s, R " << r_ohm << " ohm");
    CHECK(tau_s >= 0.3 - 1e-6);  // 3 × the 0.1 s interval
    CHECK(r_ohm > 0.02);
}

TEST_CASE("Fits are deterministic and per-log parameters separate packs", "[fit]") {
    synth::Options a, b;
    a.params.internal_resistance_ohm = 0.02f;
    b.params.internal_resistance_ohm = 0.045f;
    a.seed = 3;
    b.seed = 4;
    a.flight_s = b.flight_s = 150;
    const std::string pa = synth::write_log("pack-a", a), pb = synth::write_log("pack-b", b);
    const LoadedConfig config = default_config();
    const std::vector<Trace> traces = {load_trace(pa, ReaderOptions{}, config), load_trace(pb, ReaderOptions{}, config)};
    std::remove(pa.c_str());
    std::remove(pb.c_str());
    FitOptions fo;
    // The config's curve-point encoding ties E0 to R (E0 = full + R·i − A), so two packs that
    // differ in R alone differ in E0 too: both are per log.
    fo.params = {"kappa", "a", "b", "q"};
    fo.per_log_params = {"r", "e0"};
    const ModelSpec start = spec_from_config(config);
    const FitResult r1 = fit_model(traces, {start}, fo);
    const FitResult r2 = fit_model(traces, {start}, fo);
    REQUIRE(r1.params.size() == r2.params.size());
    for (size_t j = 0; j < r1.params.size(); ++j) CHECK(r1.params[j].value == r2.params[j].value);
    CHECK(r1.specs[0].battery.internal_resistance_ohm == Approx(0.02).epsilon(0.03));
    CHECK(r1.specs[1].battery.internal_resistance_ohm == Approx(0.045).epsilon(0.03));
    CHECK(r1.rmse_v < 0.004);  // 10 mV quantisation alone: 2.9 mV
    CHECK(fit_result_to_json(r1, fo).dump() == fit_result_to_json(r2, fo).dump());
}

TEST_CASE("Fit options are checked", "[fit]") {
    synth::Options o;
    o.flight_s = 30;
    const std::string path = synth::write_log("options", o);
    const LoadedConfig config = default_config();
    const std::vector<Trace> traces = {load_trace(path, ReaderOptions{}, config)};
    std::remove(path.c_str());
    const ModelSpec start = spec_from_config(config);
    FitOptions fo;
    fo.params = {"e0", "resistance"};
    CHECK_THROWS_WITH(fit_model(traces, {start}, fo), Catch::Contains("unknown parameter \"resistance\""));
    fo.params = {"rc1_r"};
    CHECK_THROWS_WITH(fit_model(traces, {start}, fo), Catch::Contains("RC branch 1 is not enabled"));
    fo.params = {"temp_r"};
    CHECK_THROWS_WITH(fit_model(traces, {start}, fo), Catch::Contains("temperature extension is not enabled"));
    fo.params = {"r", "r"};
    CHECK_THROWS_WITH(fit_model(traces, {start}, fo), Catch::Contains("given twice"));
    CHECK_THROWS_AS(parse_initial_mode("guess"), std::invalid_argument);
    CHECK_THROWS_AS(parse_window("half"), std::invalid_argument);
}

TEST_CASE("Multi-start: a seeded Latin hypercube takes every stratum once", "[fit]") {
    const Eigen::Vector2d lo(1, 0.1), hi(2, 10);
    const std::vector<Eigen::VectorXd> xs = latin_hypercube(lo, hi, {false, true}, 5, 42);
    REQUIRE(xs.size() == 5);
    std::vector<double> a, b;
    for (const Eigen::VectorXd& x : xs) {
        a.push_back(x[0]);
        b.push_back(std::log10(x[1]));
    }
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    for (int k = 0; k < 5; ++k) {
        CHECK(a[k] == Approx(1.1 + 0.2 * k));         // the middles of five equal strata of 1..2
        CHECK(b[k] == Approx(-1 + 0.4 * (k + 0.5)));  // of 0.1..10 in decades
    }
    // The same seed gives the same points; the strata are paired differently per coordinate.
    const std::vector<Eigen::VectorXd> again = latin_hypercube(lo, hi, {false, true}, 5, 42);
    for (int k = 0; k < 5; ++k) CHECK(again[k] == xs[k]);
    CHECK(latin_hypercube(lo, hi, {false, true}, 0, 42).empty());
}

TEST_CASE("Multi-start finds the minimum a single start misses, whatever the threads", "[fit]") {
    // ½Σr² with r = ((x − 1)(x − 4), (x − 4)/2) = ½(x − 4)²((x − 1)² + ¼): the global minimum is
    // 0 at x = 4; from x = 1 the solver stops in the local one where 2x² − 7x + 5.25 = 0,
    // x = (7 − √7)/4 = 1.0886, cost ½·2.9114²·(0.0886² + ¼) = 1.0934.
    LmProblem p;
    p.n_params = 1;
    p.group_sizes = {2};
    p.lower = Eigen::VectorXd::Constant(1, 0.1);
    p.upper = Eigen::VectorXd::Constant(1, 10);
    p.typical = Eigen::VectorXd::Constant(1, 1);
    p.residuals = [](const Eigen::VectorXd& x, int, double* r) {
        r[0] = (x[0] - 1) * (x[0] - 4);
        r[1] = 0.5 * (x[0] - 4);
    };
    const Eigen::VectorXd x0 = Eigen::VectorXd::Constant(1, 1.0);
    const LmResult single = levenberg_marquardt(p, x0, LmOptions{});
    CHECK(single.x[0] == Approx((7 - std::sqrt(7.0)) / 4).epsilon(1e-5));
    CHECK(single.cost == Approx(1.0934).epsilon(1e-3));
    // Seven more starts from 1/3 to 3 (the strata's middles reach 2.8, past the local
    // maximum at (7 + √7)/4 = 2.41).
    std::vector<Eigen::VectorXd> starts{x0};
    for (const Eigen::VectorXd& x : latin_hypercube(x0 / 3, x0 * 3, {true}, 7, 1)) starts.push_back(x);
    const MultiStartResult one = multi_start(p, starts, LmOptions{}, 1);
    const MultiStartResult two = multi_start(p, starts, LmOptions{}, 2);
    REQUIRE(one.runs.size() == 8);
    CHECK(one.runs[0].x[0] == single.x[0]);  // start 0 is the single start
    CHECK(one.runs[one.best].x[0] == Approx(4.0).epsilon(1e-6));
    CHECK(one.runs[one.best].cost < 1e-12);
    CHECK(two.best == one.best);
    for (size_t k = 0; k < one.runs.size(); ++k) CHECK(two.runs[k].x == one.runs[k].x);
}

TEST_CASE("The fits the logs cannot tell apart: Beale's region with autocorrelated residuals", "[fit]") {
    // χ²₀.₉₅ of 1, 10 and 17 degrees of freedom: 3.841, 18.307, 27.587 (tables); Wilson–Hilferty
    // is 2.5 % low at 1 and within 1 % from about 3 on.
    CHECK(near_best_cost(10, 1000, 0.0) == Approx(18.307 / 1000).epsilon(0.01));
    CHECK(near_best_cost(17, 4663, 0.0) == Approx(27.587 / 4663).epsilon(0.01));
    CHECK(near_best_cost(1, 100, 0.0) == Approx(3.841 / 100).epsilon(0.03));
    // ρ = 0.9 leaves 4663·0.1/1.9 = 245.4 independent points.
    CHECK(near_best_cost(17, 4663, 0.9) == Approx(27.587 / 245.42).epsilon(0.01));
    CHECK(near_best_cost(17, 4663, -0.3) == near_best_cost(17, 4663, 0.0));  // no gain from alternation
    CHECK(std::isfinite(near_best_cost(17, 3, 0.999)));
}

TEST_CASE("A multi-start fit reports every start and the range of the fits the logs cannot tell from the best", "[fit]") {
    synth::Options o;
    o.flight_s = 60;
    o.seed = 9;
    const std::string path = synth::write_log("fit-starts", o);
    const LoadedConfig config = default_config();
    const Trace t = load_trace(path, ReaderOptions{}, config);
    std::remove(path.c_str());
    FitOptions fo;
    fo.params = default_parameters(spec_from_config(config));
    const FitResult single = fit_model({t}, {spec_from_config(config)}, fo);
    CHECK(single.starts.empty());
    fo.starts = 6;
    fo.jobs = 2;
    const FitResult r = fit_model({t}, {spec_from_config(config)}, fo);
    REQUIRE(r.starts.size() == 6);
    CHECK(r.starts[0].rmse_v == Approx(single.rmse_v).epsilon(1e-9));  // start 0 is the one-start fit
    CHECK(r.rmse_v <= single.rmse_v);
    CHECK(r.starts[r.best_start].cost_ratio == 1.0);
    CHECK(r.rmse_v == r.starts[r.best_start].rmse_v);
    int near = 0;
    for (const StartOutcome& s : r.starts) {
        CHECK(s.cost_ratio >= 1.0);
        near += s.cost_ratio <= 1 + r.near_best_cost ? 1 : 0;
    }
    CHECK(r.near_best == near);
    for (const ParamEstimate& p : r.params) {
        INFO(p.name);
        CHECK(p.near_best_min <= p.value);
        CHECK(p.value <= p.near_best_max);
    }
    CHECK(r.near_best_cost == near_best_cost(static_cast<int>(r.params.size()), r.points, r.residual_lag1));
    fo.jobs = 1;
    CHECK(fit_result_to_json(fit_model({t}, {spec_from_config(config)}, fo), fo).dump() == fit_result_to_json(r, fo).dump());
    fo.starts = 0;
    CHECK_THROWS_WITH(fit_model({t}, {spec_from_config(config)}, fo), Catch::Contains("starts must be at least 1"));
    // Nothing to fit: one start, the others would be the same run.
    fo.starts = 6;
    fo.params.clear();
    fo.initial = InitialMode::Monitor;
    CHECK(fit_model({t}, {spec_from_config(config)}, fo).starts.empty());
}

TEST_CASE("Multi-start: two RC branches that trade places are one solution", "[fit]") {
    // One true branch (10 mOhm, 4 s) and two in the model: fits from other starts swap the
    // two. Compared as they came, the second branch's range took in the first's (3.38–44.6 s
    // against 3.69–4.03 s); ranked by time constant in every fit, the faster branch's least and
    // largest values lie below the slower one's.
    synth::Options o;
    o.rc_resistance_ohm = 0.01;
    o.rc_time_constant_s = 4;
    o.noise_v = 0.003;
    o.quantum_v = 0;
    o.flight_s = 120;
    o.seed = 31;
    const std::string path = synth::write_log("fit-two-branches", o);
    const LoadedConfig config = default_config();
    const Trace t = load_trace(path, ReaderOptions{}, config);
    std::remove(path.c_str());
    ModelSpec start = spec_from_config(config);
    enable_extension(start, "rc:1");
    enable_extension(start, "rc:20");
    FitOptions fo;
    fo.params = default_parameters(start);
    fo.starts = 12;
    fo.jobs = 2;
    const FitResult r = fit_model({t}, {start}, fo);
    std::map<std::string, const ParamEstimate*> by;
    for (const ParamEstimate& p : r.params) by[p.name] = &p;
    INFO("near best " << r.near_best << "; rc1_tau " << by["rc1_tau"]->near_best_min << "–" << by["rc1_tau"]->near_best_max
                      << " s, rc2_tau " << by["rc2_tau"]->near_best_min << "–" << by["rc2_tau"]->near_best_max << " s");
    REQUIRE(r.near_best >= 2);
    const bool rc1_faster = by["rc1_tau"]->value < by["rc2_tau"]->value;
    const ParamEstimate& fast = *by[rc1_faster ? "rc1_tau" : "rc2_tau"];
    const ParamEstimate& slow = *by[rc1_faster ? "rc2_tau" : "rc1_tau"];
    CHECK(fast.near_best_min <= slow.near_best_min);
    CHECK(fast.near_best_max <= slow.near_best_max);

    // Shared time constants with each log's own resistances (the joint fit's layout): the
    // branches trade places in every log at once.
    o.seed = 32;
    const std::string other = synth::write_log("fit-two-branches-b", o);
    const Trace t2 = load_trace(other, ReaderOptions{}, config);
    std::remove(other.c_str());
    fo.params = {"e0", "kappa", "a", "b", "q", "rc1_tau", "rc2_tau"};
    fo.per_log_params = {"r", "rc1_r", "rc2_r"};
    const FitResult joint = fit_model({t, t2}, {start}, fo);
    std::map<std::string, const ParamEstimate*> shared;
    for (const ParamEstimate& p : joint.params)
        if (p.log.empty()) shared[p.name] = &p;
    INFO("near best " << joint.near_best << "; rc1_tau " << shared["rc1_tau"]->near_best_min << "–"
                      << shared["rc1_tau"]->near_best_max << " s, rc2_tau " << shared["rc2_tau"]->near_best_min << "–"
                      << shared["rc2_tau"]->near_best_max << " s");
    REQUIRE(joint.near_best >= 2);
    const bool first_faster = shared["rc1_tau"]->value < shared["rc2_tau"]->value;
    const ParamEstimate& quick = *shared[first_faster ? "rc1_tau" : "rc2_tau"];
    const ParamEstimate& slower = *shared[first_faster ? "rc2_tau" : "rc1_tau"];
    CHECK(quick.near_best_min <= slower.near_best_min);
    CHECK(quick.near_best_max <= slower.near_best_max);
}

TEST_CASE("The extensions' bounds scale with the pack's charged voltage, not the curve encoding's", "[fit]") {
    // The config's model is 2 V low; an OCV correction alone makes up for it, up to 15 % of
    // the pack's charged voltage. With max_voltage_v at 8 V that is 1.2 V; the encoding's
    // full_voltage_v (14.8 V) would have allowed 2.2 V.
    synth::Options o;
    o.flight_s = 60;
    o.seed = 13;
    const std::string path = synth::write_log("fit-bounds", o);
    FitJob job;
    job.logs = {path};
    job.config = default_config();
    job.config.monitor.battery.full_voltage_v -= 2.0f;
    job.config.monitor.max_voltage_v = 8.0f;
    job.config.monitor.min_voltage_v = 6.0f;
    job.add = {"ocv:4"};
    job.options.params = {"ocv"};
    const nlohmann::json r = run_fit_job(job);
    std::remove(path.c_str());
    double largest = 0;
    bool at_bound = false;
    for (const auto& p : r["parameters"]) {
        if (p["name"].get<std::string>().compare(0, 3, "ocv") != 0) continue;
        largest = std::max(largest, p["value"].get<double>());
        at_bound = at_bound || p.contains("at_bound");
    }
    CHECK(largest == Approx(0.15 * 8.0).epsilon(1e-6));
    CHECK(at_bound);
}

TEST_CASE("A multi-start fit's ranges hold the value it reports, a capacity at its floor too", "[fit][data]") {
    // Flight 29's fits hold the capacity at the charge the flight drew; the raw parameter below
    // that floor had made the range miss the value reported (1.083 Ah against 1.178).
    const LoadedConfig config = load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/fitted/pbms-flight29-dinogy1.json");
    ReaderOptions reader;
    reader.shunt = config.monitor.shunt;
    const Trace t = load_trace(kFlights + "29.csv", reader, config);
    const ModelSpec start = spec_from_config(config);
    FitOptions fo;
    fo.params = default_parameters(start);
    fo.lm.max_iterations = 300;
    fo.bounds_full_voltage_v = config.monitor.max_voltage_v;
    fo.starts = 8;
    fo.jobs = 2;
    const FitResult r = fit_model({t}, {start}, fo);
    REQUIRE(r.near_best >= 2);
    bool q_seen = false;
    for (const ParamEstimate& p : r.params) {
        INFO(p.name << " " << p.value << " in " << p.near_best_min << "–" << p.near_best_max);
        CHECK(p.near_best_min <= p.value);
        CHECK(p.value <= p.near_best_max);
        q_seen = q_seen || (p.name == "q" && p.at_bound);
    }
    CHECK(q_seen);
}
