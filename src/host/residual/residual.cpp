#include "host/residual/residual.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <ostream>

#include "host/fit/effect_names.h"
#include "host/io/atomic_file.h"
#include "host/parallel.h"
#include "host/plot/plot.h"
#include "host/report/summary.h"

namespace battsim {
namespace host {
namespace residual {

namespace {

using fit::ErrorStats;
using fit::ModelSpec;
using fit::Trace;

struct Split {
    std::vector<std::vector<uint8_t>> fit, held;
    std::vector<std::vector<int>> block;  // per point: block number, −1 outside the window
    int blocks = 0;
};

Split make_split(const std::vector<Trace>& traces, fit::Window window, fit::InitialMode mode, int blocks) {
    Split s;
    s.blocks = blocks;
    for (const Trace& t : traces) {
        std::vector<size_t> idx;
        for (size_t k = 0; k < t.points.size(); ++k) {
            if (fit::in_window(t, k, window, mode)) idx.push_back(k);
        }
        std::vector<uint8_t> f(t.points.size(), 0), h(t.points.size(), 0);
        std::vector<int> b(t.points.size(), -1);
        for (size_t i = 0; i < idx.size(); ++i) {
            const int block = static_cast<int>(i * static_cast<size_t>(blocks) / idx.size());
            b[idx[i]] = block;
            // Odd blocks are held out, except the last: the fit always sees both ends of the
            // log, so a held-out block never asks the model to extrapolate in charge (past the
            // Q/(Q − it) pole the fit could not see).
            const bool held = block % 2 == 1 && block != blocks - 1;
            (held ? h : f)[idx[i]] = 1;
        }
        s.fit.push_back(std::move(f));
        s.held.push_back(std::move(h));
        s.block.push_back(std::move(b));
    }
    return s;
}

// A model state: one spec per log and the charge drawn at each log's settle sample.
struct State {
    std::vector<ModelSpec> specs;
    std::vector<float> q0;
    std::vector<std::string> params;
};

struct Eval {
    StageStats stats;
    std::vector<double> block_sq;  // per (log, block): Σe² over held-out points
    std::vector<size_t> block_n;
    double fit_mse = 0, held_mse = 0;
    std::vector<std::vector<float>> model_v;
};

ErrorStats pooled(const std::vector<Trace>& traces, const std::vector<std::vector<float>>& model_v, fit::Window w,
                  const std::vector<std::vector<uint8_t>>* masks) {
    ErrorStats total;
    double sum = 0, abs_sum = 0, sq = 0;
    for (size_t t = 0; t < traces.size(); ++t) {
        const ErrorStats s = fit::error_stats(traces[t], model_v[t], w, masks ? &(*masks)[t] : nullptr);
        total.n += s.n;
        sum += s.mean_v * s.n;
        abs_sum += s.mae_v * s.n;
        sq += s.rmse_v * s.rmse_v * s.n;
        total.max_abs_v = std::max(total.max_abs_v, s.max_abs_v);
    }
    if (total.n > 0) {
        total.mean_v = sum / total.n;
        total.mae_v = abs_sum / total.n;
        total.rmse_v = std::sqrt(sq / total.n);
    }
    return total;
}

Eval evaluate_state(const std::vector<Trace>& traces, const State& st, fit::InitialMode mode, const Split& split,
                    fit::Window window) {
    Eval ev;
    ev.model_v.resize(traces.size());
    ev.block_sq.assign(traces.size() * split.blocks, 0.0);
    ev.block_n.assign(traces.size() * split.blocks, 0);
    for (size_t t = 0; t < traces.size(); ++t) {
        fit::SimResult sim;
        fit::simulate(traces[t], st.specs[t], mode, t < st.q0.size() ? st.q0[t] : 0.0f, sim);
        ev.model_v[t] = sim.model_v;
        for (size_t k = 0; k < traces[t].points.size(); ++k) {
            if (!split.held[t][k] || !std::isfinite(sim.model_v[k])) continue;
            const double e = static_cast<double>(traces[t].points[k].voltage_v) - sim.model_v[k];
            const size_t b = t * split.blocks + split.block[t][k];
            ev.block_sq[b] += e * e;
            ++ev.block_n[b];
        }
    }
    ev.stats.all = pooled(traces, ev.model_v, window, nullptr);
    ev.stats.fit = pooled(traces, ev.model_v, window, &split.fit);
    ev.stats.heldout = pooled(traces, ev.model_v, window, &split.held);
    ev.fit_mse = ev.stats.fit.rmse_v * ev.stats.fit.rmse_v;
    ev.held_mse = ev.stats.heldout.rmse_v * ev.stats.heldout.rmse_v;
    return ev;
}

// One-sided Wilcoxon signed-rank test that the differences d (base − candidate block MSE)
// lean positive: exact distribution of W+ by counting sign patterns (ranks doubled so ties'
// average ranks stay integers). Blocks where nothing changed are left out.
double wilcoxon_p(std::vector<double> d) {
    d.erase(std::remove(d.begin(), d.end(), 0.0), d.end());
    const size_t n = d.size();
    if (n == 0) return 1.0;
    std::vector<size_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return std::fabs(d[a]) < std::fabs(d[b]); });
    std::vector<int> rank2(n);  // 2 × rank
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j + 1 < n && std::fabs(d[order[j + 1]]) == std::fabs(d[order[i]])) ++j;
        for (size_t k = i; k <= j; ++k) rank2[order[k]] = static_cast<int>(i + j + 2);  // (i+1 + j+1)
        i = j + 1;
    }
    int w = 0, total = 0;
    for (size_t i = 0; i < n; ++i) {
        total += rank2[i];
        if (d[i] > 0) w += rank2[i];
    }
    // counts[s] = number of sign patterns with W+ (doubled) = s, as probabilities.
    std::vector<double> p(static_cast<size_t>(total) + 1, 0.0);
    p[0] = 1.0;
    for (size_t i = 0; i < n; ++i) {
        for (int s = total; s >= 0; --s) {
            const double without = p[s] * 0.5;
            const double with = s >= rank2[i] ? p[s - rank2[i]] * 0.5 : 0.0;
            p[s] = without + with;
        }
    }
    double tail = 0;
    for (int s = w; s <= total; ++s) tail += p[s];
    return std::min(1.0, tail);
}

void compare(const Eval& base, const Eval& cand, size_t blocks_per_log, CandidateScore& c) {
    c.fit_rmse_v = cand.stats.fit.rmse_v;
    c.heldout_rmse_v = cand.stats.heldout.rmse_v;
    c.gain = base.held_mse > 0 ? 1.0 - cand.held_mse / base.held_mse : 0.0;
    int better = 0, changed = 0;
    std::vector<double> d;
    std::vector<size_t> log_of;  // neighbours are paired within a log only
    for (size_t b = 0; b < base.block_sq.size(); ++b) {
        if (base.block_n[b] == 0) continue;
        const double mb = base.block_sq[b] / base.block_n[b];
        const double mc = cand.block_sq[b] / std::max<size_t>(cand.block_n[b], 1);
        d.push_back(mb - mc);
        log_of.push_back(b / blocks_per_log);
        if (mc == mb) continue;
        ++changed;
        if (mc < mb) ++better;
    }
    c.blocks_better = better;
    c.blocks = changed;
    c.p_value = wilcoxon_p(d);
    // The test counts blocks as independent; short blocks share the effect's slow course, so
    // neighbouring improvements correlate and the p-value reads too small (said in the verdict).
    double mean = 0;
    for (double x : d) mean += x;
    mean = d.empty() ? 0 : mean / d.size();
    double num = 0, den = 0;
    c.block_pairs = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        den += (d[i] - mean) * (d[i] - mean);
        if (i > 0 && log_of[i] == log_of[i - 1]) {
            num += (d[i] - mean) * (d[i - 1] - mean);
            ++c.block_pairs;
        }
    }
    c.block_lag1_r = den > 0 && c.block_pairs > 0 ? num / den * d.size() / c.block_pairs : 0.0;
}

