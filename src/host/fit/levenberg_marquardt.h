// Bounded Levenberg–Marquardt for residuals that come in independent groups (one group per
// log): a parameter that touches only one log's residuals costs one log's simulation per
// Jacobian column, not all of them. Central finite differences, Marquardt scaling,
// Nielsen's damping update, bounds by projection. One solve is single-threaded and
// deterministic; multi_start() runs several side by side, with the same result.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace battsim {
namespace host {
namespace fit {

struct LmProblem {
    int n_params = 0;
    std::vector<int> group_sizes;  // residuals per group
    // Writes group g's residuals for parameters x into r (group_sizes[g] values).
    std::function<void(const Eigen::VectorXd& x, int g, double* r)> residuals;
    // Groups each parameter touches; an empty list means all groups.
    std::vector<std::vector<int>> param_groups;
    Eigen::VectorXd lower, upper;
    Eigen::VectorXd typical;  // magnitude used for the finite-difference step
};

struct LmOptions {
    int max_iterations = 100;
    double cost_tolerance = 1e-9;  // stop when an accepted step gains less than this (relative)
    double step_tolerance = 1e-10;
    double fd_relative_step = 1e-3;
};

struct LmResult {
    Eigen::VectorXd x;
    Eigen::VectorXd residuals;  // at x
    Eigen::MatrixXd jacobian;   // at x
    double cost = 0;            // ½·Σ r²
    int iterations = 0;
    int evaluations = 0;        // full residual evaluations (Jacobians counted by groups run)
    std::string stop_reason;
    std::vector<bool> at_bound;
};

LmResult levenberg_marquardt(const LmProblem& problem, const Eigen::VectorXd& x0, const LmOptions& options);

// `count` points of a Latin hypercube over the box lo..hi: each coordinate's range is cut
// into `count` strata and every point takes the middle of a different one, the strata
// shuffled per coordinate by a generator seeded with `seed` (the same points on every
// platform). A coordinate with log_scale[j] is cut evenly in its logarithm (lo > 0).
std::vector<Eigen::VectorXd> latin_hypercube(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                             const std::vector<bool>& log_scale, int count, uint64_t seed);

// Runs the solver from every start, `jobs` threads at a time; `best` is the run with the
// least cost, the lowest index among equals, so the result does not depend on `jobs`. Only
// that run is kept whole: a Jacobian per start (27,000 points × 27 parameters of the Samsung
// curves: 6 MB) would have made 1,000 starts take gigabytes.
struct StartSummary {
    Eigen::VectorXd x;
    double cost = 0;
    double score = 0;  // what `summarise` made of the run (0 without it)
    int iterations = 0;
    std::string stop_reason;
};
struct MultiStartResult {
    std::vector<StartSummary> runs;  // in the order of the starts
    size_t best = 0;
    LmResult best_run;
};
MultiStartResult multi_start(const LmProblem& problem, const std::vector<Eigen::VectorXd>& starts, const LmOptions& options,
                             int jobs, const std::function<double(const LmResult&)>& summarise = nullptr);

// s²·(JᵀJ)⁻¹ over the parameters not at a bound (zero rows/columns for the others), with
// s² = Σr²/(m − n_free). Singular directions (rank-deficient JᵀJ) get infinite variance.
Eigen::MatrixXd covariance(const LmResult& result);

}  // namespace fit
}  // namespace host
}  // namespace battsim
