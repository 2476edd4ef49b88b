#include "host/fit/levenberg_marquardt.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "host/parallel.h"
#include "host/sim/rng.h"

namespace battsim {
namespace host {
namespace fit {

namespace {

struct Evaluator {
    const LmProblem& p;
    std::vector<int> offsets;
    int m = 0;
    int evaluations = 0;

    explicit Evaluator(const LmProblem& problem) : p(problem) {
        for (int s : p.group_sizes) {
            offsets.push_back(m);
            m += s;
        }
    }
    // Non-finite residuals (a model pushed out of its range) count as a large error, so
    // the step that produced them is rejected instead of poisoning the solve.
    static void sanitise(double* r, int n) {
        for (int i = 0; i < n; ++i) {
            if (!std::isfinite(r[i])) r[i] = 1e3;
        }
    }
    void all(const Eigen::VectorXd& x, Eigen::VectorXd& r) {
        r.resize(m);
        for (size_t g = 0; g < p.group_sizes.size(); ++g) {
            p.residuals(x, static_cast<int>(g), r.data() + offsets[g]);
            sanitise(r.data() + offsets[g], p.group_sizes[g]);
        }
        ++evaluations;
    }
    void jacobian(const Eigen::VectorXd& x, const Eigen::VectorXd& r, double rel_step, Eigen::MatrixXd& J) {
        J.setZero(m, p.n_params);
        std::vector<double> plus, minus;
        for (int j = 0; j < p.n_params; ++j) {
            const double scale = std::max(std::fabs(x[j]), p.typical[j]);
            double h = rel_step * (scale > 0 ? scale : 1.0);
            double up = x[j] + h, down = x[j] - h;
            // One-sided at a bound; the step shrinks if both sides are blocked.
            if (up > p.upper[j]) up = x[j];
            if (down < p.lower[j]) down = x[j];
            if (up == down) continue;
            std::vector<int> groups = p.param_groups.empty() ? std::vector<int>() : p.param_groups[j];
            if (groups.empty()) {
                for (size_t g = 0; g < p.group_sizes.size(); ++g) groups.push_back(static_cast<int>(g));
            }
            Eigen::VectorXd xu = x, xd = x;
            xu[j] = up;
            xd[j] = down;
            for (int g : groups) {
                const int n = p.group_sizes[g];
                plus.assign(n, 0.0);
                minus.assign(n, 0.0);
                if (up != x[j]) {
                    p.residuals(xu, g, plus.data());
                    sanitise(plus.data(), n);
                } else {
                    std::copy(r.data() + offsets[g], r.data() + offsets[g] + n, plus.begin());
                }
                if (down != x[j]) {
                    p.residuals(xd, g, minus.data());
                    sanitise(minus.data(), n);
                } else {
                    std::copy(r.data() + offsets[g], r.data() + offsets[g] + n, minus.begin());
                }
                const double inv = 1.0 / (up - down);
                for (int i = 0; i < n; ++i) J(offsets[g] + i, j) = (plus[i] - minus[i]) * inv;
            }
        }
    }
};

Eigen::VectorXd project(const Eigen::VectorXd& x, const LmProblem& p) {
    Eigen::VectorXd y = x;
    for (int j = 0; j < y.size(); ++j) y[j] = std::clamp(y[j], p.lower[j], p.upper[j]);
    return y;
}

}  // namespace

LmResult levenberg_marquardt(const LmProblem& problem, const Eigen::VectorXd& x0, const LmOptions& options) {
    Evaluator ev(problem);
    LmResult out;
    Eigen::VectorXd x = project(x0, problem);
    Eigen::VectorXd r;
    ev.all(x, r);
    double cost = 0.5 * r.squaredNorm();
    Eigen::MatrixXd J;
    const int n = problem.n_params;
    if (n == 0 || ev.m == 0) {
        out.x = x;
        out.residuals = r;
        out.jacobian = Eigen::MatrixXd::Zero(ev.m, n);
        out.cost = cost;
        out.stop_reason = n == 0 ? "no free parameters" : "no residuals";
        out.at_bound.assign(n, false);
        out.evaluations = ev.evaluations;
        return out;
    }
    ev.jacobian(x, r, options.fd_relative_step, J);
    Eigen::MatrixXd A = J.transpose() * J;
    Eigen::VectorXd g = J.transpose() * r;
    double lambda = 1e-3;
    double nu = 2.0;
    int small_gains = 0;
    out.stop_reason = "iteration limit";
    int it = 0;
    for (; it < options.max_iterations; ++it) {
        const double max_diag = std::max(A.diagonal().maxCoeff(), 1e-300);
        Eigen::VectorXd d = A.diagonal();
        for (int j = 0; j < n; ++j) d[j] = std::max(d[j], 1e-12 * max_diag);
        Eigen::MatrixXd M = A;
        M.diagonal() += lambda * d;
        const Eigen::VectorXd step = M.ldlt().solve(-g);
        const Eigen::VectorXd x_new = project(x + step, problem);
        const Eigen::VectorXd dx = x_new - x;
        if (!dx.allFinite()) {
            out.stop_reason = "singular step";
            break;
        }
        if (dx.norm() <= options.step_tolerance * (x.norm() + options.step_tolerance)) {
            out.stop_reason = "step below tolerance";
            break;
        }
        Eigen::VectorXd r_new;
        ev.all(x_new, r_new);
        const double cost_new = 0.5 * r_new.squaredNorm();
        const double predicted = -(dx.dot(g) + 0.5 * dx.dot(A * dx));
        if (cost_new < cost) {
            const double gain = cost - cost_new;
            const double rho = predicted > 0 ? gain / predicted : 1.0;
            x = x_new;
            r = r_new;
            cost = cost_new;
            lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
            lambda = std::max(lambda, 1e-15);
            nu = 2.0;
            small_gains = gain <= options.cost_tolerance * cost ? small_gains + 1 : 0;
            ev.jacobian(x, r, options.fd_relative_step, J);
            A = J.transpose() * J;
            g = J.transpose() * r;
            if (small_gains >= 2) {
                ++it;
                out.stop_reason = "cost change below tolerance";
                break;
            }
        } else {
            lambda *= nu;
            nu *= 2.0;
            if (lambda > 1e16) {
                out.stop_reason = "no further decrease";
                break;
            }
        }
    }
    out.x = x;
    out.residuals = r;
    out.jacobian = J;
    out.cost = cost;
    out.iterations = it;
    out.evaluations = ev.evaluations;
    out.at_bound.resize(n);
    for (int j = 0; j < n; ++j) {
        const double tol = 1e-9 * std::max(1.0, std::fabs(x[j]));
        // Held there, or left there by logs that do not move it (zero gradient): either way at
        // its bound, as the brief says, not "not moved by these logs" alone.
        out.at_bound[j] = (x[j] - problem.lower[j] <= tol && g[j] >= 0) || (problem.upper[j] - x[j] <= tol && g[j] <= 0);
    }
    return out;
}

std::vector<Eigen::VectorXd> latin_hypercube(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                             const std::vector<bool>& log_scale, int count, uint64_t seed) {
    std::vector<Eigen::VectorXd> xs(std::max(count, 0), lo);
    sim::Rng rng(seed);
    std::vector<int> order(xs.size());
    for (int j = 0; j < lo.size(); ++j) {
        for (int k = 0; k < count; ++k) order[k] = k;
        for (int k = count - 1; k > 0; --k) std::swap(order[k], order[rng.uniform_int(0, k)]);
        const bool log_j = j < static_cast<int>(log_scale.size()) && log_scale[j] && lo[j] > 0;
        for (int k = 0; k < count; ++k) {
            const double u = (order[k] + 0.5) / count;
            xs[k][j] = log_j ? lo[j] * std::pow(hi[j] / lo[j], u) : lo[j] + (hi[j] - lo[j]) * u;
        }
    }
    return xs;
}

MultiStartResult multi_start(const LmProblem& problem, const std::vector<Eigen::VectorXd>& starts, const LmOptions& options,
                             int jobs, const std::function<double(const LmResult&)>& summarise) {
    MultiStartResult out;
    out.runs.resize(starts.size());
    std::mutex lock;
    bool any = false;
    parallel_for(starts.size(), jobs, [&](size_t k) {
        LmResult r = levenberg_marquardt(problem, starts[k], options);
        out.runs[k] = StartSummary{r.x, r.cost, summarise ? summarise(r) : 0.0, r.iterations, r.stop_reason};
        // The least (cost, index) wins whichever run finishes first.
        const std::lock_guard<std::mutex> hold(lock);
        if (!any || r.cost < out.best_run.cost || (r.cost == out.best_run.cost && k < out.best)) {
            out.best_run = std::move(r);
            out.best = k;
            any = true;
        }
    });
    return out;
}

Eigen::MatrixXd covariance(const LmResult& res) {
    const int n = static_cast<int>(res.x.size());
    const int m = static_cast<int>(res.residuals.size());
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n, n);
    std::vector<int> free;
    for (int j = 0; j < n; ++j) {
        if (res.at_bound[j]) continue;
        if (res.jacobian.col(j).squaredNorm() > 0) {
            free.push_back(j);
        } else {
            // A parameter with no effect on the residuals is not known at all (it had read ± 0).
            cov(j, j) = std::numeric_limits<double>::infinity();
        }
    }
    const int nf = static_cast<int>(free.size());
    if (nf == 0 || m <= nf) {
        for (int j : free) cov(j, j) = std::numeric_limits<double>::infinity();
        return cov;
    }
    Eigen::MatrixXd Jf(m, nf);
    for (int a = 0; a < nf; ++a) Jf.col(a) = res.jacobian.col(free[a]);
    // Column scaling keeps the eigen-decomposition well conditioned across units.
    Eigen::VectorXd scale(nf);
    for (int a = 0; a < nf; ++a) scale[a] = 1.0 / Jf.col(a).norm();
    const Eigen::MatrixXd Js = Jf * scale.asDiagonal();
    const Eigen::MatrixXd A = Js.transpose() * Js;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
    const Eigen::VectorXd ev = eig.eigenvalues();
    const double tol = 1e-12 * std::max(ev.maxCoeff(), 1e-300);
    Eigen::MatrixXd inv = Eigen::MatrixXd::Zero(nf, nf);
    std::vector<bool> singular(nf, false);
    for (int k = 0; k < nf; ++k) {
        const Eigen::VectorXd v = eig.eigenvectors().col(k);
        if (ev[k] > tol) {
            inv += (v * v.transpose()) / ev[k];
        } else {
            for (int a = 0; a < nf; ++a) {
                if (std::fabs(v[a]) > 1e-3) singular[a] = true;
            }
        }
    }
    const double s2 = res.residuals.squaredNorm() / (m - nf);
    for (int a = 0; a < nf; ++a) {
        for (int b = 0; b < nf; ++b) cov(free[a], free[b]) = s2 * inv(a, b) * scale[a] * scale[b];
    }
    for (int a = 0; a < nf; ++a) {
        if (singular[a]) cov(free[a], free[a]) = std::numeric_limits<double>::infinity();
    }
    return cov;
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