// The noise level the priors are weighed against: the starting model's RMSE on the points
// being fitted (at least 1 mV).
double prior_noise_v(const std::vector<Trace>& traces, const State& st, const std::vector<std::vector<uint8_t>>* mask,
                     const ResidualOptions& o) {
    double sq = 0;
    size_t n = 0;
    for (size_t t = 0; t < traces.size(); ++t) {
        fit::SimResult sim;
        fit::simulate(traces[t], st.specs[t], o.initial, st.q0[t], sim);
        const ErrorStats s = fit::error_stats(traces[t], sim.model_v, o.window, mask ? &(*mask)[t] : nullptr);
        sq += s.rmse_v * s.rmse_v * s.n;
        n += s.n;
    }
    return std::max(n ? std::sqrt(sq / n) : 0.0, 1e-3);
}

State refit(const std::vector<Trace>& traces, const State& from, const std::vector<std::string>& params,
            const std::vector<std::vector<uint8_t>>* mask, const ResidualOptions& o,
            fit::InitialMode mode = fit::InitialMode::Free) {
    fit::FitOptions fo;
    for (const std::string& p : params) {
        if (std::find(o.fixed.begin(), o.fixed.end(), p) == o.fixed.end()) fo.params.push_back(p);
    }
    fo.initial = mode == fit::InitialMode::Free ? o.initial : mode;
    fo.window = o.window;
    fo.mask = mask;
    fo.initial_start = &from.q0;
    fo.priors = fit::default_priors(from.specs[0]);
    fo.max_capacity_ah = o.max_capacity_ah;
    fo.bounds_full_voltage_v = o.bounds_full_voltage_v;
    fo.bounds_capacity_ah = o.bounds_capacity_ah;
    fo.prior_noise_v = prior_noise_v(traces, from, mask, o);
    fo.max_points_per_log = o.max_points_per_log;
    fo.lm.max_iterations = o.max_iterations;
    fo.starts = o.starts;
    fo.jobs = o.jobs;
    fo.fewer_parameters_advice = "more parameters kept at the config's values with --fixed";
    const fit::FitResult r = fit::fit_model(traces, from.specs, fo);
    State s;
    s.specs = r.specs;
    s.q0 = r.initial_ah;
    s.params = params;
    return s;
}

// Filtered current with time constant tau (the RC branch's response with R = 1) along a trace.
std::vector<double> rc_response(const Trace& t, const ModelSpec& s, double tau) {
    std::vector<double> x(t.points.size(), 0.0);
    double v = 0;
    for (size_t k = 0; k < t.points.size(); ++k) {
        const fit::TracePoint& p = t.points[k];
        if (!p.valid) continue;
        const double i = s.ext.current_sensor.gain * p.current_a + s.ext.current_sensor.offset_a;
        const double decay = std::exp(-std::max(static_cast<double>(p.dt_s), 0.0) / tau);
        v = decay * v + (1 - decay) * i;
        x[k] = v;
    }
    return x;
}

// A measured temperature that moves less than this over the flights shows no self-heating
// (a pack flown hard warms by several kelvin; a sensor's quantisation is 0.1-1 K).
constexpr double kStillTemperatureK = 1.0;

