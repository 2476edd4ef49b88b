#include "host/fit/model.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/estimate/coulomb_counter.h"
#include "core/estimate/low_pass.h"

namespace battsim {
namespace host {
namespace fit {

ModelSpec spec_from_config(const LoadedConfig& c) {
    ModelSpec s;
    s.battery = c.monitor.battery;
    s.ext = c.monitor.extensions;
    s.reaction_time_s = c.monitor.current_filter.time_constant_s;
    return s;
}

void spec_to_config(const ModelSpec& s, LoadedConfig& c) {
    c.monitor.battery = s.battery;
    c.monitor.extensions = s.ext;
    c.monitor.current_filter.time_constant_s = s.reaction_time_s;
    // Fitted curve points encode E0 and K, often with a large curve current: the reference
    // estimator must keep E0 when it adopts a resistance (TremblayModel::set_resistance_ohm).
    c.monitor.capacity.resistance_keeps_e0 = true;
}

NaturalParams natural_from_params(const core::TremblayParams& p) {
    core::TremblayModel m;
    m.configure(p);
    const core::TremblayParams& q = m.params();  // after the model's own guards
    NaturalParams n;
    n.e0_v = m.e0_v();
    n.r_ohm = q.internal_resistance_ohm;
    n.a_v = m.a_v();
    n.b_per_ah = m.b_per_ah();
    n.q_ah = q.capacity_ah;
    n.kappa = q.exponential_capacity_ah / (q.exponential_capacity_ah + q.curve_current_a);
    return n;
}

namespace {
// The curve current kappa stands for, q_exp (1/kappa − 1), within the config's limits: full =
// E0 − R·i + A and exponential = full − A must stay ≥ 0.1 V, and the curve current ≤ 10 kA.
double capped_curve_current_a(const NaturalParams& n, double q_exp) {
    const double kappa = std::clamp(n.kappa, 1e-9, 1.0);
    double i_max = 1e4;
    if (n.r_ohm > 0) i_max = std::min(i_max, (n.e0_v - 0.1) / n.r_ohm);
    return std::clamp(q_exp * (1.0 / kappa - 1.0), 0.0, std::max(i_max, 0.0));
}
}  // namespace

double k_of(const NaturalParams& n) {
    // The same guards as params_from_natural(), so K matches the config written: below the
    // kappa the curve current's cap allows, a smaller kappa changes nothing (a fit to a
    // flight had reported K 174 times below the config's).
    const double q = std::max(n.q_ah, 1e-3);
    const double q_exp = std::clamp(3.0 / std::max(n.b_per_ah, 1e-9), 1e-6, 0.999 * q);
    const double k_max = n.a_v * std::exp(-3.0) * (q - q_exp) / (q * q_exp);
    const double kappa = q_exp / (q_exp + capped_curve_current_a(n, q_exp));
    return kappa * k_max;
}

core::TremblayParams params_from_natural(const NaturalParams& n, const core::TremblayParams& keep) {
    core::TremblayParams p = keep;
    const double q = std::max(n.q_ah, 1e-3);
    const double q_exp = std::clamp(3.0 / std::max(n.b_per_ah, 1e-9), 1e-6, 0.999 * q);
    const double i = capped_curve_current_a(n, q_exp);
    p.capacity_ah = static_cast<float>(q);
    p.exponential_capacity_ah = static_cast<float>(q_exp);
    p.internal_resistance_ohm = static_cast<float>(std::max(n.r_ohm, 0.0));
    p.curve_current_a = static_cast<float>(i);
    p.full_voltage_v = static_cast<float>(n.e0_v - n.r_ohm * i + n.a_v);
    p.exponential_voltage_v = static_cast<float>(n.e0_v - n.r_ohm * i);
    const double fraction = keep.capacity_ah > 0 ? std::clamp(static_cast<double>(keep.nominal_zone_capacity_ah) /
                                                                  keep.capacity_ah, 0.0, 0.999)
                                                 : 0.9;
    p.nominal_zone_capacity_ah = static_cast<float>(std::max(fraction * q, 1e-6));
    core::TremblayModel m;
    m.configure(p);
    p.nominal_zone_voltage_v =
        std::max(0.1f, m.voltage_v(p.nominal_zone_capacity_ah, p.curve_current_a, p.curve_current_a));
    return p;
}

void simulate(const Trace& trace, const ModelSpec& spec, InitialMode mode, float initial_ah, SimResult& out,
              bool keep_states) {
    const size_t n = trace.points.size();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    out.model_v.assign(n, nan);
    if (keep_states) {
        out.used_ah.assign(n, nan);
        out.filtered_a.assign(n, nan);
        out.temperature_c.assign(n, nan);
        out.rc_total_v.assign(n, nan);
    }
    core::LowPassFilter filter;
    core::LowPassFilter::Config fc;
    fc.time_constant_s = spec.reaction_time_s;
    filter.configure(fc);
    core::ExtendedModel model;
    model.configure(spec.battery, spec.ext);
    core::CoulombCounter counter;
    bool initialised = false;
    out.initial_ah = 0;
    const long settle = first_model_index(trace, mode);
    for (size_t k = 0; k < n; ++k) {
        const TracePoint& p = trace.points[k];
        if (!p.valid) continue;
        const float current_a = model.corrected_current_a(p.current_a);
        const float filtered_a = filter.update(current_a, p.dt_s);
        model.update(current_a, p.dt_s, p.has_temperature, p.temperature_c);
        if (!initialised) {
            if (static_cast<long>(k) < settle || settle < 0) {
                continue;
            }
            float q0 = initial_ah;
            if (mode == InitialMode::Monitor) q0 = model.used_ah_at_voltage(p.voltage_v, current_a);
            if (mode == InitialMode::Zero) q0 = 0.0f;  // settled on the first valid sample
            counter.reset(q0 * 1000.0f, 0.0f);
            out.initial_ah = counter.status().consumed_mah * 0.001f;
            initialised = true;
        } else {
            counter.update(current_a, p.voltage_v, p.dt_s);
        }
        const float used_ah = counter.status().consumed_mah * 0.001f;
        out.model_v[k] = model.voltage_v(used_ah, current_a, filtered_a);
        if (keep_states) {
            out.used_ah[k] = used_ah;
            out.filtered_a[k] = filtered_a;
            out.temperature_c[k] = model.status().temperature_c;
            float rc = 0;
            for (int b = 0; b < spec.ext.rc_count; ++b) rc += model.status().rc_voltage_v[b];
            out.rc_total_v[k] = rc;
        }
    }
}

long first_model_index(const Trace& trace, InitialMode mode) {
    if (mode != InitialMode::Zero) return trace.settle_index;
    for (size_t k = 0; k < trace.points.size(); ++k) {
        if (trace.points[k].valid) return static_cast<long>(k);
    }
    return -1;
}

bool in_window(const Trace& trace, size_t k, Window w, InitialMode mode) {
    const TracePoint& p = trace.points[k];
    const long first = first_model_index(trace, mode);
    if (!p.valid || first < 0 || static_cast<long>(k) < first) return false;
    return w == Window::All || p.in_flight;
}

ErrorStats error_stats(const Trace& trace, const std::vector<float>& model_v, Window window,
                       const std::vector<uint8_t>* mask) {
    ErrorStats s;
    double sum = 0, abs_sum = 0, sq_sum = 0;
    for (size_t k = 0; k < trace.points.size() && k < model_v.size(); ++k) {
        const TracePoint& p = trace.points[k];
        if (!p.valid || !std::isfinite(model_v[k]) || (window == Window::Flight && !p.in_flight)) continue;
        if (mask != nullptr && (k >= mask->size() || !(*mask)[k])) continue;
        const double e = static_cast<double>(p.voltage_v) - model_v[k];
        ++s.n;
        sum += e;
        abs_sum += std::fabs(e);
        sq_sum += e * e;
        s.max_abs_v = std::max(s.max_abs_v, std::fabs(e));
    }
    if (s.n > 0) {
        s.mean_v = sum / s.n;
        s.mae_v = abs_sum / s.n;
        s.rmse_v = std::sqrt(sq_sum / s.n);
    }
    return s;
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
