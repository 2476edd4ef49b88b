#include "host/fit/ocv_stitch.h"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <ostream>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <Eigen/Dense>

#include "core/model/ocv.h"
#include "host/input_shape.h"
#include "host/fit/trace.h"
#include "host/report/summary.h"

namespace battsim {
namespace host {
namespace fit {

namespace {

// One flight's samples, per cell.
struct Rows {
    std::vector<double> v, i, fast, slow, q_ah;
    std::vector<double> weight;  // the rest's samples count more (the curve itself, no sag)
};

Rows load_rows(const Trace& t, int cells, double slow_time_s, const OcvStitchOptions& o) {
    Rows r;
    double q = 0.0, fast = 0.0, slow = 0.0;
    bool first = true;
    for (const TracePoint& p : t.points) {
        if (!p.valid) continue;
        const double i = p.current_a;
        const double dt = first ? 0.0 : static_cast<double>(p.dt_s);
        if (first) {
            fast = slow = i;
            first = false;
        } else {
            fast += (i - fast) * dt / (o.fast_time_s + dt);
            slow += (i - slow) * dt / (slow_time_s + dt);
            q += i * dt / 3600.0;
        }
        r.v.push_back(static_cast<double>(p.voltage_v) / cells);
        r.i.push_back(i);
        r.fast.push_back(fast);
        r.slow.push_back(slow);
        r.q_ah.push_back(q);
        r.weight.push_back(std::fabs(i) < 1.0 ? o.rest_weight : 1.0);
    }
    return r;
}

// Piecewise-linear curve over evenly spaced SOC points, continued linearly past both ends
// (a flight may start above the table's top or sag below its bottom).
struct Segment {
    int j = 0;       // left point
    double w = 0;    // weight of point j + 1 (outside 0..1 past the ends)
};
Segment segment(double soc, int points) {
    const double x = soc * (points - 1);
    Segment s;
    s.j = std::min(std::max(static_cast<int>(std::floor(x)), 0), points - 2);
    s.w = x - s.j;
    return s;
}
double curve_v(const std::vector<double>& k, double soc) {
    const Segment s = segment(soc, static_cast<int>(k.size()));
    return (1.0 - s.w) * k[s.j] + s.w * k[s.j + 1];
}
double curve_slope(const std::vector<double>& k, double soc) {
    const Segment s = segment(soc, static_cast<int>(k.size()));
    return (k[s.j + 1] - k[s.j]) * (k.size() - 1);
}

struct Shared {
    std::vector<double> knots;
    double r_fast = 0, r_slow = 0;  // per cell, shared by the fleet
    // Per cell, ohm per Ah drawn since the log began: a pack warms in flight and its
    // resistance falls; a constant resistance would read that as a curve rising under load.
    double r_warm = 0;
};

struct Flight {
    Rows rows;
    double s0 = 1.0;
    double r = 0.0;  // per cell: each flight's own ohmic resistance (packs and temperatures differ)
    bool test = false;
    double rest_start_v = 0, rest_end_v = 0;  // per cell, 0 = no rest there
};

double predict(const Shared& m, const Flight& f, size_t n, double soc) {
    return curve_v(m.knots, soc) - (f.r + m.r_warm * f.rows.q_ah[n]) * f.rows.i[n] - m.r_fast * f.rows.fast[n] -
           m.r_slow * f.rows.slow[n];
}
double residual(const Shared& m, const Flight& f, size_t n, double capacity_ah) {
    return f.rows.v[n] - predict(m, f, n, f.s0 - f.rows.q_ah[n] / capacity_ah);
}

// The mean voltage (ohmic sag added back) of the samples at rest (|I| < 1 A) at one end of
// a flight, over at most 50 samples; 0 if the log does not start (end) at rest.
double rest_voltage(const Rows& r, double r_cell, bool at_end) {
    const size_t n = r.v.size();
    double sum = 0.0;
    size_t count = 0;
    for (size_t k = 0; k < n && count < 50; ++k) {
        const size_t i = at_end ? n - 1 - k : k;
        if (std::fabs(r.i[i]) >= 1.0) break;
        sum += r.v[i] + r_cell * r.i[i];
        ++count;
    }
    return count >= 5 ? sum / static_cast<double>(count) : 0.0;
}

// Where each flight starts on the state-of-charge axis, before any table is known: the
// fullest start is full; a flight that starts at a voltage some placed flight rested at
// starts at that state of charge (interpolated among the placed rests); its own landing
// rest, the charge it drew further down, is then known too. Flights that start below every
// placed rest continue the chain at `slope_v` per unit of SOC. The landing rest is read
// before the polarisation has relaxed, so the chain leans low; the fit then corrects it.
void chain_starts(std::vector<Flight>& flights, double capacity_ah, double slope_v) {
    std::vector<std::pair<double, double>> known;  // (voltage, soc)
    std::vector<size_t> order;
    for (size_t n = 0; n < flights.size(); ++n)
        if (!flights[n].test && flights[n].rest_start_v > 0.0) order.push_back(n);
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return flights[a].rest_start_v > flights[b].rest_start_v; });
    for (size_t idx = 0; idx < order.size(); ++idx) {
        Flight& f = flights[order[idx]];
        double soc = 1.0;
        if (!known.empty()) {
            std::sort(known.begin(), known.end());
            const double v = f.rest_start_v;
            auto hi = std::lower_bound(known.begin(), known.end(), std::make_pair(v, -1e9));
            if (hi == known.begin()) soc = known.front().second - (known.front().first - v) / slope_v;
            else if (hi == known.end()) soc = std::min(1.0, known.back().second + (v - known.back().first) / slope_v);
            else {
                const auto lo = hi - 1;
                const double t = hi->first > lo->first ? (v - lo->first) / (hi->first - lo->first) : 0.5;
                soc = lo->second + t * (hi->second - lo->second);
            }
        }
        f.s0 = soc;
        known.push_back({f.rest_start_v, soc});
        if (f.rest_end_v > 0.0 && !f.rows.q_ah.empty())
            known.push_back({f.rest_end_v, soc - f.rows.q_ah.back() / capacity_ah});
    }
}

// Calls fn(flight index, flight, sample index, state of charge) for every sample of the
// fitted (not test) flights: the loop every sum over the data shares.
template <typename Fn>
void for_each_fitted_sample(const std::vector<Flight>& flights, double capacity_ah, Fn&& fn) {
    for (size_t fi = 0; fi < flights.size(); ++fi) {
        const Flight& f = flights[fi];
        if (f.test) continue;
        for (size_t n = 0; n < f.rows.v.size(); ++n) fn(fi, f, n, f.s0 - f.rows.q_ah[n] / capacity_ah);
    }
}

double huber_weight(double residual, double bound) {
    const double a = std::fabs(residual);
    return a <= bound ? 1.0 : bound / a;
}

// The robust scale of the fitted flights' residuals (1.4826 × median |r|), floored at 1 mV.
double robust_scale(const std::vector<Flight>& flights, const Shared& m, double capacity_ah) {
    std::vector<double> a;
    for_each_fitted_sample(flights, capacity_ah, [&](size_t, const Flight& f, size_t n, double) {
        a.push_back(std::fabs(residual(m, f, n, capacity_ah)));
    });
    if (a.empty()) return 1e-3;
    std::nth_element(a.begin(), a.begin() + static_cast<long>(a.size() / 2), a.end());
    return std::max(1.4826 * a[a.size() / 2], 1e-3);
}

// The weight of the empty point's correction in the second difference centred on point j.
// The empty point's prior is the user's empty voltage, not the curve's: a second difference
// through it (sigma 5 mV against its own 10 mV) had carried the correction's slope down to it,
// 209 mV (21 sigma) below it in the unit test's fleet. So the second difference at SOC 0.05
// takes the empty point at its prior: it still holds the point at 0.05, and no longer moves
// the empty one.
double empty_coefficient(size_t j) { return j == 1 ? 0.0 : 1.0; }

// The table's penalty, (t − x)ᵀP(t − x) with P = diag(1/σ²) (σ_empty at SOC 0, σ_prior
// elsewhere) + DᵀD/σ_smooth² (D: second differences), added to normal equations over the
// table's points (the first ones): a += P, b += P·t. `t` is the prior for a solve for the
// table itself, prior − table for a step.
void add_table_penalty(Eigen::MatrixXd& a, Eigen::VectorXd& b, const std::vector<double>& t, const OcvStitchOptions& o) {
    const int k = static_cast<int>(t.size());
    for (int j = 0; j < k; ++j) {
        const double sg = j == 0 ? o.empty_sigma_v : o.prior_sigma_v;
        a(j, j) += 1.0 / (sg * sg);
        b(j) += t[static_cast<size_t>(j)] / (sg * sg);
    }
    const double ws = 1.0 / (o.smooth_sigma_v * o.smooth_sigma_v);
    for (int j = 1; j + 1 < k; ++j) {
        const int idx[3] = {j - 1, j, j + 1};
        const double c[3] = {empty_coefficient(static_cast<size_t>(j)), -2.0, 1.0};
        double d2 = 0.0;
        for (int p = 0; p < 3; ++p) d2 += c[p] * t[static_cast<size_t>(idx[p])];
        for (int p = 0; p < 3; ++p) {
            b(idx[p]) += ws * c[p] * d2;
            for (int q = 0; q < 3; ++q) a(idx[p], idx[q]) += ws * c[p] * c[q];
        }
    }
}

// For fixed starting states, the table (unless `fixed_knots`), each fitted flight's ohmic
// resistance and the shared polarisation, by weighted linear least squares with the prior
// and smoothness terms on the table.
void solve_shared(std::vector<Flight>& flights, const std::vector<double>& prior, bool fixed_knots,
                  double capacity_ah, double scale, const OcvStitchOptions& o, Shared& m) {
    const int k = static_cast<int>(prior.size());
    const int nk = fixed_knots ? 0 : k;
    std::vector<int> column(flights.size(), -1);
    int np = nk;
    for (size_t f = 0; f < flights.size(); ++f)
        if (!flights[f].test) column[f] = np++;
    const int pf = np, ps = np + 1, pw = np + 2;
    np += 3;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(np, np);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(np);
    const double bound = o.huber_k * scale;
    const double data_w = 1.0 / (scale * scale);
    for_each_fitted_sample(flights, capacity_ah, [&](size_t fi, const Flight& f, size_t n, double soc) {
        const double h = huber_weight(residual(m, f, n, capacity_ah), bound) * data_w * f.rows.weight[n];
        const Segment s = segment(soc, k);
        double y = f.rows.v[n];
        // Only the two points, the flight's resistance, the polarisation and the warming are non-zero.
        const int idx[6] = {s.j, s.j + 1, column[fi], pf, ps, pw};
        const double row[6] = {1.0 - s.w, s.w, -f.rows.i[n], -f.rows.fast[n], -f.rows.slow[n], -f.rows.i[n] * f.rows.q_ah[n]};
        int first = 0;
        if (fixed_knots) {
            y -= (1.0 - s.w) * m.knots[s.j] + s.w * m.knots[s.j + 1];
            first = 2;
        }
        for (int p = first; p < 6; ++p) {
            b(idx[p]) += h * row[p] * y;
            for (int q = first; q < 6; ++q) a(idx[p], idx[q]) += h * row[p] * row[q];
        }
    });
    if (!fixed_knots) add_table_penalty(a, b, prior, o);
    // A whisper of ridge on the resistances keeps a log without current changes solvable.
    for (int p = nk; p < np; ++p) a(p, p) += 1e-9 * (a(p, p) + 1.0);
    const Eigen::VectorXd x = a.ldlt().solve(b);
    if (!x.allFinite()) throw std::invalid_argument("the OCV fit is singular: the logs hold too little current");
    if (!fixed_knots)
        for (int j = 0; j < k; ++j) m.knots[static_cast<size_t>(j)] = x(j);
    for (size_t f = 0; f < flights.size(); ++f)
        if (column[f] >= 0) flights[f].r = x(column[f]);
    m.r_fast = x(pf);
    m.r_slow = x(ps);
    m.r_warm = x(pw);
}

// The table must not fall as SOC rises (the monitor inverts it, and a fold lets a flight's
// start slide to either side): pool adjacent violators, weighted by what holds each point.
void make_monotone(std::vector<double>& k, const std::vector<double>& weight) {
    struct Block { double sum, w; size_t n; };
    std::vector<Block> blocks;
    for (size_t j = 0; j < k.size(); ++j) {
        const double w = std::max(weight[j], 1e-9);
        blocks.push_back({k[j] * w, w, 1});
        while (blocks.size() > 1) {
            const Block& b = blocks.back();
            const Block& a = blocks[blocks.size() - 2];
            if (a.sum / a.w <= b.sum / b.w) break;
            const Block merged{a.sum + b.sum, a.w + b.w, a.n + b.n};
            blocks.pop_back();
            blocks.back() = merged;
        }
    }
    size_t j = 0;
    for (const Block& b : blocks)
        for (size_t n = 0; n < b.n; ++n, ++j) k[j] = b.sum / b.w;
}

// Gauss-Newton on one flight's starting state of charge (and, for a test flight, its
// resistance), the shared parameters fixed. Returns the SOC step.
double update_flight(Flight& f, const Shared& m, double capacity_ah, double scale, const OcvStitchOptions& o,
                     bool with_resistance) {
    const double bound = o.huber_k * scale;
    double a00 = 0, a01 = 0, a11 = 0, b0 = 0, b1 = 0;
    for (size_t n = 0; n < f.rows.v.size(); ++n) {
        const double soc = f.s0 - f.rows.q_ah[n] / capacity_ah;
        const double res = residual(m, f, n, capacity_ah);
        const double g0 = curve_slope(m.knots, soc), g1 = -f.rows.i[n];
        const double h = huber_weight(res, bound) * f.rows.weight[n];
        a00 += h * g0 * g0;
        a01 += h * g0 * g1;
        a11 += h * g1 * g1;
        b0 += h * g0 * res;
        b1 += h * g1 * res;
    }
    double d0 = 0.0, d1 = 0.0;
    const double det = a00 * a11 - a01 * a01;
    if (with_resistance && det > 1e-12 * (a00 * a11 + 1e-30)) {
        d0 = (a11 * b0 - a01 * b1) / det;
        d1 = (a00 * b1 - a01 * b0) / det;
    } else if (a00 > 0.0) {
        d0 = b0 / a00;
    }
    const double step = std::max(-0.1, std::min(0.1, d0));
    f.s0 = std::max(-0.2, std::min(1.2, f.s0 + step));
    if (with_resistance) f.r += d1;
    return step;
}

double rms(const Flight& f, const Shared& m, double capacity_ah) {
    double s = 0.0;
    for (size_t n = 0; n < f.rows.v.size(); ++n) {
        const double res = residual(m, f, n, capacity_ah);
        s += res * res;
    }
    return f.rows.v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(f.rows.v.size()));
}

double pooled_rms(const std::vector<Flight>& flights, const Shared& m, double capacity_ah, bool test) {
    double s = 0.0;
    size_t n = 0;
    for (const Flight& f : flights) {
        if (f.test != test) continue;
        const double r = rms(f, m, capacity_ah);
        s += r * r * static_cast<double>(f.rows.v.size());
        n += f.rows.v.size();
    }
    return n ? std::sqrt(s / static_cast<double>(n)) : 0.0;
}

// Samples per table point (interpolation weight) of the fitted flights.
std::vector<double> support(const std::vector<Flight>& flights, double capacity_ah, int points) {
    std::vector<double> w(static_cast<size_t>(points), 0.0);
    for_each_fitted_sample(flights, capacity_ah, [&](size_t, const Flight&, size_t, double soc) {
        const Segment g = segment(soc, points);
        const double x = std::max(0.0, std::min(1.0, g.w));
        w[static_cast<size_t>(g.j)] += 1.0 - x;
        w[static_cast<size_t>(g.j + 1)] += x;
    });
    return w;
}

double median_resistance(const std::vector<Flight>& flights) {
    std::vector<double> r;
    for (const Flight& f : flights)
        if (!f.test) r.push_back(f.r);
    if (r.empty()) return 0.0;
    std::nth_element(r.begin(), r.begin() + static_cast<long>(r.size() / 2), r.end());
    return r[r.size() / 2];
}

// The penalised robust objective with the weights held: the fitted flights' weighted squared
// residuals over scale², plus the prior and smoothness terms on the table.
double objective(const std::vector<Flight>& flights, const std::vector<std::vector<double>>& h, const Shared& m,
                 const std::vector<double>& prior, double capacity_ah, double scale, const OcvStitchOptions& o) {
    double sum = 0.0;
    for_each_fitted_sample(flights, capacity_ah, [&](size_t fi, const Flight& f, size_t n, double) {
        const double r = residual(m, f, n, capacity_ah);
        sum += h[fi][n] * r * r;
    });
    sum /= scale * scale;
    const size_t k = prior.size();
    for (size_t j = 0; j < k; ++j) {
        const double sg = j == 0 ? o.empty_sigma_v : o.prior_sigma_v;
        const double d = (m.knots[j] - prior[j]) / sg;
        sum += d * d;
    }
    for (size_t j = 1; j + 1 < k; ++j) {
        const double d2 = empty_coefficient(j) * (m.knots[j - 1] - prior[j - 1]) - 2.0 * (m.knots[j] - prior[j]) + (m.knots[j + 1] - prior[j + 1]);
        sum += d2 * d2 / (o.smooth_sigma_v * o.smooth_sigma_v);
    }
    return sum;
}

void keep_rising(std::vector<double>& knots, const std::vector<Flight>& flights, double capacity_ah) {
    std::vector<double> w = support(flights, capacity_ah, static_cast<int>(knots.size()));
    for (double& x : w) x += 1.0;  // the prior's share where no flight reaches
    make_monotone(knots, w);
    for (size_t j = 1; j < knots.size(); ++j) knots[j] = std::max(knots[j], knots[j - 1] + 1e-4);
}

// Levenberg-Marquardt on everything at once: the table, each fitted flight's start and
// resistance, the shared polarisation and warming. Alternating the linear solve with the
// per-flight steps creeps along the valley where the table slides along itself while the
// starts follow, and stops short of the bottom; the joint step goes down it. The fullest
// flight's start stays where it is (the gauge).
int refine_jointly(std::vector<Flight>& flights, const std::vector<double>& prior, double capacity_ah,
                   const OcvStitchOptions& o, Shared& m) {
    const int k = static_cast<int>(prior.size());
    size_t fixed = flights.size();
    for (size_t f = 0; f < flights.size(); ++f)
        if (!flights[f].test && (fixed == flights.size() || flights[f].s0 > flights[fixed].s0)) fixed = f;
    std::vector<int> col_s(flights.size(), -1), col_r(flights.size(), -1);
    int np = k;
    for (size_t f = 0; f < flights.size(); ++f) {
        if (flights[f].test) continue;
        if (f != fixed || !o.fullest_is_full) col_s[f] = np++;
        col_r[f] = np++;
    }
    const int pf = np, ps = np + 1, pw = np + 2;
    np += 3;
    // The fullest start is full: no other may pass it (they had, to 1.015-1.036 on the Samsung
    // 30Q's five full discharges, which then ended above SOC 0 and bent the table's empty
    // point 27 sigma below its prior).
    const double top_soc = o.fullest_is_full && fixed < flights.size() ? flights[fixed].s0 : 1.2;
    double lambda = 1e-3;
    int it = 0;
    for (; it < o.iterations; ++it) {
        const double scale = robust_scale(flights, m, capacity_ah);
        const double bound = o.huber_k * scale;
        std::vector<std::vector<double>> h(flights.size());
        for (size_t fi = 0; fi < flights.size(); ++fi) h[fi].resize(flights[fi].rows.v.size());
        for_each_fitted_sample(flights, capacity_ah, [&](size_t fi, const Flight& f, size_t n, double) {
            h[fi][n] = huber_weight(residual(m, f, n, capacity_ah), bound) * f.rows.weight[n];
        });
        Eigen::MatrixXd a = Eigen::MatrixXd::Zero(np, np);
        Eigen::VectorXd b = Eigen::VectorXd::Zero(np);
        const double data_w = 1.0 / (scale * scale);
        for_each_fitted_sample(flights, capacity_ah, [&](size_t fi, const Flight& f, size_t n, double soc) {
            const Segment g = segment(soc, k);
            const double res = residual(m, f, n, capacity_ah);
            const double w = h[fi][n] * data_w;
            // d(prediction)/d(parameter); a fixed start has no column.
            const int idx[7] = {g.j, g.j + 1, col_s[fi], col_r[fi], pf, ps, pw};
            const double d[7] = {1.0 - g.w, g.w, curve_slope(m.knots, soc), -f.rows.i[n], -f.rows.fast[n], -f.rows.slow[n],
                                 -f.rows.i[n] * f.rows.q_ah[n]};
            for (int p = 0; p < 7; ++p) {
                if (idx[p] < 0) continue;
                b(idx[p]) += w * d[p] * res;
                for (int q = 0; q < 7; ++q)
                    if (idx[q] >= 0) a(idx[p], idx[q]) += w * d[p] * d[q];
            }
        });
        std::vector<double> towards(prior.size());  // the step's target: prior − table
        for (size_t j = 0; j < prior.size(); ++j) towards[j] = prior[j] - m.knots[j];
        add_table_penalty(a, b, towards, o);
        const double f0 = objective(flights, h, m, prior, capacity_ah, scale, o);
        bool accepted = false;
        double decrease = 0.0;
        for (int tries = 0; tries < 12 && !accepted; ++tries) {
            Eigen::MatrixXd damped = a;
            for (int p = 0; p < np; ++p) damped(p, p) += lambda * (a(p, p) + 1e-12);
            const Eigen::VectorXd x = damped.ldlt().solve(b);
            if (!x.allFinite()) {
                lambda *= 10.0;
                continue;
            }
            // Try the step in place (the flights hold all the samples: copying them per try
            // would cost more than the step); undo it if the objective does not fall.
            const Shared kept = m;
            std::vector<std::pair<double, double>> kept_flights;  // (s0, r)
            for (const Flight& f : flights) kept_flights.push_back({f.s0, f.r});
            for (int j = 0; j < k; ++j) m.knots[static_cast<size_t>(j)] += x(j);
            for (size_t f = 0; f < flights.size(); ++f) {
                if (col_s[f] >= 0) flights[f].s0 = std::max(-0.2, std::min(top_soc, flights[f].s0 + x(col_s[f])));
                if (col_r[f] >= 0) flights[f].r += x(col_r[f]);
            }
            m.r_fast += x(pf);
            m.r_slow += x(ps);
            m.r_warm += x(pw);
            keep_rising(m.knots, flights, capacity_ah);
            const double f1 = objective(flights, h, m, prior, capacity_ah, scale, o);
            if (f1 < f0) {
                decrease = (f0 - f1) / std::max(f0, 1e-30);
                lambda = std::max(lambda / 3.0, 1e-9);
                accepted = true;
            } else {
                m = kept;
                for (size_t f = 0; f < flights.size(); ++f) std::tie(flights[f].s0, flights[f].r) = kept_flights[f];
                lambda *= 5.0;
            }
        }
        if (!accepted || decrease < 1e-10) break;
    }
    return it;
}

// Fits the starting states and the shared parameters; returns the iterations run.
int fit(std::vector<Flight>& flights, const std::vector<double>& prior, bool fixed_knots, double capacity_ah,
        const OcvStitchOptions& o, Shared& m) {
    // Alternating steps bring the table and the starts near (and fit the resistances alone
    // on the config's curve); the joint refinement then finishes.
    const int alternations = fixed_knots ? o.iterations : std::min(o.iterations, 20);
    int it = 0;
    for (; it < alternations; ++it) {
        const double scale = robust_scale(flights, m, capacity_ah);
        const std::vector<double> before = m.knots;
        solve_shared(flights, prior, fixed_knots, capacity_ah, scale, o, m);
        if (!fixed_knots) keep_rising(m.knots, flights, capacity_ah);
        double moved = 0.0;
        for (size_t j = 0; j < before.size(); ++j) moved = std::max(moved, std::fabs(m.knots[j] - before[j]));
        double largest = -1e9, stepped = 0.0;
        for (Flight& f : flights) {
            if (f.test) continue;
            for (int g = 0; g < 3; ++g)
                stepped = std::max(stepped, std::fabs(update_flight(f, m, capacity_ah, scale, o, false)));
            largest = std::max(largest, f.s0);
        }
        if (o.fullest_is_full && !fixed_knots) {
            // Slide every start so the fullest one is full; the table follows at the next solve.
            const double shift = 1.0 - largest;
            for (Flight& f : flights)
                if (!f.test) f.s0 += shift;
            stepped = std::max(stepped, std::fabs(shift));
        }
        if (it > 2 && moved < 1e-6 && stepped < 1e-6) break;
    }
    if (!fixed_knots) it += refine_jointly(flights, prior, capacity_ah, o, m);
    // The test flights: their starting states only.
    const double scale = robust_scale(flights, m, capacity_ah);
    for (Flight& f : flights)
        if (f.test)
            for (int g = 0; g < 30; ++g)
                if (std::fabs(update_flight(f, m, capacity_ah, scale, o, true)) < 1e-7 && g > 3) break;
    return it;
}

// What a user must know before trusting the table.
void add_notes(OcvStitch& s, const std::vector<Flight>& flights, double config_resistance_ohm) {
    double lo = 1e9, hi = -1e9;
    for (const Flight& f : flights)
        if (!f.test) {
            lo = std::min(lo, f.s0);
            hi = std::max(hi, f.s0);
        }
    auto mv = [](double v) { return std::to_string(static_cast<int>(std::lround(v * 1000.0))) + " mV"; };
    const long fitted = std::count_if(flights.begin(), flights.end(), [](const Flight& f) { return !f.test; });
    if (fitted == 1)
        s.notes.push_back("one flight: nothing stitches its slice to another's, so the table's shape cannot be told "
                          "from the sag's model; fit flights that take off at different charges");
    else if (hi - lo < 0.15)
        s.notes.push_back("the flights start within " + std::to_string(static_cast<int>(std::lround((hi - lo) * 100.0))) +
                          " % of charge of each other: nothing stitches their slices, so the table's shape cannot be told "
                          "from the sag's model; fit flights that take off at different charges");
    if (s.rms_v >= s.rms_before_v)
        s.notes.push_back("the table fits these flights no better than the config's curve (" + mv(s.rms_v) + " against " +
                          mv(s.rms_before_v) + " per cell): keep the config's");
    if (s.test_rms_v > 0.0 && s.test_rms_v >= s.test_rms_before_v)
        s.notes.push_back("on the test flights the table is no better than the config's curve (" + mv(s.test_rms_v) +
                          " against " + mv(s.test_rms_before_v) + " per cell)");
    // Where no sample reached, the table follows the correction's slope from where they did,
    // and nothing checks it (ground-only logs had moved it 85 mV at SOC 0.85).
    double moved_v = 0.0;
    std::string where;
    const size_t k = s.table_v.size();
    // The empty end (j = 0) is left out: no flight reaches it, and its own prior pins it.
    for (size_t j = 1; j < k && j < s.support.size() && j < s.prior_v.size(); ++j) {
        const double d = std::fabs(s.table_v[j] - s.prior_v[j]);
        if (s.support[j] > 0.5 || d < 0.01) continue;
        moved_v = std::max(moved_v, d);
        char soc[16];
        std::snprintf(soc, sizeof soc, "%.2f", k > 1 ? static_cast<double>(j) / static_cast<double>(k - 1) : 0.0);
        where += (where.empty() ? "" : ", ") + std::string(soc);
    }
    if (moved_v > 0.0)
        s.notes.push_back("the table moved by up to " + mv(moved_v) + " per cell at state-of-charge points no sample reached (" +
                          where + "): that is the fit's extrapolation, not a measurement; keep the config's curve there "
                          "or fly those charges");
    if (s.fast_ohm < 0.0 || s.slow_ohm < 0.0 || s.resistance_ohm < 0.0)
    {
        auto mohm = [](double r) { return std::to_string(static_cast<int>(std::lround(r * 1000.0))) + " mOhm"; };
        s.notes.push_back("a fitted pack resistance is negative (ohmic " + mohm(s.resistance_ohm) + ", fast " +
                          mohm(s.fast_ohm) + ", slow " + mohm(s.slow_ohm) +
                          "): no pack has one; the flights hold too few load changes to fit them");
    }
    // On the config's curve the resistances are only a baseline, and they soak up what the curve
    // misses: a make-config curve 527 mV per cell off the Samsung 30Q's discharges had printed
    // -0.671 ohm ohmic and -0.899 ohm slow without a word. Said beyond half the config's
    // resistance below zero: a millohm either side of it is the fit's noise.
    const double below_ohm = -0.5 * config_resistance_ohm;
    if (s.fast_before_ohm < below_ohm || s.slow_before_ohm < below_ohm || s.resistance_before_ohm < below_ohm) {
        auto mohm = [](double r) { return std::to_string(static_cast<int>(std::lround(r * 1000.0))) + " mOhm"; };
        s.notes.push_back("on the config's curve a fitted pack resistance is negative (ohmic " + mohm(s.resistance_before_ohm) +
                          ", fast " + mohm(s.fast_before_ohm) + ", slow " + mohm(s.slow_before_ohm) +
                          "): no pack has one; they soak up what that curve misses (" + mv(s.rms_before_v) +
                          " per cell), so the config curve's figures describe that curve, not the pack");
    }
    if (s.soc_min < -0.02)
        s.notes.push_back("the flights span " + std::to_string(static_cast<int>(std::lround((s.soc_max - s.soc_min) * 100.0))) +
                          " % of the config's capacity: the packs hold more than it says, or the starts are misplaced");
}

// Refuses (ImplausibleTable) a table no pack has, before anyone writes it: a point far
// outside the voltages measured and the config's curve, a fold, an empty point far below the
// config's minimum voltage, or a point no sample reached far from the config's curve (the
// prior that is all it has). The HPPC log of the Panasonic 18650PF, whose clock jumps over the
// discharges between its pulse sets, had written 0.93 V at SOC 0 and 1.21 V from 5 to 45 %,
// exit 0. `measured_*`: the fitted samples' per-cell voltage span; `clock_jumps`: per fitted
// log with any, its gaps over 60 s (the charge drawn across one is not counted).
void check_plausible(const OcvStitch& s, double measured_min_v, double measured_max_v, double min_cell_v,
                     const std::vector<std::pair<std::string, int>>& clock_jumps, const std::string& file,
                     const OcvStitchOptions& o) {
    const size_t k = s.table_v.size();
    if (k < 2) return;
    const auto soc = [&](size_t j) {
        char b[16];
        std::snprintf(b, sizeof b, "%.2f", static_cast<double>(j) / static_cast<double>(k - 1));
        return std::string(b);
    };
    const auto volts = [](double v) {
        char b[24];
        std::snprintf(b, sizeof b, "%.3f V", v);
        return std::string(b);
    };
    auto mv = [](double v) { return std::to_string(static_cast<int>(std::lround(v * 1000.0))) + " mV"; };
    std::vector<std::string> wrong;
    // 3 prior sigmas past both the measured voltages and the config's curve: nothing measured
    // or assumed puts a point there.
    const double margin_v = 3.0 * o.prior_sigma_v;
    const double lo_v = std::min(measured_min_v, *std::min_element(s.prior_v.begin(), s.prior_v.end())) - margin_v;
    const double hi_v = std::max(measured_max_v, *std::max_element(s.prior_v.begin(), s.prior_v.end())) + margin_v;
    size_t worst = k;
    double worst_by_v = 0.0;
    for (size_t j = 0; j < k; ++j) {
        const double by_v = std::max(lo_v - s.table_v[j], s.table_v[j] - hi_v);
        if (by_v > worst_by_v) {
            worst_by_v = by_v;
            worst = j;
        }
    }
    if (worst < k)
        wrong.push_back("at SOC " + soc(worst) + " it reads " + volts(s.table_v[worst]) + " per cell, " + mv(worst_by_v) +
                        " outside the voltages measured (" + volts(measured_min_v) + " .. " + volts(measured_max_v) +
                        ") and the config's curve, widened by " + mv(margin_v) + " (3 x --prior-sigma)");
    for (size_t j = 1; j < k; ++j)
        if (!(s.table_v[j] > s.table_v[j - 1])) {
            wrong.push_back("it falls from " + volts(s.table_v[j - 1]) + " at SOC " + soc(j - 1) + " to " + volts(s.table_v[j]) +
                            " at " + soc(j) + " (expected rising)");
            break;
        }
    const double empty_floor_v = min_cell_v - 5.0 * o.empty_sigma_v;
    if (s.table_v[0] < empty_floor_v)
        wrong.push_back("its empty point (SOC 0) reads " + volts(s.table_v[0]) + " per cell, " + mv(min_cell_v - s.table_v[0]) +
                        " below the config's minimum voltage " + volts(min_cell_v) + " (expected no more than " +
                        mv(5.0 * o.empty_sigma_v) + " below, 5 x --empty-sigma)");
    // Where no sample reached, the prior is all there is: a point far from it was dragged
    // there by its neighbours (the rising constraint, the smoothness), not measured.
    double dragged_v = 0.0, dragged_sigmas = 0.0;
    std::string where;
    for (size_t j = 0; j < k && j < s.support.size(); ++j) {
        if (s.support[j] > 0.5) continue;
        const double sigma_v = j == 0 ? o.empty_sigma_v : o.prior_sigma_v;
        const double d = std::fabs(s.table_v[j] - s.prior_v[j]);
        if (d <= 5.0 * sigma_v) continue;
        if (d / sigma_v > dragged_sigmas) {
            dragged_sigmas = d / sigma_v;
            dragged_v = d;
        }
        where += (where.empty() ? "" : ", ") + soc(j);
    }
    if (!where.empty())
        wrong.push_back("at SOC " + where + ", which no sample reached, it lies up to " + mv(dragged_v) + " per cell (" +
                        std::to_string(static_cast<int>(std::lround(dragged_sigmas))) +
                        " sigma) from the config's curve, its only prior there (expected within 5 sigma: --prior-sigma, "
                        "--empty-sigma at SOC 0)");
    if (wrong.empty()) return;
    std::string what = "the stitched OCV table is one no pack has, so it is not written: ";
    for (size_t n = 0; n < wrong.size(); ++n) what += (n ? "; " : "") + wrong[n];
    if (!clock_jumps.empty()) {
        what += ". The log's clock jumps (";
        for (size_t n = 0; n < clock_jumps.size(); ++n)
            what += (n ? ", " : "") + (clock_jumps.size() > 1 || file.empty() ? clock_jumps[n].first + ": " : std::string()) +
                    std::to_string(clock_jumps[n].second) + " gap(s) over 60 s";
        what += "): the charge drawn across a gap is not counted, so the samples after it sit at the wrong state of "
                "charge; fit logs without gaps, or each session apart";
    } else {
        char capacity[32];
        std::snprintf(capacity, sizeof capacity, "%.3g Ah", s.capacity_ah);
        what += ". The samples' state of charge (the charge counted against the config's " + std::string(capacity) +
                ") does not match their voltage: is the config this pack's (capacity, cells, minimum voltage), and "
                "the current's sign right?";
    }
    throw ImplausibleTable(file, what);
}

}  // namespace