// Enables candidate `name` in every spec of `st`; returns false (with a note) if it does not apply.
bool prepare(const std::string& name, const std::vector<Trace>& traces, State& st, const Eval& ev, const Split& split,
             fit::InitialMode mode, std::vector<std::string>& added, std::string& note, std::string& description) {
    ModelSpec& s0 = st.specs[0];
    bool any_temperature = false, all_temperature = true;
    for (const Trace& t : traces) {
        any_temperature = any_temperature || t.has_temperature;
        all_temperature = all_temperature && t.has_temperature;
    }
    if (name == "rc_polarisation") {
        description = "fast polarisation: one more RC branch (current filtered with a time constant)";
        if (s0.ext.rc_count >= core::kMaxRcBranches) {
            note = "all " + std::to_string(core::kMaxRcBranches) + " RC branches in use";
            return false;
        }
        // Start the time constant where the residual correlates best with the filtered current.
        static const double kTaus[] = {0.3, 1, 3, 10, 30, 100, 300, 1000};
        double best_gain = -1, best_tau = 10, best_r = 1e-4;
        for (double tau : kTaus) {
            double sxx = 0, sxy = 0, sx = 0, sy = 0;
            size_t n = 0;
            for (size_t t = 0; t < traces.size(); ++t) {
                const std::vector<double> x = rc_response(traces[t], st.specs[t], tau);
                for (size_t k = 0; k < x.size(); ++k) {
                    if (!split.fit[t][k] || !std::isfinite(ev.model_v[t][k])) continue;
                    const double y = static_cast<double>(traces[t].points[k].voltage_v) - ev.model_v[t][k];
                    sxx += x[k] * x[k];
                    sxy += x[k] * y;
                    sx += x[k];
                    sy += y;
                    ++n;
                }
            }
            if (n < 3) continue;
            const double vxx = sxx - sx * sx / n, vxy = sxy - sx * sy / n;
            if (!(vxx > 0)) continue;
            const double slope = vxy / vxx;  // residual ≈ −R·x
            const double explained = vxy * vxy / vxx;
            if (slope < 0 && explained > best_gain) {
                best_gain = explained;
                best_tau = tau;
                best_r = -slope;
            }
        }
        const int b = s0.ext.rc_count;
        for (ModelSpec& s : st.specs) {
            s.ext.rc[b].time_constant_s = static_cast<float>(best_tau);
            s.ext.rc[b].resistance_ohm = static_cast<float>(std::max(best_r, 1e-5));
            s.ext.rc_count = static_cast<uint8_t>(b + 1);
        }
        const std::string p = "rc" + std::to_string(b + 1);
        added = {p + "_r", p + "_tau"};
        return true;
    }
    if (name == "temperature") {
        description = "temperature (measured): Arrhenius resistance and polarisation, linear capacity and E0";
        if (!all_temperature) {
            note = "not every log carries a temperature";
            return false;
        }
        if (s0.ext.temperature.enabled) {
            note = "already in the model";
            return false;
        }
        for (ModelSpec& s : st.specs) s.ext.temperature.enabled = true;
        added = {"temp_r", "temp_k", "temp_q", "temp_e0"};
        return true;
    }
    if (name == "self_heating") {
        description = "self-heating: lumped I2R thermal state driving Arrhenius resistance and polarisation";
        if (all_temperature) {
            note = "the logs carry a measured temperature (see temperature)";
            // A reading that holds still (an ambient logged as a constant) cannot show the pack
            // heating, and replaces the state that would: a helper's 7 degC column on flight 30
            // had kept self-heating out, MAE 0.041 V instead of 0.0085 V.
            double low_c = INFINITY, high_c = -INFINITY;
            for (const Trace& t : traces)
                for (const fit::TracePoint& p : t.points)
                    if (p.in_flight && p.has_temperature && std::isfinite(p.temperature_c)) {
                        low_c = std::min(low_c, static_cast<double>(p.temperature_c));
                        high_c = std::max(high_c, static_cast<double>(p.temperature_c));
                    }
            if (high_c >= low_c && high_c - low_c < kStillTemperatureK) {
                char buf[200];
                std::snprintf(buf, sizeof buf,
                              ", which moves %.1f K in flight (%.1f-%.1f degC): it cannot show the pack heating; "
                              "to test self-heating, leave it out (--no-temperature)",
                              high_c - low_c, low_c, high_c);
                note += buf;
            }
            return false;
        }
        if (s0.ext.temperature.enabled || s0.ext.thermal.enabled) {
            note = "already in the model";
            return false;
        }
        for (ModelSpec& s : st.specs) {
            s.ext.temperature.enabled = true;
            s.ext.thermal.enabled = true;
            s.ext.temperature.reference_c = s.ext.thermal.ambient_c;
            // Only activation × thermal resistance is identified without a measurement; the
            // thermal resistance stays at 1 K/W and the activations carry the scale.
            s.ext.thermal.thermal_resistance_k_per_w = 1.0f;
            s.ext.thermal.time_constant_s = 600.0f;
        }
        added = {"temp_r", "temp_k", "thermal_tau"};
        (void)any_temperature;
        return true;
    }
    if (name == "soc_shape") {
        description = "OCV shape misfit: piecewise-linear correction over the charge drawn (8 points)";
        if (s0.ext.ocv.count >= 2) {
            note = "already in the model";
            return false;
        }
        double max_used = 0;
        for (size_t t = 0; t < traces.size(); ++t) {
            fit::SimResult sim;
            fit::simulate(traces[t], st.specs[t], mode, st.q0[t], sim, true);
            for (float u : sim.used_ah) {
                if (std::isfinite(u)) max_used = std::max(max_used, static_cast<double>(u));
            }
        }
        if (!(max_used > 0)) {
            note = "no charge drawn";
            return false;
        }
        for (ModelSpec& s : st.specs) {
            s.ext.ocv.count = 8;
            s.ext.ocv.span_ah = static_cast<float>(max_used * 1.02);
            for (int j = 0; j < core::kMaxOcvPoints; ++j) s.ext.ocv.delta_v[j] = 0.0f;
        }
        added = {"ocv"};
        return true;
    }
    if (name == "current_sensor") {
        description = "current-sensor gain and offset (seen by the filter, the counter and the model)";
        if (s0.ext.current_sensor.gain != 1.0f || s0.ext.current_sensor.offset_a != 0.0f) {
            note = "already in the model";
            return false;
        }
        added = {"gain", "offset"};
        return true;
    }
    if (name == "hysteresis") {
        description = "voltage hysteresis (one state moving with the charge through the cell)";
        if (s0.ext.hysteresis.magnitude_v != 0.0f) {
            note = "already in the model";
            return false;
        }
        // Hysteresis shows only where the current changes direction; in a log that only
        // discharges, its state is one more function of the charge drawn and would pass for
        // an OCV-shape misfit.
        double out_ah = 0, in_ah = 0;
        for (const Trace& t : traces) {
            for (const fit::TracePoint& p : t.points) {
                if (!p.valid) continue;
                (p.current_a > 0 ? out_ah : in_ah) += std::fabs(static_cast<double>(p.current_a)) * p.dt_s / 3600.0;
            }
        }
        if (in_ah < 0.02 * out_ah || in_ah < 0.005) {
            note = "the current never reverses (charge in: " + std::to_string(in_ah * 1000).substr(0, 6) +
                   " mAh): hysteresis cannot be told from the OCV shape";
            return false;
        }
        for (ModelSpec& s : st.specs) {
            s.ext.hysteresis.magnitude_v = 1e-3f;
            s.ext.hysteresis.rate_per_ah = 10.0f;
        }
        added = {"hyst_m", "hyst_rate"};
        return true;
    }
    if (name == "sample_timing") {
        description = "sample timing: current sampled earlier or later than the voltage";
        if (s0.ext.current_sensor.lead_s != 0.0f) {
            note = "already in the model";
            return false;
        }
        added = {"lead"};
        return true;
    }
    note = "unknown candidate";
    return false;
}

// The newly enabled effect of `name` set to (almost) no effect; the parameters that have no
// gradient at exactly zero keep a tiny value.
void neutralise(const std::string& name, State& st) {
    for (ModelSpec& s : st.specs) {
        if (name == "rc_polarisation" && s.ext.rc_count > 0) s.ext.rc[s.ext.rc_count - 1].resistance_ohm = 1e-6f;
        if (name == "hysteresis") s.ext.hysteresis.magnitude_v = 1e-6f;
        if (name == "temperature" || name == "self_heating") {
            s.ext.temperature.resistance_activation_k = 0;
            s.ext.temperature.polarisation_activation_k = 0;
            s.ext.temperature.capacity_ah_per_c = 0;
            s.ext.temperature.e0_v_per_c = 0;
        }
        if (name == "soc_shape") {
            for (float& v : s.ext.ocv.delta_v) v = 0;
        }
        if (name == "current_sensor") {
            s.ext.current_sensor.gain = 1;
            s.ext.current_sensor.offset_a = 0;
        }
        if (name == "sample_timing") s.ext.current_sensor.lead_s = 0;
    }
}

std::vector<std::pair<std::string, double>> effect_values(const ModelSpec& s, const std::vector<std::string>& params) {
    std::vector<std::pair<std::string, double>> v;
    for (const std::string& p : params) {
        if (p.size() >= 5 && p.compare(0, 2, "rc") == 0) {
            const int b = p[2] - '1';
            v.push_back({p, p.substr(4) == "r" ? s.ext.rc[b].resistance_ohm : s.ext.rc[b].time_constant_s});
        } else if (p == "temp_r") v.push_back({p, s.ext.temperature.resistance_activation_k});
        else if (p == "temp_k") v.push_back({p, s.ext.temperature.polarisation_activation_k});
        else if (p == "temp_q") v.push_back({p, s.ext.temperature.capacity_ah_per_c});
        else if (p == "temp_e0") v.push_back({p, s.ext.temperature.e0_v_per_c});
        else if (p == "thermal_tau") v.push_back({p, s.ext.thermal.time_constant_s});
        else if (p == "hyst_m") v.push_back({p, s.ext.hysteresis.magnitude_v});
        else if (p == "hyst_rate") v.push_back({p, s.ext.hysteresis.rate_per_ah});
        else if (p == "gain") v.push_back({p, s.ext.current_sensor.gain});
        else if (p == "offset") v.push_back({p, s.ext.current_sensor.offset_a});
        else if (p == "lead") v.push_back({p, s.ext.current_sensor.lead_s});
        else if (p == "ocv") {
            for (int j = 0; j < s.ext.ocv.count; ++j) v.push_back({"ocv" + std::to_string(j + 1), s.ext.ocv.delta_v[j]});
        }
    }
    return v;
}

