// Nonlinear least squares of the model parameters along one or more logs (constant-current
// discharges and flights alike): the model is simulated along each log's current exactly as
// the monitor runs it (filtered current, coulomb-counted charge, initial charge), and the
// parameters minimise Σ (measured − model voltage)² with each log weighted equally.
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "host/fit/levenberg_marquardt.h"
#include "host/fit/model.h"

namespace battsim {
namespace host {
namespace fit {

// Parameter names accepted by FitOptions (and `battsim fit --params`):
//   e0 r kappa a b q reaction                 base model (kappa: K as a fraction of K_max)
//   rcN_r rcN_tau                             RC branch N = 1..3 (must be enabled in the spec)
//   temp_r temp_k temp_q temp_e0              temperature dependence (Arrhenius R, K; dQ/dT, dE0/dT)
//   thermal_rth thermal_tau                   lumped thermal state
//   hyst_m hyst_rate                          hysteresis
//   ocv                                       every OCV-correction point
//   gain offset lead                          current sensor
// `initial` (charge drawn at the settle sample) is always per log and free with
// InitialMode::Free.
std::vector<std::string> known_parameter_names();
// Throws std::invalid_argument ("OPTION: unknown parameter "x"; expected one of ...", no
// prefix when `option` is empty) unless `name` is one of known_parameter_names().
void check_parameter_name(const std::string& name, const std::string& option = std::string());
// The base parameters plus those of every extension enabled in `spec`.
std::vector<std::string> default_parameters(const ModelSpec& spec);

struct FitOptions {
    std::vector<std::string> params;          // fitted, shared by all logs
    std::vector<std::string> per_log_params;  // fitted separately for each log
    InitialMode initial = InitialMode::Free;
    Window window = Window::All;
    // Per log, per sample: nonzero = use in the objective (null = all in the window).
    const std::vector<std::vector<uint8_t>>* mask = nullptr;
    // InitialMode::Free: starting charge per log (null = the monitor's estimate from the replay).
    const std::vector<float>* initial_start = nullptr;
    size_t max_points_per_log = 20000;  // longer logs are thinned evenly (the simulation still runs every sample)
    bool equal_log_weights = true;
    // When the six base parameters are all fitted and shared: also start from the best
    // linear least-squares solution over a grid of capacities and exponential-zone sizes (the
    // model is linear in E0, R, K and A once Q and B are fixed) and keep the better fit.
    bool linear_start = true;
    // The fitted capacity stays at or below this × the starting (configured) capacity, and at
    // or above the charge the logs show was drawn. Tremblay's form cannot follow every cell's
    // knee; unbounded, the fit may push the Q/(Q − it) pole far out and let the other terms
    // imitate a straight line, which no longer is a discharge curve.
    double max_capacity_factor = 1.5;
    double max_capacity_ah = 0;  // > 0: this absolute cap instead of the factor
    // The pack's charged voltage and capacity that scale the plausibility bounds of the
    // extensions' parameters (0 = the start spec's full_voltage_v and capacity; the fit and
    // residual jobs give the config's max_voltage_v).
    double bounds_full_voltage_v = 0;
    double bounds_capacity_ah = 0;
    // Gaussian priors (MAP): one extra residual noise_v·(x − mean)/sigma per prior. They pin
    // directions the data leave flat (an OCV correction trading off against E0) and cost
    // little where the data speak. `name` is an expanded parameter name (ocv1, temp_e0, ...).
    struct Prior {
        std::string name;
        double mean = 0, sigma = 1;
    };
    std::vector<Prior> priors;
    double prior_noise_v = 0.01;
    LmOptions lm;
    // Starting points: 1 = the config's values (and the linear start above). More adds
    // starts - 1 points spread around them by a seeded Latin hypercube (the same points on
    // every run and machine); the fit with the least error is kept, and those the logs
    // cannot tell from it show how far the logs leave each parameter free. `jobs` threads
    // run them; the result does not depend on it.
    int starts = 1;
    int jobs = 1;
    // The remedy for more parameters than samples, in the caller's options (TooLittleData).
    std::string fewer_parameters_advice = "fewer parameters with --params";
};

struct ParamEstimate {
    std::string name;
    std::string log;  // per-log parameter: the log's label; empty = shared
    std::string unit;
    double value = 0;
    double start = 0;
    double sigma = 0;      // from s²(JᵀJ)⁻¹; infinite when not identifiable
    double sigma_ar1 = 0;  // inflated for the residuals' lag-1 autocorrelation
    bool at_bound = false;
    // Multi-start: the range over the fits the logs cannot tell from the best (NaN with one start).
    double near_best_min = std::numeric_limits<double>::quiet_NaN();
    double near_best_max = std::numeric_limits<double>::quiet_NaN();
};

// One starting point's fit (multi-start).
struct StartOutcome {
    int index = 0;       // 0 = the config's values; 1.. = the spread points
    double rmse_v = 0;   // over the objective's points, unweighted
    double cost_ratio = 1;  // its weighted sum of squares over the best one's
    int iterations = 0;
    std::string stop_reason;
};

struct LogFitStats {
    std::string label;
    std::string path;
    float initial_ah = 0;
    ErrorStats fit_all, fit_flight;          // with the fitted initial charge (the fit's own view)
    ErrorStats monitor_all, monitor_flight;  // initial charge as the monitor would set it
};

struct FitResult {
    std::vector<ModelSpec> specs;  // one per log (identical when nothing is per-log)
    std::vector<float> initial_ah;
    std::vector<ParamEstimate> params;
    std::vector<ParamEstimate> derived;  // K, the config's curve points (delta method)
    std::vector<LogFitStats> logs;
    double rmse_v = 0;  // over the objective's points, unweighted
    double mae_v = 0;
    size_t points = 0;
    double residual_lag1 = 0;
    int iterations = 0;
    int evaluations = 0;
    std::string stop_reason;
    std::vector<StartOutcome> starts;  // every start, in order (empty with one start)
    int best_start = 0;
    // Starts the logs cannot tell from the best, the best included: their sum of squares is
    // within near_best_cost (a fraction) of the best's (near_best_cost()).
    int near_best = 0;
    double near_best_cost = 0;
};

// How much more than the best sum of squares S a fit may have and still lie in the
// parameters' approximate 95 % joint confidence region (Beale): S·χ²₀.₉₅(p)/n_eff, with p
// the fitted parameters and n_eff the points deflated by the residuals' lag-1
// autocorrelation ρ as the σ are, n·(1 − ρ)/(1 + ρ). χ² by the Wilson–Hilferty formula.
double near_best_cost(int params, size_t points, double lag1);

// Throws std::invalid_argument for unknown parameter names or parameters of extensions that
// are not enabled, and TooLittleData for a log with no sample in the objective (why: none
// valid, no initial charge, no flight) or no more samples than parameters. `start` holds one
// spec per log (or a single spec for all).
FitResult fit_model(const std::vector<Trace>& traces, const std::vector<ModelSpec>& start, const FitOptions& options);

// Statistics of one spec on one trace (both initial modes the fit reports).
LogFitStats evaluate(const Trace& trace, const ModelSpec& spec, InitialMode mode, float initial_ah);

nlohmann::json fit_result_to_json(const FitResult& r, const FitOptions& options);
nlohmann::json error_stats_to_json(const ErrorStats& s);

// Weak physical priors (zero mean) for the extensions enabled in `spec`: OCV-correction
// points σ = 0.5 % of E0 (about 18 mV per Li-ion cell), dE0/dT σ = 0.3 mV/K per 3.7 V,
// dQ/dT σ = 0.5 % of Q per K. Nothing else carries one.
std::vector<FitOptions::Prior> default_priors(const ModelSpec& spec);

const char* to_string(InitialMode m);
InitialMode parse_initial_mode(const std::string& s);  // throws std::invalid_argument
const char* to_string(Window w);
Window parse_window(const std::string& s);

}  // namespace fit
}  // namespace host
}  // namespace battsim