OcvStitch stitch_ocv(const std::vector<std::string>& logs, const std::vector<std::string>& test_logs,
                     const ReaderOptions& reader, const LoadedConfig& config, const OcvStitchOptions& o) {
    std::vector<OcvStitchLog> all;
    for (const std::string& p : logs) all.push_back({p, reader, false});
    for (const std::string& p : test_logs) all.push_back({p, reader, true});
    return stitch_ocv(all, config, o);
}

OcvStitch stitch_ocv(const std::vector<OcvStitchLog>& logs, const LoadedConfig& config, const OcvStitchOptions& o,
                     std::ostream* notes_out) {
    if (o.points < 2 || o.points > core::kOcvTableMaxPoints)
        throw std::invalid_argument("--points: expected 2.." + std::to_string(core::kOcvTableMaxPoints));
    if (!(o.fast_time_s > 0.0) || !(o.slow_time_s >= 0.0) || !(o.prior_sigma_v > 0.0) || !(o.smooth_sigma_v > 0.0) || !(o.empty_sigma_v > 0.0) || !(o.rest_weight > 0.0) ||
        !(o.huber_k > 0.0) || o.iterations < 1)
        throw std::invalid_argument("OCV fit options: time constants, sigmas and huber_k must be > 0, iterations >= 1");
    OcvStitch s;
    s.fast_time_s = o.fast_time_s;
    const core::MonitorConfig& mc = config.monitor;
    s.cells = mc.cells_in_series;
    s.capacity_ah = mc.battery.capacity_ah;
    if (!(s.capacity_ah > 0.0)) throw std::invalid_argument("the config's capacity_ah must be > 0");

    core::OcvCurve prior_curve;
    prior_curve.configure(o.prior_from_table ? mc.joint.ocv : core::OcvTable{}, s.cells, mc.battery);
    // A model curve runs into its pole at empty; the user's empty voltage is the better guess.
    const double empty_v = static_cast<double>(mc.min_voltage_v) / s.cells;
    for (int j = 0; j < o.points; ++j) {
        const double v = static_cast<double>(prior_curve.voltage_v(static_cast<float>(j) / (o.points - 1))) / s.cells;
        s.prior_v.push_back(std::max(v, empty_v));
    }
    for (int j = o.points - 2; j >= 0; --j)  // and never above the next point
        s.prior_v[static_cast<size_t>(j)] = std::min(s.prior_v[static_cast<size_t>(j)], s.prior_v[static_cast<size_t>(j) + 1]);

    // A log with fewer than 10 valid samples says nothing of the curve: left out, and said.
    size_t said = 0;  // notes written to notes_out
    std::vector<Trace> traces;
    std::vector<bool> is_test;
    for (const OcvStitchLog& log : logs) {
        Trace t = load_trace(log.path, log.reader, config);
        // What replay says of the log (a config for another pack stitches a table no cell has:
        // a 6S config on 4S flights, 2.77 V per cell at full; a current of the other sign
        // stitches a charge), said as it is read: a fit that then fails for want of data
        // says why.
        for (const std::string& note : t.notes) s.notes.push_back(log.path + ": " + note);
        size_t valid = 0;
        for (const TracePoint& p : t.points) valid += p.valid;
        if (valid < 10) s.notes.push_back(log.path + ": " + std::to_string(valid) + " valid samples, left out");
        if (notes_out)
            for (; said < s.notes.size(); ++said) *notes_out << "battsim fit-ocv: note: " << s.notes[said] << "\n";
        if (valid < 10) continue;
        traces.push_back(std::move(t));
        is_test.push_back(log.test);
    }
    if (std::find(is_test.begin(), is_test.end(), false) == is_test.end())
        throw TooLittleData(logs.size() == 1 ? logs[0].path : std::string(), "no log to fit holds 10 valid samples");
    // The curve is read over the charge the flights draw: logs that never fly had "fitted" a
    // resistance below zero and a state of charge above 1, exit 0.
    double flown_ah = 0;
    for (size_t n = 0; n < traces.size(); ++n)
        for (const TracePoint& p : traces[n].points)
            if (!is_test[n] && p.valid && p.flying) flown_ah += static_cast<double>(p.current_a) * p.dt_s / 3600.0;
    if (!(flown_ah >= 0.02 * s.capacity_ah)) {
        char what[160];
        std::snprintf(what, sizeof what,
                      "the logs to fit draw %.3f Ah in flight, under 2 %% of the config's %.3g Ah: the OCV is read over the "
                      "charge flights draw",
                      flown_ah, s.capacity_ah);
        throw TooLittleData(logs.size() == 1 ? logs[0].path : std::string(), what);
    }

    // One fit per candidate slow time constant; the one whose fit leaves the smallest error wins.
    const double r_config = mc.battery.internal_resistance_ohm / s.cells;
    struct Run {
        double slow_time_s = 0;
        std::vector<Flight> flights, on_prior;
        Shared before, after;
        int iterations = 0;
        double rms_v = 0;
    };
    std::vector<double> slow_times = o.slow_time_s > 0.0 ? std::vector<double>{o.slow_time_s} : std::vector<double>{20, 30, 45, 60, 90};
    Run best;
    bool have = false;
    for (double slow_time_s : slow_times) {
        Run run;
        run.slow_time_s = slow_time_s;
        for (size_t n = 0; n < traces.size(); ++n) {
            Flight f;
            f.test = is_test[n];
            f.rows = load_rows(traces[n], s.cells, slow_time_s, o);
            // Start: where the config's curve puts the flight's first (resting) voltage.
            f.r = r_config;
            f.rest_start_v = rest_voltage(f.rows, r_config, false);
            f.rest_end_v = rest_voltage(f.rows, r_config, true);
            if (!f.rows.v.empty())
                f.s0 = prior_curve.soc_at_voltage(static_cast<float>((f.rows.v[0] + r_config * f.rows.i[0]) * s.cells));
            run.flights.push_back(std::move(f));
        }
        run.before.knots = s.prior_v;
        run.on_prior = run.flights;
        fit(run.on_prior, s.prior_v, true, s.capacity_ah, o, run.before);
        run.after = run.before;
        for (size_t n = 0; n < run.flights.size(); ++n) {
            run.flights[n].s0 = run.on_prior[n].s0;
            run.flights[n].r = run.on_prior[n].r;
        }
        if (o.fullest_is_full) chain_starts(run.flights, s.capacity_ah, o.chain_slope_v);
        for (Flight& f : run.flights)
            if (f.test) f.s0 = std::max(0.0, std::min(1.0, f.s0));
        run.iterations = fit(run.flights, s.prior_v, false, s.capacity_ah, o, run.after);
        run.rms_v = pooled_rms(run.flights, run.after, s.capacity_ah, false);
        s.slow_time_candidates.push_back({slow_time_s, run.rms_v});
        if (!have || run.rms_v < best.rms_v) {
            best = std::move(run);
            have = true;
        }
    }
    std::vector<Flight>& flights = best.flights;
    const std::vector<Flight>& on_prior = best.on_prior;
    const Shared& before = best.before;
    const Shared& after = best.after;
    s.slow_time_s = best.slow_time_s;
    s.iterations = best.iterations;

    s.table_v = after.knots;  // rising: fit() keeps it so
    s.support = support(flights, s.capacity_ah, o.points);
    s.soc_min = 1e9;
    s.soc_max = -1e9;
    for (const Flight& f : flights) {
        if (f.test) continue;
        for (double q : f.rows.q_ah) {
            s.soc_min = std::min(s.soc_min, f.s0 - q / s.capacity_ah);
            s.soc_max = std::max(s.soc_max, f.s0 - q / s.capacity_ah);
        }
    }
    s.resistance_before_ohm = median_resistance(on_prior) * s.cells;
    s.fast_before_ohm = before.r_fast * s.cells;
    s.slow_before_ohm = before.r_slow * s.cells;
    s.resistance_ohm = median_resistance(flights) * s.cells;
    s.fast_ohm = after.r_fast * s.cells;
    s.slow_ohm = after.r_slow * s.cells;
    s.rms_before_v = pooled_rms(on_prior, before, s.capacity_ah, false);
    s.rms_v = pooled_rms(flights, after, s.capacity_ah, false);
    s.test_rms_before_v = pooled_rms(on_prior, before, s.capacity_ah, true);
    s.test_rms_v = pooled_rms(flights, after, s.capacity_ah, true);
    add_notes(s, flights, mc.battery.internal_resistance_ohm);
    if (notes_out)
        for (; said < s.notes.size(); ++said) *notes_out << "battsim fit-ocv: note: " << s.notes[said] << "\n";
    {
        double measured_min_v = 1e9, measured_max_v = -1e9;
        for (const Flight& f : flights)
            if (!f.test)
                for (double v : f.rows.v) {
                    measured_min_v = std::min(measured_min_v, v);
                    measured_max_v = std::max(measured_max_v, v);
                }
        std::vector<std::pair<std::string, int>> clock_jumps;
        for (size_t n = 0; n < traces.size(); ++n) {
            if (is_test[n]) continue;
            int gaps = 0;
            double last_s = -1.0;
            for (const TracePoint& p : traces[n].points) {
                if (!p.valid) continue;
                if (last_s >= 0.0 && p.time_s - last_s > InputShape::kLongestGapS) ++gaps;
                last_s = p.time_s;
            }
            if (gaps > 0) clock_jumps.push_back({traces[n].path, gaps});
        }
        size_t fitted_logs = 0;
        for (bool t : is_test) fitted_logs += !t;
        std::string file;
        for (size_t n = 0; n < traces.size() && fitted_logs == 1; ++n)
            if (!is_test[n]) file = traces[n].path;
        check_plausible(s, measured_min_v, measured_max_v, empty_v, clock_jumps, file, o);
    }
    for (size_t n = 0; n < traces.size(); ++n) {
        OcvStitchFlight out;
        out.log = traces[n].path;
        out.test = is_test[n];
        out.samples = flights[n].rows.v.size();
        out.charge_ah = flights[n].rows.q_ah.empty() ? 0.0 : flights[n].rows.q_ah.back();
        const Flight& f = flights[n];
        const size_t step = std::max<size_t>(1, f.rows.v.size() / 600);
        for (size_t k = 0; k < f.rows.v.size(); k += step) {
            const double soc = f.s0 - f.rows.q_ah[k] / s.capacity_ah;
            out.soc.push_back(soc);
            out.ocv_v.push_back(f.rows.v[k] + (curve_v(after.knots, soc) - predict(after, f, k, soc)));  // + the sag
        }
        s.flights.push_back(out);
    }
    for (size_t n = 0; n < flights.size(); ++n) {
        OcvStitchFlight& out = s.flights[n];
        out.start_soc_before = on_prior[n].s0;
        out.start_soc = flights[n].s0;
        out.rms_before_v = rms(on_prior[n], before, s.capacity_ah);
        out.rms_v = rms(flights[n], after, s.capacity_ah);
        out.resistance_before_ohm = on_prior[n].r * s.cells;
        out.resistance_ohm = flights[n].r * s.cells;
    }
    return s;
}