double quantile(const std::vector<double>& sorted, double p) {
    if (sorted.empty()) return 0;
    const double pos = p * (sorted.size() - 1);
    const size_t i = static_cast<size_t>(pos);
    const double f = pos - i;
    return i + 1 < sorted.size() ? sorted[i] + f * (sorted[i + 1] - sorted[i]) : sorted[i];
}

}  // namespace

std::vector<std::string> candidate_names() {
    return {"rc_polarisation", "temperature", "self_heating", "soc_shape", "current_sensor", "hysteresis", "sample_timing"};
}

Structure residual_structure(const std::vector<Trace>& traces, const std::vector<std::vector<float>>& model_v,
                             fit::Window window, fit::InitialMode mode) {
    Structure s;
    std::vector<std::vector<double>> runs;
    std::vector<double> all, dts;
    for (size_t t = 0; t < traces.size(); ++t) {
        std::vector<double> e;
        for (size_t k = 0; k < traces[t].points.size(); ++k) {
            const fit::TracePoint& p = traces[t].points[k];
            if (!fit::in_window(traces[t], k, window, mode) || !std::isfinite(model_v[t][k])) continue;
            e.push_back(static_cast<double>(p.voltage_v) - model_v[t][k]);
            if (p.dt_s > 0) dts.push_back(p.dt_s);
        }
        all.insert(all.end(), e.begin(), e.end());
        runs.push_back(std::move(e));
    }
    s.n = all.size();
    if (s.n < 2) return s;
    double sum = 0;
    for (double e : all) sum += e;
    s.mean_v = sum / s.n;
    double m2 = 0, m3 = 0, m4 = 0;
    for (double e : all) {
        const double d = e - s.mean_v;
        m2 += d * d;
        m3 += d * d * d;
        m4 += d * d * d * d;
    }
    m2 /= s.n;
    m3 /= s.n;
    m4 /= s.n;
    s.sd_v = std::sqrt(m2);
    s.skewness = m2 > 0 ? m3 / std::pow(m2, 1.5) : 0;
    s.excess_kurtosis = m2 > 0 ? m4 / (m2 * m2) - 3 : 0;
    std::vector<double> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    for (double p : {0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99}) s.quantiles.push_back({p, quantile(sorted, p)});
    std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
    const double dt = dts.empty() ? 0 : dts[dts.size() / 2];
    for (int lag : {1, 2, 5, 10, 20, 50, 100, 200, 500}) {
        double num = 0;
        size_t pairs = 0;
        for (const auto& e : runs) {
            for (size_t k = lag; k < e.size(); ++k) {
                num += (e[k] - s.mean_v) * (e[k - lag] - s.mean_v);
                ++pairs;
            }
        }
        if (pairs < 10) break;
        s.lags.push_back(lag);
        s.lag_s.push_back(lag * dt);
        s.acf.push_back(m2 > 0 ? num / (m2 * s.n) : 0);
    }
    s.white_band = 1.96 / std::sqrt(static_cast<double>(s.n));
    const double lo = quantile(sorted, 0.005), hi = quantile(sorted, 0.995);
    const int bins = 15;
    if (hi > lo) {
        for (int b = 0; b <= bins; ++b) s.histogram_edges_v.push_back(lo + (hi - lo) * b / bins);
        s.histogram_counts.assign(bins, 0);
        for (double e : all) {
            if (e < lo || e > hi) continue;
            const int b = std::min(bins - 1, static_cast<int>((e - lo) / (hi - lo) * bins));
            ++s.histogram_counts[b];
        }
    }
    return s;
}

namespace {

// A candidate effect added to the current model, before its fit: whether it applies, and
// the model with it at its data-driven start.
struct Prepared {
    bool applicable = false;
    State trial;
    std::vector<std::string> added;
    std::string note, description;
};

Prepared prepare_candidate(const std::string& name, const std::vector<Trace>& traces, const State& current,
                           const Eval& current_eval, const Split& split, const ResidualOptions& o) {
    Prepared p;
    p.trial = current;
    p.applicable = prepare(name, traces, p.trial, current_eval, split, o.initial, p.added, p.note, p.description);
    return p;
}

// One prepared candidate fitted on the fit blocks and scored on the held-out ones; `fitted`
// gets the model with it.
CandidateScore judge(const std::string& name, const Prepared& prepared, const std::vector<Trace>& traces,
                     const State& current, const Eval& current_eval, const Split& split, const ResidualOptions& o,
                     State& fitted) {
    CandidateScore c;
    c.name = name;
    c.note = prepared.note;
    c.description = prepared.description;
    if (!prepared.applicable) {
        c.applicable = false;
        return c;
    }
    const State& trial = prepared.trial;
    const std::vector<std::string>& added = prepared.added;
    std::vector<std::string> params = current.params;
    params.insert(params.end(), added.begin(), added.end());
    Eval ev;
    try {
        // The new effect alone first (few, well-conditioned parameters), then everything.
        fitted = refit(traces, refit(traces, trial, added, &split.fit, o), params, &split.fit, o);
        ev = evaluate_state(traces, fitted, o.initial, split, o.window);
        if (ev.fit_mse > current_eval.fit_mse) {
            // The data-driven start led the fit astray; the effect switched (almost) off
            // reproduces the current model, so a fit from there can only improve on it.
            State neutral = trial;
            neutralise(name, neutral);
            fitted = refit(traces, refit(traces, neutral, added, &split.fit, o), params, &split.fit, o);
            ev = evaluate_state(traces, fitted, o.initial, split, o.window);
        }
    } catch (const fit::TooLittleData& e) {
        // More parameters than the log's fitting samples: this effect cannot be judged on it,
        // which is a finding about the candidate, not a failure of the run (and the remedy
        // for the run does not apply to it).
        c.applicable = false;
        c.note = e.finding();
        return c;
    } catch (const std::invalid_argument& e) {
        c.applicable = false;
        c.note = e.what();
        return c;
    }
    compare(current_eval, ev, static_cast<size_t>(split.blocks), c);
    c.values = effect_values(fitted.specs[0], added);
    c.significant = c.gain >= o.min_gain && c.p_value <= o.max_p;
    return c;
}

// The options' names and counts, checked before any log is read (a misspelt name after
// minutes of reading long logs had cost those minutes).
void check_names(const ResidualOptions& o) {
    if (o.blocks < 4 || o.blocks % 2 != 0) throw std::invalid_argument("--blocks must be even and at least 4");
    // A misspelt --fixed name had been ignored, and the parameter fitted after all.
    for (size_t i = 0; i < o.fixed.size(); ++i) {
        const std::string& f = o.fixed[i];
        fit::check_parameter_name(f, "--fixed");
        if (std::find(o.fixed.begin(), o.fixed.begin() + static_cast<long>(i), f) != o.fixed.begin() + static_cast<long>(i))
            throw std::invalid_argument("--fixed: parameter \"" + f + "\" given twice");  // as fit's --params says
    }
    const std::vector<std::string> effects = candidate_names();
    for (const std::string& given : o.candidates) {
        const std::string n = fit::candidate_name(given);  // fit --add's short names (rc, thermal, ocv, sensor, timing) too
        if (std::find(effects.begin(), effects.end(), n) == effects.end()) {
            std::string list;
            for (const std::string& k : effects) list += (list.empty() ? "" : ", ") + k;
            throw std::invalid_argument("unknown candidate \"" + n + "\"; expected " + list +
                                        " (or fit --add's names: rc, thermal, ocv, sensor, timing)");
        }
    }
}

}  // namespace

ResidualReport analyse(const std::vector<Trace>& traces, const ModelSpec& spec, const ResidualOptions& options,
                       std::ostream* progress) {
    if (traces.empty()) throw std::invalid_argument("no logs");
    ResidualOptions o = options;
    o.max_capacity_ah = o.max_capacity_factor * spec.battery.capacity_ah;
    if (o.bounds_full_voltage_v <= 0) o.bounds_full_voltage_v = spec.battery.full_voltage_v;
    o.bounds_capacity_ah = spec.battery.capacity_ah;
    check_names(o);
    ResidualReport rep;
    rep.initial = o.initial;
    for (const Trace& t : traces) rep.logs.push_back(t.path);
    if (o.initial == fit::InitialMode::Monitor) throw std::invalid_argument("the initial charge is free or zero");
    const Split split = make_split(traces, o.window, o.initial, o.blocks);
    const fit::InitialMode config_mode = o.initial == fit::InitialMode::Zero ? fit::InitialMode::Zero : fit::InitialMode::Monitor;
    std::vector<std::string> names = o.candidates.empty() ? candidate_names() : o.candidates;
    for (std::string& n : names) n = fit::candidate_name(n);  // fit --add's short names too (checked above)

    // Stage 0: the config as given, run as the monitor runs it.
    State config;
    config.specs.assign(traces.size(), spec);
    for (const Trace& t : traces) config.q0.push_back(t.monitor_initial_ah);
    const Eval config_eval = evaluate_state(traces, config, config_mode, split, o.window);
    Stage s0;
    s0.name = "config";
    s0.description = "the config as given (initial charge as the monitor sets it)";
    s0.stats = config_eval.stats;
    s0.spec = spec;
    rep.stages.push_back(s0);
    for (size_t t = 0; t < traces.size(); ++t) rep.before.push_back(fit::evaluate(traces[t], spec, config_mode, 0.0f));
    rep.structure_before = residual_structure(traces, config_eval.model_v, o.window, o.initial);

    // Stage 1: the base parameters (and any extension already configured) refitted.
    // Each refit takes seconds on long logs: said as it goes, so a minute-long run is not silent.
    if (progress) *progress << "battsim residual: refitting the parameters\n";
    State current = refit(traces, config, fit::default_parameters(spec), &split.fit, o);
    Eval current_eval = evaluate_state(traces, current, o.initial, split, o.window);
    {
        Stage s1;
        s1.name = "parameters";
        s1.description = "parameters refitted, initial charge fitted per log";
        s1.stats = current_eval.stats;
        CandidateScore c;
        compare(config_eval, current_eval, static_cast<size_t>(split.blocks), c);
        s1.gain = c.gain;
        s1.p_value = c.p_value;
        s1.spec = current.specs[0];
        rep.stages.push_back(s1);
    }

    // Greedy forward selection, judged on the held-out blocks.
    for (int round = 0; round < o.max_effects; ++round) {
        // The candidates are independent given the current model: judged side by side, each
        // into its own slot, then taken in the order of `names` as one at a time would be.
        // They take the threads, so each one's starts run in turn.
        ResidualOptions one_thread = o;
        one_thread.jobs = 1;
        // Each candidate prepared once, in turn; the progress names only those that apply (a
        // log with a temperature leaves self-heating out, one whose current never reverses
        // hysteresis): "trying" each had read as if it were.
        std::vector<Prepared> prepared;
        for (const std::string& name : names) {
            prepared.push_back(prepare_candidate(name, traces, current, current_eval, split, o));
            if (progress && prepared.back().applicable)
                *progress << "battsim residual: effect " << round + 1 << " of at most " << o.max_effects << ": trying "
                          << name << "\n";
        }
        std::vector<CandidateScore> tried(names.size());
        std::vector<State> fitted_states(names.size());
        host::parallel_for(names.size(), o.jobs, [&](size_t i) {
            tried[i] = judge(names[i], prepared[i], traces, current, current_eval, split, one_thread, fitted_states[i]);
        });
        std::vector<CandidateScore> scores;
        State best_state;
        int best = -1;
        for (size_t i = 0; i < names.size(); ++i) {
            scores.push_back(tried[i]);
            const CandidateScore& c = scores.back();
            if (c.significant && (best < 0 || c.gain > scores[best].gain)) {
                best = static_cast<int>(scores.size()) - 1;
                best_state = fitted_states[i];
            }
        }
        std::stable_sort(scores.begin(), scores.end(), [](const CandidateScore& a, const CandidateScore& b) {
            if (a.applicable != b.applicable) return a.applicable;
            return a.gain > b.gain;
        });
        rep.stages.back().candidates = scores;
        if (best < 0) break;
        const CandidateScore* chosen = nullptr;
        for (const CandidateScore& c : scores) {
            if (c.significant && (chosen == nullptr || c.gain > chosen->gain)) chosen = &c;
        }
        const Eval ev = evaluate_state(traces, best_state, o.initial, split, o.window);
        Stage st;
        st.name = chosen->name;
        st.description = chosen->description;
        st.stats = ev.stats;
        st.gain = chosen->gain;
        st.p_value = chosen->p_value;
        st.block_lag1_r = chosen->block_lag1_r;
        st.block_pairs = chosen->block_pairs;
        st.spec = best_state.specs[0];
        rep.effects.push_back(chosen->name);
        rep.stages.push_back(st);
        current = best_state;
        current_eval = ev;
    }

    // The chosen model refitted on every sample.
    State final_state = refit(traces, current, current.params, nullptr, o);
    {
        // A refit on every sample starts from the last stage and can only improve its
        // objective; the check guards the pooled error against the thinning and weighting.
        const Eval refitted = evaluate_state(traces, final_state, o.initial, split, o.window);
        if (refitted.stats.all.rmse_v > current_eval.stats.all.rmse_v) final_state = current;
    }
    // The monitor sets the initial charge by inverting the model at the settle sample, not by
    // fitting it: polish the model for that, and keep the polish if the monitor would then
    // see a smaller error.
    if (o.initial == fit::InitialMode::Free) {
        State polished = refit(traces, final_state, current.params, nullptr, o, fit::InitialMode::Monitor);
        double before_sq = 0, after_sq = 0;
        for (size_t t = 0; t < traces.size(); ++t) {
            const fit::LogFitStats b = fit::evaluate(traces[t], final_state.specs[t], fit::InitialMode::Monitor, 0.0f);
            const fit::LogFitStats a = fit::evaluate(traces[t], polished.specs[t], fit::InitialMode::Monitor, 0.0f);
            before_sq += b.monitor_all.rmse_v * b.monitor_all.rmse_v * b.monitor_all.n;
            after_sq += a.monitor_all.rmse_v * a.monitor_all.rmse_v * a.monitor_all.n;
        }
        rep.monitor_polished = after_sq < before_sq;
        if (rep.monitor_polished) {
            // The polished model's own fitted initial charges, for the "fitted" figures and the
            // remaining residual: they had been the monitor's, so "fitted" repeated its error.
            final_state = refit(traces, polished, {}, nullptr, o);
            final_state.params = current.params;
        }
    }
    rep.final_specs = final_state.specs;
    rep.final_initial_ah = final_state.q0;
    std::vector<std::vector<float>> final_v;
    for (size_t t = 0; t < traces.size(); ++t) {
        rep.after.push_back(fit::evaluate(traces[t], final_state.specs[t], o.initial, final_state.q0[t]));
        fit::SimResult sim;
        fit::simulate(traces[t], final_state.specs[t], o.initial, final_state.q0[t], sim);
        final_v.push_back(sim.model_v);
    }
    rep.structure_after = residual_structure(traces, final_v, o.window, o.initial);

    // The verdict, in words.
    char buf[512];
    const Stage& last_stage = rep.stages.back();
    if (!rep.effects.empty()) {
        std::string list;
        for (size_t i = 2; i < rep.stages.size(); ++i) {
            std::snprintf(buf, sizeof buf, "%s%s (%.1f %% of the held-out error variance, p = %.2g)",
                          list.empty() ? "" : ", then ", rep.stages[i].name.c_str(), 100 * rep.stages[i].gain, rep.stages[i].p_value);
            list += buf;
        }
        rep.verdict = "Explained on held-out data by: " + list + ".";
        // Blocks shorter than the effects' course: a researcher had read p = 4e-27 off 1000
        // blocks of a few samples each, where the default 20 gave 0.002.
        const Stage* worst = nullptr;
        for (size_t i = 2; i < rep.stages.size(); ++i) {
            const Stage& st = rep.stages[i];
            if (st.block_pairs >= 3 && st.block_lag1_r > std::max(0.3, 1.96 / std::sqrt(static_cast<double>(st.block_pairs))) &&
                (worst == nullptr || st.block_lag1_r > worst->block_lag1_r))
                worst = &st;
        }
        if (worst) {
            std::snprintf(buf, sizeof buf,
                          " Neighbouring held-out blocks improve together (%s: lag-1 correlation %.2f over %d pairs), so they "
                          "are not independent and the p-values read too small; fewer, longer blocks (--blocks) test honestly.",
                          worst->name.c_str(), worst->block_lag1_r, worst->block_pairs);
            rep.verdict += buf;
        }
    } else {
        const CandidateScore* top = nullptr;
        for (const CandidateScore& c : last_stage.candidates) {
            if (c.applicable && (top == nullptr || c.gain > top->gain)) top = &c;
        }
        // With --max-effects 0 no effect was tried: "no candidate explains" had read as a finding.
        rep.verdict = o.max_effects == 0 ? "No effect was tried (--max-effects 0): the parameters were only refitted"
                                         : "No candidate effect explains the residual on held-out data";
        if (top) {
            std::snprintf(buf, sizeof buf, " (best: %s, %.1f %% of the held-out error variance, p = %.2g)",
                          top->name.c_str(), 100 * top->gain, top->p_value);
            rep.verdict += buf;
        }
        rep.verdict += o.max_effects == 0 ? "." : "; nothing was added.";
    }
    const Structure& s = rep.structure_after;
    if (!s.acf.empty()) {
        std::snprintf(buf, sizeof buf,
                      " Remaining residual: RMSE %.4f V, lag-1 autocorrelation %.2f (white noise: within +-%.3f), "
                      "skewness %.2f, excess kurtosis %.2f.",
                      std::sqrt(s.sd_v * s.sd_v + s.mean_v * s.mean_v), s.acf[0], s.white_band, s.skewness, s.excess_kurtosis);
        rep.verdict += buf;
        rep.verdict += std::fabs(s.acf[0]) > s.white_band
                           ? (o.max_effects == 0 ? " It is not white: it has memory the model does not capture."
                                                 : " It is not white: it has memory the candidates do not capture.")
                           : " It is consistent with white noise.";
    }
    return rep;
}