void hold_out_every(std::vector<OcvStitchLog>& logs, unsigned every) {
    if (every == 0) return;
    for (std::size_t k = 0; k < logs.size(); ++k) logs[k].test = k % every == 1 % every;
}

LoadedConfig with_stitched_table(const LoadedConfig& config, const OcvStitch& s) {
    LoadedConfig out = config;
    core::OcvTable& t = out.monitor.joint.ocv;
    t.points = static_cast<int>(s.table_v.size());
    for (size_t j = 0; j < s.table_v.size(); ++j) t.cell_voltage_v[j] = static_cast<float>(s.table_v[j]);
    return out;
}

nlohmann::json to_json(const OcvStitch& s) {
    using nlohmann::json;
    // Six significant figures, as the other reports (round_sig): 1 µV per cell, and no
    // 0.009217188882135187 ohm. The config written keeps the fit's own values.
    const auto r = [](double x) { return round_sig(x); };
    const auto rs = [&](const std::vector<double>& v) {
        json a = json::array();
        for (double x : v) a.push_back(r(x));
        return a;
    };
    json flights = json::array();
    bool any_test = false;  // without --test logs there is no held-out error (it had read 0.0)
    for (const OcvStitchFlight& f : s.flights) any_test = any_test || f.test;
    for (const OcvStitchFlight& f : s.flights)
        flights.push_back({{"log", f.log},
                           {"test", f.test},
                           {"samples", f.samples},
                           {"charge_ah", r(f.charge_ah)},
                           {"start_soc", {{"config_curve", r(f.start_soc_before)}, {"fitted", r(f.start_soc)}}},
                           {"rms_v_per_cell", {{"config_curve", r(f.rms_before_v)}, {"fitted", r(f.rms_v)}}},
                           {"pack_resistance_ohm", {{"config_curve", r(f.resistance_before_ohm)}, {"fitted", r(f.resistance_ohm)}}}});
    return {{"schema", "battsim.ocv_stitch"},
            {"schema_version", 1},
            {"battsim_version", BATTSIM_VERSION},  // as every other report: which release wrote it
            {"cells", s.cells},
            {"capacity_ah", r(s.capacity_ah)},
            {"ocv_cell_voltage_v", {{"config_curve", rs(s.prior_v)}, {"fitted", rs(s.table_v)}}},
            {"support_samples", rs(s.support)},
            {"soc_span", {r(s.soc_min), r(s.soc_max)}},
            {"pack_resistance_ohm",
             {{"config_curve", {{"ohmic_median", r(s.resistance_before_ohm)}, {"fast", r(s.fast_before_ohm)}, {"slow", r(s.slow_before_ohm)}}},
              {"fitted", {{"ohmic_median", r(s.resistance_ohm)}, {"fast", r(s.fast_ohm)}, {"slow", r(s.slow_ohm)}}}}},
            {"rms_v_per_cell",
             {{"config_curve", r(s.rms_before_v)}, {"fitted", r(s.rms_v)}, {"test_config_curve", any_test ? json(r(s.test_rms_before_v)) : json(nullptr)},
              {"test_fitted", any_test ? json(r(s.test_rms_v)) : json(nullptr)}}},
            {"iterations", s.iterations},
            {"polarisation_time_s", {{"fast", r(s.fast_time_s)}, {"slow", r(s.slow_time_s)}}},
            {"slow_time_candidates", [&] {
                 json a = json::array();
                 for (const auto& c : s.slow_time_candidates) a.push_back({{"slow_time_s", r(c.first)}, {"rms_v_per_cell", r(c.second)}});
                 return a;
             }()},
            {"notes", s.notes},
            {"flights", flights}};
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