namespace {
nlohmann::json stats_json(const ErrorStats& s) { return fit::error_stats_to_json(s); }
nlohmann::json structure_json(const Structure& s) {
    nlohmann::json j;
    j["n"] = s.n;
    j["mean_v"] = round_sig(s.mean_v, 5);
    j["sd_v"] = round_sig(s.sd_v, 5);
    j["skewness"] = round_sig(s.skewness, 4);
    j["excess_kurtosis"] = round_sig(s.excess_kurtosis, 4);
    nlohmann::json q = nlohmann::json::object();
    for (const auto& p : s.quantiles) {
        char key[16];
        std::snprintf(key, sizeof key, "p%02d", static_cast<int>(std::lround(p.first * 100)));
        q[key] = round_sig(p.second, 5);
    }
    j["quantiles_v"] = q;
    nlohmann::json acf = nlohmann::json::array();
    for (size_t i = 0; i < s.acf.size(); ++i)
        acf.push_back({{"lag", s.lags[i]}, {"lag_s", round_sig(s.lag_s[i], 4)}, {"r", round_sig(s.acf[i], 4)}});
    j["autocorrelation"] = acf;
    j["white_noise_band"] = round_sig(s.white_band, 4);
    j["histogram"] = {{"edges_v", nlohmann::json::array()}, {"counts", s.histogram_counts}};
    for (double e : s.histogram_edges_v) j["histogram"]["edges_v"].push_back(round_sig(e, 5));
    return j;
}
}  // namespace

nlohmann::json report_to_json(const ResidualReport& r, const ResidualOptions& o) {
    nlohmann::json j;
    j["schema"] = "battsim.residual";
    j["schema_version"] = 1;
    j["battsim_version"] = BATTSIM_VERSION;
    j["logs"] = r.logs;
    j["options"] = {{"window", fit::to_string(o.window)}, {"initial", fit::to_string(o.initial)}, {"blocks", o.blocks}, {"min_gain", o.min_gain},
                    {"max_p", o.max_p}, {"max_effects", o.max_effects}, {"fixed", o.fixed},
                    {"max_capacity_factor", o.max_capacity_factor}, {"max_iterations", o.max_iterations},
                    {"starts", o.starts}};
    nlohmann::json stages = nlohmann::json::array();
    for (const Stage& s : r.stages) {
        nlohmann::json st = {{"name", s.name}, {"description", s.description},
                             {"all", stats_json(s.stats.all)}, {"fit", stats_json(s.stats.fit)}, {"heldout", stats_json(s.stats.heldout)}};
        if (s.name != "config") {
            st["gain"] = round_sig(s.gain, 4);
            st["p_value"] = round_sig(s.p_value, 3);
        }
        if (s.block_pairs > 0) st["block_lag1_r"] = round_sig(s.block_lag1_r, 3);
        nlohmann::json cands = nlohmann::json::array();
        for (const CandidateScore& c : s.candidates) {
            nlohmann::json cj = {{"name", c.name}, {"description", c.description}, {"applicable", c.applicable}};
            if (!c.applicable) {
                cj["note"] = c.note;
            } else {
                cj["gain"] = round_sig(c.gain, 4);
                cj["p_value"] = round_sig(c.p_value, 3);
                cj["blocks_better"] = c.blocks_better;
                cj["blocks"] = c.blocks;
                if (c.block_pairs > 0) cj["block_lag1_r"] = round_sig(c.block_lag1_r, 3);
                cj["significant"] = c.significant;
                cj["fit_rmse_v"] = round_sig(c.fit_rmse_v, 5);
                cj["heldout_rmse_v"] = round_sig(c.heldout_rmse_v, 5);
                nlohmann::json v = nlohmann::json::object();
                for (const auto& kv : c.values) v[kv.first] = round_sig(kv.second, 6);
                cj["values"] = v;
            }
            cands.push_back(cj);
        }
        if (!cands.empty()) st["candidates_scored"] = cands;
        stages.push_back(st);
    }
    j["stages"] = stages;
    j["effects"] = r.effects;
    j["monitor_polished"] = r.monitor_polished;
    nlohmann::json logs = nlohmann::json::array();
    for (size_t t = 0; t < r.before.size(); ++t) {
        const fit::LogFitStats& b = r.before[t];
        const fit::LogFitStats& a = r.after[t];
        const bool zero = r.initial == fit::InitialMode::Zero;
        logs.push_back({{"label", b.label},
                        {"before", {{"all", stats_json(zero ? b.fit_all : b.monitor_all)}, {"flight", stats_json(zero ? b.fit_flight : b.monitor_flight)}}},
                        {"after", {{"all", stats_json(a.fit_all)}, {"flight", stats_json(a.fit_flight)}}},
                        {"after_monitor_initial", {{"all", stats_json(a.monitor_all)}, {"flight", stats_json(a.monitor_flight)}}},
                        {"initial_ah", round_sig(r.final_initial_ah[t], 6)}});
    }
    j["per_log"] = logs;
    j["structure_before"] = structure_json(r.structure_before);
    j["structure_after"] = structure_json(r.structure_after);
    j["verdict"] = r.verdict;
    return j;
}

void print_report(const ResidualReport& r, std::ostream& out) {
    char buf[256];
    // The steps judge the model's shape, each log's initial charge fitted; the lines after the
    // table also give the error with the charge the monitor reads at its start, which on a
    // log whose first rest reads wrong is the larger one.
    out << (r.initial == fit::InitialMode::Zero ? "steps (logs start full):\n" : "steps (each log's initial charge fitted):\n");
    std::snprintf(buf, sizeof buf, "%-18s %10s %10s %10s %10s %8s %8s\n", "step", "RMSE all", "MAE all", "RMSE fit", "RMSE held",
                  "gain", "p");
    out << buf;
    for (const Stage& s : r.stages) {
        if (s.name == "config") {
            std::snprintf(buf, sizeof buf, "%-18s %10.4f %10.4f %10.4f %10.4f %8s %8s\n", s.name.c_str(), s.stats.all.rmse_v,
                          s.stats.all.mae_v, s.stats.fit.rmse_v, s.stats.heldout.rmse_v, "-", "-");
        } else {
            std::snprintf(buf, sizeof buf, "%-18s %10.4f %10.4f %10.4f %10.4f %7.1f%% %8.2g\n",
                          (s.name == "parameters" ? s.name : "+ " + s.name).c_str(), s.stats.all.rmse_v, s.stats.all.mae_v,
                          s.stats.fit.rmse_v, s.stats.heldout.rmse_v, 100 * s.gain, s.p_value);
        }
        out << buf;
    }
    const Stage& last = r.stages.back();
    if (!last.candidates.empty()) {
        out << "candidates at the last step (held-out gain, Wilcoxon signed-rank test over held-out blocks):\n";
        for (const CandidateScore& c : last.candidates) {
            if (!c.applicable) {
                std::snprintf(buf, sizeof buf, "  %-16s not applicable: %s\n", c.name.c_str(), c.note.c_str());
            } else {
                std::snprintf(buf, sizeof buf, "  %-16s %7.1f%%  %d/%d blocks better, p = %.2g%s\n", c.name.c_str(), 100 * c.gain,
                              c.blocks_better, c.blocks, c.p_value, c.significant ? "  (significant)" : "");
            }
            out << buf;
        }
    }
    const bool zero = r.initial == fit::InitialMode::Zero;
    out << (zero ? "before: the config; after: the final model, refitted on all samples (logs start full)\n"
                 : "before: the config as the monitor runs it; after: the final model, refitted on all samples, with the\n"
                   "initial charge as the monitor sets it (fitted: the initial charge fitted instead)\n");
    if (r.monitor_polished) {
        // Said only when so: flight 30's fitted figure was the better one (0.01739 V against 0.0179 V).
        double sq = 0;
        size_t n = 0;
        for (const fit::LogFitStats& a : r.after) {
            sq += a.fit_all.rmse_v * a.fit_all.rmse_v * static_cast<double>(a.fit_all.n);
            n += a.fit_all.n;
        }
        const bool worse = n > 0 && std::sqrt(sq / static_cast<double>(n)) > r.stages.back().stats.all.rmse_v;
        out << "the final model was refitted for the initial charge the monitor sets, which lowered the monitor's\n"
            << (worse ? "error: with the charge fitted it fits less well than the last step above\n" : "error\n");
    }
    for (size_t t = 0; t < r.before.size(); ++t) {
        const fit::LogFitStats& b = r.before[t];
        const fit::LogFitStats& a = r.after[t];
        const ErrorStats& ba = zero ? b.fit_all : b.monitor_all;
        const ErrorStats& bf = zero ? b.fit_flight : b.monitor_flight;
        const ErrorStats& aa = zero ? a.fit_all : a.monitor_all;
        const ErrorStats& af = zero ? a.fit_flight : a.monitor_flight;
        char flight[64] = "no flight";
        if (bf.n > 0 && af.n > 0) std::snprintf(flight, sizeof flight, "%.4f -> %.4f V (flight)", bf.mae_v, af.mae_v);
        std::snprintf(buf, sizeof buf, "%s: MAE %.4f -> %.4f V (all), %s; RMSE %.4f -> %.4f V (all); fitted: MAE %.4f V (all)\n",
                      b.label.c_str(), ba.mae_v, aa.mae_v, flight, ba.rmse_v, aa.rmse_v, a.fit_all.mae_v);
        out << buf;
    }
    out << r.verdict << "\n";
}

size_t plot_residual(const std::vector<Trace>& traces, const ResidualReport& r, const ModelSpec& config_spec,
                     const std::string& path) {
    plot::check_plot_path(path);
    std::vector<plot::Panel> panels;
    // Two panels per log (voltage, residual), for up to 4 logs, then the pooled ACF and histogram.
    constexpr size_t kMaxLogs = 4;
    const size_t shown = std::min(traces.size(), kMaxLogs);
    double residual_range_v = 0.0;
    for (size_t ti = 0; ti < shown; ++ti) {
        const Trace& t = traces[ti];
        fit::SimResult before, after;
        fit::simulate(t, config_spec, r.initial == fit::InitialMode::Zero ? fit::InitialMode::Zero : fit::InitialMode::Monitor,
                      0.0f, before);
        fit::simulate(t, r.final_specs[ti], r.initial, r.final_initial_ah[ti], after);
        plot::Panel v;
        v.title = t.label + ": measured voltage, the config's model and the final model";
        v.xlabel = "time (s)";
        v.ylabel = "voltage (V)";
        plot::Panel e;
        e.title = t.label + ": residual (measured - model)";
        e.xlabel = "time (s)";
        e.ylabel = "residual (V)";
        std::vector<double> time, meas, mb, ma, eb, ea;
        for (size_t k = 0; k < t.points.size(); ++k) {
            const fit::TracePoint& p = t.points[k];
            if (!p.valid) continue;
            time.push_back(p.time_s);
            meas.push_back(p.voltage_v);
            mb.push_back(std::isfinite(before.model_v[k]) ? before.model_v[k] : NAN);
            ma.push_back(std::isfinite(after.model_v[k]) ? after.model_v[k] : NAN);
            eb.push_back(p.voltage_v - mb.back());
            ea.push_back(p.voltage_v - ma.back());
        }
        // The axes follow the measurement and the final residual: a config model that runs away
        // (a pole reached) would otherwise squash everything else flat.
        {
            std::vector<double> m, a, b;
            for (size_t k = 0; k < meas.size(); ++k) {
                m.push_back(meas[k]);
                if (std::isfinite(ea[k])) a.push_back(std::fabs(ea[k]));
                if (std::isfinite(eb[k])) b.push_back(std::fabs(eb[k]));
            }
            std::sort(m.begin(), m.end());
            std::sort(a.begin(), a.end());
            std::sort(b.begin(), b.end());
            const double lo = quantile(m, 0.0), hi = quantile(m, 1.0), pad = 0.1 * std::max(hi - lo, 0.01);
            v.y_min = lo - pad;
            v.y_max = hi + pad;
            const double ra = std::max(quantile(a, 0.99), 1e-3), rb = quantile(b, 0.9);
            const double range_v = std::min(std::max(3 * ra, rb), 15 * ra);
            e.y_min = -range_v;
            e.y_max = range_v;
            residual_range_v = std::max(residual_range_v, range_v);
        }
        // Measured last, so it is drawn on top of the models it is compared with.
        v.series = {plot::line_series("config model", time, mb, "#ff7f0e", false, 1.2),
                    plot::line_series("final model", time, ma, "#d62728", false, 1.2),
                    plot::line_series("measured", time, meas, "black", false, 0.8)};
        e.series = {plot::line_series("before (config)", time, eb, "#ff7f0e", false, 1.0),
                    plot::line_series("after (final)", time, ea, "#1f77b4", false, 1.0)};
        panels.push_back(v);
        panels.push_back(e);
    }
    plot::Panel acf;
    acf.title = "autocorrelation of the residual (all logs)";
    acf.xlabel = "lag (s)";
    acf.ylabel = "r";
    plot::Series ab, aa, band_hi, band_lo;
    ab.title = "before";
    ab.style = "linespoints";
    ab.color = "#ff7f0e";
    aa.title = "after";
    aa.style = "linespoints";
    aa.color = "#1f77b4";
    for (size_t i = 0; i < r.structure_before.acf.size(); ++i) {
        ab.x.push_back(r.structure_before.lag_s[i]);
        ab.y.push_back(r.structure_before.acf[i]);
    }
    for (size_t i = 0; i < r.structure_after.acf.size(); ++i) {
        aa.x.push_back(r.structure_after.lag_s[i]);
        aa.y.push_back(r.structure_after.acf[i]);
    }
    band_hi.title = "white-noise band";
    band_hi.color = "#7f7f7f";
    band_lo.title = "";
    band_lo.color = "#7f7f7f";
    if (!aa.x.empty()) {
        band_hi.x = {0.0, aa.x.back()};
        band_hi.y = {r.structure_after.white_band, r.structure_after.white_band};
        band_lo.x = band_hi.x;
        band_lo.y = {-r.structure_after.white_band, -r.structure_after.white_band};
    }
    acf.series = {ab, aa, band_hi, band_lo};
    panels.push_back(acf);
    plot::Panel h;
    h.title = "residual histogram (all logs)";
    h.xlabel = "residual (V)";
    h.ylabel = "share of samples";
    auto hist = [](const Structure& s, const std::string& title, const char* color) {
        plot::Series x;
        x.title = title;
        x.style = "steps";
        x.color = color;
        x.width = 1.5;
        size_t total = 0;
        for (size_t c : s.histogram_counts) total += c;
        for (size_t b = 0; b < s.histogram_counts.size(); ++b) {
            x.x.push_back(s.histogram_edges_v[b]);
            x.y.push_back(total ? static_cast<double>(s.histogram_counts[b]) / total : 0);
        }
        if (!s.histogram_counts.empty()) {
            x.x.push_back(s.histogram_edges_v.back());
            x.y.push_back(x.y.back());
        }
        return x;
    };
    h.series = {hist(r.structure_before, "before", "#ff7f0e"), hist(r.structure_after, "after", "#1f77b4")};
    h.x_min = -residual_range_v;  // the residual panels' widest range, for the same reason
    h.x_max = residual_range_v;
    panels.push_back(h);
    plot::render(panels,
                 "battsim residual: " + (traces.size() == 1 ? traces[0].path : std::to_string(traces.size()) + " logs"), path);
    return traces.size() - shown;
}

nlohmann::json run_residual_job(const ResidualJob& job, ResidualReport* out, std::ostream* progress) {
    if (job.logs.empty()) throw std::invalid_argument("no logs");
    if (!job.plot_path.empty()) plot::check_plot_path(job.plot_path);
    check_names(job.options);
    // The logs in the order of their paths: the fits are pooled sums, and a greedy choice on
    // the edge of significance had followed the order they were given in (Matrice 100 flights
    // 1 and 140 gained rc_polarisation one way, self_heating and sample_timing the other).
    std::vector<std::string> logs = job.logs;
    std::sort(logs.begin(), logs.end());
    std::vector<Trace> traces;
    for (const std::string& path : logs) {
        if (progress) *progress << "battsim residual: reading " << path << "\n";
        traces.push_back(fit::load_trace(path, job.reader, job.config));
        fit::say_notes("battsim residual", traces.back(), progress);
    }
    const ModelSpec spec = fit::spec_from_config(job.config);
    if (progress) *progress << "battsim residual: analysing\n";
    ResidualOptions options = job.options;
    if (options.bounds_full_voltage_v <= 0) options.bounds_full_voltage_v = job.config.monitor.max_voltage_v;  // as fit's
    ResidualReport rep = analyse(traces, spec, options, progress);
    nlohmann::json j = report_to_json(rep, options);
    j["config"] = job.config.name;
    if (!job.output_config.empty()) {
        LoadedConfig c = job.config;
        fit::spec_to_config(rep.final_specs[0], c);
        c.name = job.name.empty() ? job.config.name + "-residual" : job.name;
        std::string effects;
        for (const std::string& e : rep.effects) effects += (effects.empty() ? "" : ", ") + e;
        c.description = "battsim residual " BATTSIM_VERSION " on " + std::to_string(traces.size()) + " log(s) from " +
                               job.config.name + "; effects added: " + (effects.empty() ? "none" : effects);
        write_file_atomic(job.output_config, json_text(config_to_json(c), 2) + "\n");
        j["config_written"] = job.output_config;
    }
    if (!job.plot_path.empty()) {
        const size_t left_out = plot_residual(traces, rep, spec, job.plot_path);
        j["plot"] = job.plot_path;
        if (left_out > 0)
            j["plot_note"] = "the plot shows the first " + std::to_string(traces.size() - left_out) + " of the " +
                             std::to_string(traces.size()) + " logs (the ACF and histogram pool all)";
    }
    if (out) *out = std::move(rep);
    return j;
}

}  // namespace residual
}  // namespace host
}  // namespace battsim
