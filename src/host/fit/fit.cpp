#include "host/fit/fit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>

#include "host/report/summary.h"

namespace battsim {
namespace host {
namespace fit {

namespace {

enum class Kind { E0, R, Kappa, A, B, Q, Reaction, RcR, RcTau, TempR, TempK, TempQ, TempE0, ThermalRth, ThermalTau,
                  HystM, HystRate, Ocv, Gain, Offset, Lead, Initial };

struct Def {
    Kind kind;
    int index = 0;  // RC branch or OCV point
    std::string name;
    const char* unit = "";
    double lo = 0, hi = 0, typical = 1;
};

bool is_base(Kind k) { return k == Kind::E0 || k == Kind::R || k == Kind::Kappa || k == Kind::A || k == Kind::B || k == Kind::Q; }

// `full_v` and `capacity_ah` scale the plausibility bounds (the pack's size, not the fit's
// current state, so a refit never finds its start outside the box).
std::vector<Def> expand(const std::string& name, const ModelSpec& s, double full_v, double capacity_ah) {
    auto one = [&](Kind k, const char* unit, double lo, double hi, double typ, int index = 0) {
        return std::vector<Def>{Def{k, index, name, unit, lo, hi, typ}};
    };
    if (name == "e0") return one(Kind::E0, "V", 0.1, 1000, 1.0);
    if (name == "r") return one(Kind::R, "ohm", 0, 10, 0.005);
    if (name == "kappa") return one(Kind::Kappa, "", 1e-6, 1, 0.01);
    if (name == "a") return one(Kind::A, "V", 1e-4, 100, 0.05);
    if (name == "b") return one(Kind::B, "1/Ah", 1e-2, 1e5, 1.0);
    if (name == "q") return one(Kind::Q, "Ah", 1e-3, 1e4, 0.1);
    if (name == "reaction") return one(Kind::Reaction, "s", 0.05, 1e4, 1.0);
    if (name.size() >= 5 && name.compare(0, 2, "rc") == 0 && name[2] >= '1' && name[2] <= '3' && name[3] == '_') {
        const int b = name[2] - '1';
        if (b >= s.ext.rc_count)
            throw std::invalid_argument("parameter \"" + name + "\": RC branch " + std::to_string(b + 1) +
                                        " is not enabled (the model has " + std::to_string(s.ext.rc_count) + ")");
        const std::string what = name.substr(4);
        // Polarisation, not a second charge counter: a branch slower than an hour with ohms of
        // resistance would integrate the current and stand in for the OCV slope.
        if (what == "r") return one(Kind::RcR, "ohm", 0, 0.02 * std::max(full_v, 0.1), 1e-3, b);
        if (what == "tau") return one(Kind::RcTau, "s", 0.05, 3600, 0.1, b);
    }
    // Plausibility bounds: a fit may use an effect's parameters to paper over a different
    // misfit (a current "gain" of 0.5, a hysteresis of volts); values beyond these are not
    // that effect any more. Scaled by the pack's full voltage (4.2 V per Li-ion cell).
    const double v_full = std::max(full_v, 0.1);
    auto need = [&](bool on, const char* ext) {
        if (!on) throw std::invalid_argument("parameter \"" + name + "\": the " + ext + " extension is not enabled");
    };
    if (name == "temp_r" || name == "temp_k" || name == "temp_q" || name == "temp_e0") {
        need(s.ext.temperature.enabled, "temperature");
        // Resistance and polarisation rise in the cold; capacity falls; E0's entropic slope
        // stays within 1 mV/K per cell.
        if (name == "temp_r") return one(Kind::TempR, "K", 0, 1.5e4, 100);
        if (name == "temp_k") return one(Kind::TempK, "K", 0, 1.5e4, 100);
        if (name == "temp_q") return one(Kind::TempQ, "Ah/degC", 0, 0.02 * capacity_ah, 1e-3);
        return one(Kind::TempE0, "V/degC", -2.4e-4 * v_full, 2.4e-4 * v_full, 1e-4);
    }
    if (name == "thermal_rth" || name == "thermal_tau") {
        need(s.ext.thermal.enabled, "thermal");
        if (name == "thermal_rth") return one(Kind::ThermalRth, "K/W", 0, 1e4, 0.1);
        return one(Kind::ThermalTau, "s", 1, 1e6, 10);
    }
    // Hysteresis lowers the voltage after discharge and raises it after charge: M ≥ 0.
    if (name == "hyst_m") return one(Kind::HystM, "V", 0, 0.02 * v_full, 1e-3);
    // The rate is harmless with a zero magnitude (a fit may drive M to its bound of 0).
    if (name == "hyst_rate") return one(Kind::HystRate, "1/Ah", 0.01, 1e5, 1);
    if (name == "ocv") {
        need(s.ext.ocv.count >= 2, "ocv_correction");
        std::vector<Def> v;
        for (int j = 0; j < s.ext.ocv.count; ++j)
            v.push_back(Def{Kind::Ocv, j, "ocv" + std::to_string(j + 1), "V", -0.15 * v_full, 0.15 * v_full, 1e-3});
        return v;
    }
    // A current sensor more than 10 % off, or a skew beyond a second, is a wiring or
    // configuration fault to fix, not an effect to fit.
    if (name == "gain") return one(Kind::Gain, "", 0.9, 1.1, 0.01);
    if (name == "offset") return one(Kind::Offset, "A", -10, 10, 0.01);
    if (name == "lead") return one(Kind::Lead, "s", -1, 1, 0.01);
    check_parameter_name(name);
    throw std::logic_error("parameter \"" + name + "\" is known but has no definition");
}

double get(const ModelSpec& s, const NaturalParams& n, const Def& d) {
    switch (d.kind) {
        case Kind::E0: return n.e0_v;
        case Kind::R: return n.r_ohm;
        case Kind::Kappa: return n.kappa;
        case Kind::A: return n.a_v;
        case Kind::B: return n.b_per_ah;
        case Kind::Q: return n.q_ah;
        case Kind::Reaction: return s.reaction_time_s;
        case Kind::RcR: return s.ext.rc[d.index].resistance_ohm;
        case Kind::RcTau: return s.ext.rc[d.index].time_constant_s;
        case Kind::TempR: return s.ext.temperature.resistance_activation_k;
        case Kind::TempK: return s.ext.temperature.polarisation_activation_k;
        case Kind::TempQ: return s.ext.temperature.capacity_ah_per_c;
        case Kind::TempE0: return s.ext.temperature.e0_v_per_c;
        case Kind::ThermalRth: return s.ext.thermal.thermal_resistance_k_per_w;
        case Kind::ThermalTau: return s.ext.thermal.time_constant_s;
        case Kind::HystM: return s.ext.hysteresis.magnitude_v;
        case Kind::HystRate: return s.ext.hysteresis.rate_per_ah;
        case Kind::Ocv: return s.ext.ocv.delta_v[d.index];
        case Kind::Gain: return s.ext.current_sensor.gain;
        case Kind::Offset: return s.ext.current_sensor.offset_a;
        case Kind::Lead: return s.ext.current_sensor.lead_s;
        case Kind::Initial: return 0;
    }
    return 0;
}

void set(ModelSpec& s, NaturalParams& n, const Def& d, double v) {
    const float f = static_cast<float>(v);
    switch (d.kind) {
        case Kind::E0: n.e0_v = v; break;
        case Kind::R: n.r_ohm = v; break;
        case Kind::Kappa: n.kappa = v; break;
        case Kind::A: n.a_v = v; break;
        case Kind::B: n.b_per_ah = v; break;
        case Kind::Q: n.q_ah = v; break;
        case Kind::Reaction: s.reaction_time_s = f; break;
        case Kind::RcR: s.ext.rc[d.index].resistance_ohm = f; break;
        case Kind::RcTau: s.ext.rc[d.index].time_constant_s = f; break;
        case Kind::TempR: s.ext.temperature.resistance_activation_k = f; break;
        case Kind::TempK: s.ext.temperature.polarisation_activation_k = f; break;
        case Kind::TempQ: s.ext.temperature.capacity_ah_per_c = f; break;
        case Kind::TempE0: s.ext.temperature.e0_v_per_c = f; break;
        case Kind::ThermalRth: s.ext.thermal.thermal_resistance_k_per_w = f; break;
        case Kind::ThermalTau: s.ext.thermal.time_constant_s = f; break;
        case Kind::HystM: s.ext.hysteresis.magnitude_v = f; break;
        case Kind::HystRate: s.ext.hysteresis.rate_per_ah = f; break;
        case Kind::Ocv: s.ext.ocv.delta_v[d.index] = f; break;
        case Kind::Gain: s.ext.current_sensor.gain = f; break;
        case Kind::Offset: s.ext.current_sensor.offset_a = f; break;
        case Kind::Lead: s.ext.current_sensor.lead_s = f; break;
        case Kind::Initial: break;
    }
}

struct Slot {
    Def def;
    int log = -1;  // -1 = shared
};

// How far a multi-start's points reach from a parameter's start: times or over `factor`
// (log-uniform) around a positive start of a parameter that cannot go negative, else ±
// `width`; both clipped to the parameter's box. Wide where logs often leave a parameter
// loose (time constants, the exponential zone, the activation energies), narrow where a
// wrong start only costs iterations (E0, the capacity).
struct StartSpread {
    double factor = 1, width = 0;
};

StartSpread spread_of(const Def& d) {
    const double box = d.hi - d.lo;
    switch (d.kind) {
        case Kind::E0: return {1.05, 0.05 * box};
        case Kind::R: return {2, 0.01};
        case Kind::Kappa: return {10, 0.1};
        case Kind::A: case Kind::B: case Kind::Reaction: return {3, 3 * d.typical};
        case Kind::Q: return {1.3, 0.3 * d.typical};
        case Kind::RcR: return {3, box / 4};
        case Kind::RcTau: return {5, box / 4};
        case Kind::TempR: case Kind::TempK: return {2, 3000};
        case Kind::TempQ: case Kind::TempE0: case Kind::HystM: return {3, box / 2};
        case Kind::ThermalRth: return {3, 1};
        case Kind::ThermalTau: case Kind::HystRate: return {3, 3 * d.typical};
        case Kind::Ocv: return {1, box / 15};  // ± 2 % of the full voltage
        case Kind::Gain: return {1.1, box / 2};
        case Kind::Offset: return {1, 0.5};
        case Kind::Lead: return {1, 0.5};
        case Kind::Initial: return {3, 0.2 * box};
    }
    return {};
}

// The median interval between the logs' valid samples (0 when they have none).
double median_interval_s(const std::vector<Trace>& traces) {
    std::vector<float> dt;
    for (const Trace& t : traces) {
        for (const TracePoint& p : t.points)
            if (p.valid && p.dt_s > 0.0f) dt.push_back(p.dt_s);
    }
    if (dt.empty()) return 0.0;
    std::nth_element(dt.begin(), dt.begin() + static_cast<long>(dt.size() / 2), dt.end());
    return dt[dt.size() / 2];
}

class Problem {
public:
    Problem(const std::vector<Trace>& traces, const std::vector<ModelSpec>& start, const FitOptions& o)
        : traces_(traces), options_(o) {
        if (traces.empty()) throw std::invalid_argument("no logs");
        if (start.size() != 1 && start.size() != traces.size())
            throw std::invalid_argument("expected one start spec or one per log");
        for (size_t t = 0; t < traces.size(); ++t) {
            start_.push_back(start.size() == 1 ? start[0] : start[t]);
            natural_.push_back(natural_from_params(start_.back().battery));
        }
        auto add = [&](const std::string& name, int log) {
            const ModelSpec& st = start_[log < 0 ? 0 : log];
            const double full_v = o.bounds_full_voltage_v > 0 ? o.bounds_full_voltage_v : st.battery.full_voltage_v;
            const double cap = o.bounds_capacity_ah > 0 ? o.bounds_capacity_ah : st.battery.capacity_ah;
            for (const Def& d : expand(name, st, full_v, cap)) {
                for (const Slot& s : slots_) {
                    if (s.def.name == d.name && (s.log == log || s.log < 0 || log < 0))
                        throw std::invalid_argument("parameter \"" + d.name + "\" given twice");
                }
                slots_.push_back(Slot{d, log});
                if (is_base(d.kind)) base_free_ = true;
            }
        };
        for (const std::string& p : o.params) add(p, -1);
        for (const std::string& p : o.per_log_params) {
            for (size_t t = 0; t < traces.size(); ++t) add(p, static_cast<int>(t));
        }
        if (o.initial == InitialMode::Free) {
            for (size_t t = 0; t < traces.size(); ++t) {
                const double q = start_[t].battery.capacity_ah;
                // Not below zero: the monitor's own estimate (the model inverted) never is, so a
                // model that needs a pack "fuller than full" would not replay as fitted.
                slots_.push_back(Slot{Def{Kind::Initial, 0, "initial", "Ah", 0.0, q, 0.01}, static_cast<int>(t)});
            }
        }
        select_points();
        for (size_t j = 0; j < slots_.size(); ++j) {
            for (size_t k = 0; k < o.priors.size(); ++k) {
                if (o.priors[k].name == slots_[j].def.name) {
                    if (!(o.priors[k].sigma > 0)) throw std::invalid_argument("prior on \"" + o.priors[k].name + "\": sigma must be positive");
                    prior_of_.push_back({static_cast<int>(j), static_cast<int>(k)});
                }
            }
        }
        // Charge counted after each log's settle sample: the capacity must exceed it.
        for (const Trace& tr : traces_) {
            double sum = 0, peak = 0;
            const long first = first_model_index(tr, o.initial);
            for (long k = std::max(first, 0L) + 1; k < static_cast<long>(tr.points.size()); ++k) {
                const TracePoint& p = tr.points[k];
                if (!p.valid || first < 0) continue;
                sum += static_cast<double>(p.current_a) * p.dt_s / 3600.0;
                peak = std::max(peak, sum);
            }
            counted_ah_.push_back(peak);
        }
        for (size_t j = 0; j < slots_.size(); ++j) {
            if (slots_[j].def.kind == Kind::Q) q_slot_log_ = slots_[j].log;  // −1 shared; per-log: any log
            if (slots_[j].def.kind == Kind::Initial) initial_slot_[slots_[j].log] = static_cast<int>(j);
        }
        // The capacity's box: from the charge drawn (with the starting initial charge) to the
        // cap; B keeps the exponential zone inside the largest capacity allowed. spec_for()
        // applies the floor again with the current initial charge.
        for (Slot& sl : slots_) {
            if (sl.def.kind != Kind::Q && sl.def.kind != Kind::B) continue;
            const size_t first = sl.log < 0 ? 0 : static_cast<size_t>(sl.log);
            const size_t last = sl.log < 0 ? traces_.size() : first + 1;
            double floor_ah = 0, cap = 0;
            for (size_t u = first; u < last; ++u) {
                const double q0 = o.initial == InitialMode::Zero ? 0.0
                                  : o.initial_start && u < o.initial_start->size() ? (*o.initial_start)[u]
                                                                                  : traces_[u].monitor_initial_ah;
                floor_ah = std::max(floor_ah, 1.01 * (std::max(q0, 0.0) + counted_ah_[u]));
                cap = std::max(cap, capacity_cap(static_cast<int>(u)));
            }
            cap = std::max(cap, floor_ah);
            if (sl.def.kind == Kind::Q) {
                sl.def.lo = std::max(sl.def.lo, floor_ah);
                sl.def.hi = std::min(sl.def.hi, cap);
            } else {
                sl.def.lo = std::max(sl.def.lo, 3.0 / (0.99 * cap));
            }
        }
        // An RC branch relaxing within a few samples cannot be told from the ohmic resistance,
        // and takes it over: the Panasonic cell's 10 Hz fit put 31 mOhm into a 0.18 s branch and
        // left R at 0, and the monitor, whose resistance pairs samples 0.13 s and more apart,
        // then read the cell as far more resistive than its config (high_resistance 2 s into
        // the very log it was fitted to). So a branch is no faster than three usual intervals.
        const double min_tau_s = 3.0 * median_interval_s(traces_);
        for (Slot& sl : slots_) {
            if (sl.def.kind == Kind::RcTau) sl.def.lo = std::max(sl.def.lo, std::min(min_tau_s, 0.5 * sl.def.hi));
        }
    }

    LmProblem lm_problem() {
        LmProblem p;
        p.n_params = static_cast<int>(slots_.size());
        for (const auto& pts : points_) p.group_sizes.push_back(static_cast<int>(pts.size()));
        if (!prior_of_.empty()) p.group_sizes.push_back(static_cast<int>(prior_of_.size()));
        p.lower.resize(p.n_params);
        p.upper.resize(p.n_params);
        p.typical.resize(p.n_params);
        for (int j = 0; j < p.n_params; ++j) {
            const Slot& s = slots_[j];
            p.lower[j] = s.def.lo;
            p.upper[j] = s.def.hi;
            p.typical[j] = s.def.typical;
            std::vector<int> groups;
            if (s.log >= 0) {
                groups.push_back(s.log);
                for (const auto& pr : prior_of_) {
                    if (pr.first == j) groups.push_back(static_cast<int>(traces_.size()));
                }
            }
            p.param_groups.push_back(groups);
        }
        p.residuals = [this](const Eigen::VectorXd& x, int g, double* r) { residuals(x, g, r); };
        return p;
    }

    Eigen::VectorXd start_vector() const {
        Eigen::VectorXd x(slots_.size());
        for (size_t j = 0; j < slots_.size(); ++j) {
            const Slot& s = slots_[j];
            const int t = s.log < 0 ? 0 : s.log;
            if (s.def.kind == Kind::Initial) {
                const double q0 = options_.initial_start && static_cast<size_t>(t) < options_.initial_start->size()
                                      ? (*options_.initial_start)[t]
                                      : traces_[t].monitor_initial_ah;
                x[j] = std::clamp(q0, s.def.lo, s.def.hi);
            } else {
                x[j] = std::clamp(get(start_[t], natural_[t], s.def), s.def.lo, s.def.hi);
            }
        }
        return x;
    }

    // Capacity slot j as reported: the model's capacity where spec_for() holds it up at the
    // charge the logs drew, else the fitted value itself.
    double reported_capacity(const Eigen::VectorXd& x, size_t j) const {
        const double effective = spec_for(x, slots_[j].log < 0 ? 0 : slots_[j].log).battery.capacity_ah;
        return std::fabs(effective - x[j]) > 1e-6 * effective ? effective : x[j];
    }

    // x with the fitted RC branches reordered to rank by time constant as they do in `like`.
    // Two branches that trade places fit the same: for comparing fits, one solution. A
    // shared time constant carries its branch's resistances in every log along; a log's own
    // time constant, that log's resistance.
    Eigen::VectorXd rc_branches_like(const Eigen::VectorXd& x, const Eigen::VectorXd& like) const {
        Eigen::VectorXd y = x;
        for (int group = -1; group < static_cast<int>(traces_.size()); ++group) {
            int tau_slot[core::kMaxRcBranches];
            std::map<int, int> r_slots[core::kMaxRcBranches];  // log (−1 shared) → slot
            std::fill(tau_slot, tau_slot + core::kMaxRcBranches, -1);
            for (size_t j = 0; j < slots_.size(); ++j) {
                const Slot& sl = slots_[j];
                if (sl.def.kind == Kind::RcTau && sl.log == group) tau_slot[sl.def.index] = static_cast<int>(j);
                if (sl.def.kind == Kind::RcR && (sl.log == group || (group < 0 && sl.log >= 0)))
                    r_slots[sl.def.index][sl.log] = static_cast<int>(j);
            }
            std::vector<int> both;  // branches with time constant and resistances fitted: interchangeable
            for (int b = 0; b < core::kMaxRcBranches; ++b) {
                if (tau_slot[b] >= 0 && !r_slots[b].empty()) both.push_back(b);
            }
            // Only branches whose resistances are fitted in the same logs can trade places.
            for (int b : both) {
                if (r_slots[b].size() != r_slots[both[0]].size() ||
                    !std::equal(r_slots[b].begin(), r_slots[b].end(), r_slots[both[0]].begin(),
                                [](const auto& u, const auto& v) { return u.first == v.first; }))
                    both.clear();
                if (both.empty()) break;
            }
            const auto by_tau = [&](const Eigen::VectorXd& v) {
                std::vector<int> order = both;
                std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return v[tau_slot[a]] < v[tau_slot[b]]; });
                return order;
            };
            const std::vector<int> mine = by_tau(x), theirs = by_tau(like);
            for (size_t i = 0; i < both.size(); ++i) {
                y[tau_slot[theirs[i]]] = x[tau_slot[mine[i]]];
                for (const auto& r : r_slots[theirs[i]]) y[r.second] = x[r_slots[mine[i]].at(r.first)];
            }
        }
        return y;
    }

    // `count` starting points around x0 (spread_of), a Latin hypercube.
    std::vector<Eigen::VectorXd> spread_starts(const Eigen::VectorXd& x0, int count) const {
        Eigen::VectorXd lo(x0.size()), hi(x0.size());
        std::vector<bool> log_scale(x0.size());
        for (size_t j = 0; j < slots_.size(); ++j) {
            const Def& d = slots_[j].def;
            const StartSpread sp = spread_of(d);
            log_scale[j] = d.lo >= 0 && x0[j] > 0 && sp.factor > 1;
            lo[j] = log_scale[j] ? std::max(d.lo, x0[j] / sp.factor) : std::max(d.lo, x0[j] - sp.width);
            hi[j] = log_scale[j] ? std::min(d.hi, x0[j] * sp.factor) : std::min(d.hi, x0[j] + sp.width);
        }
        return latin_hypercube(lo, hi, log_scale, count, 0x6261747473696dULL);  // "battsim"
    }

    ModelSpec spec_for(const Eigen::VectorXd& x, int t, float* initial_ah = nullptr) const {
        ModelSpec s = start_[t];
        NaturalParams n = natural_[t];
        for (size_t j = 0; j < slots_.size(); ++j) {
            const Slot& sl = slots_[j];
            if (sl.log >= 0 && sl.log != t) continue;
            if (sl.def.kind == Kind::Initial) {
                if (initial_ah) *initial_ah = static_cast<float>(x[j]);
                continue;
            }
            set(s, n, sl.def, x[j]);
        }
        // A fitted capacity never falls below the charge the log shows was drawn: past it the
        // Q/(Q − it) pole would wreck every sample the fit did not see.
        if (q_slot_log_ != kNoQ) {
            const size_t first = q_slot_log_ < 0 ? 0 : static_cast<size_t>(t);
            const size_t last = q_slot_log_ < 0 ? traces_.size() : first + 1;
            double floor_ah = 0;
            for (size_t u = first; u < last; ++u) {
                const auto it = initial_slot_.find(static_cast<int>(u));
                const double q0 = it != initial_slot_.end() ? x[it->second]
                                  : options_.initial == InitialMode::Zero ? 0.0
                                                                          : traces_[u].monitor_initial_ah;
                floor_ah = std::max(floor_ah, std::max(q0, 0.0) + counted_ah_[u] * std::max(1.0, static_cast<double>(s.ext.current_sensor.gain)));
            }
            n.q_ah = std::min(n.q_ah, capacity_cap(t));
            n.q_ah = std::max(n.q_ah, 1.01 * floor_ah);
        }
        // Untouched base parameters keep the config's own float values (no round trip).
        if (base_free_) s.battery = params_from_natural(n, start_[t].battery);
        return s;
    }

    void residuals(const Eigen::VectorXd& x, int t, double* r) const {
        if (t == static_cast<int>(traces_.size())) {
            for (size_t i = 0; i < prior_of_.size(); ++i) {
                const FitOptions::Prior& pr = options_.priors[prior_of_[i].second];
                r[i] = options_.prior_noise_v * (x[prior_of_[i].first] - pr.mean) / pr.sigma;
            }
            return;
        }
        float q0 = 0;
        const ModelSpec s = spec_for(x, t, &q0);
        SimResult sim;
        simulate(traces_[t], s, options_.initial, q0, sim);
        const std::vector<size_t>& pts = points_[t];
        const double w = weights_[t];
        for (size_t i = 0; i < pts.size(); ++i) {
            const size_t k = pts[i];
            r[i] = w * (static_cast<double>(traces_[t].points[k].voltage_v) - sim.model_v[k]);
        }
    }

    // Derived quantities of log t's base model: K, and the config's curve points.
    std::vector<double> derived(const Eigen::VectorXd& x, int t) const {
        NaturalParams n = natural_[t];
        ModelSpec s = start_[t];
        for (size_t j = 0; j < slots_.size(); ++j) {
            const Slot& sl = slots_[j];
            if ((sl.log >= 0 && sl.log != t) || !is_base(sl.def.kind)) continue;
            set(s, n, sl.def, x[j]);
        }
        const core::TremblayParams p = params_from_natural(n, start_[t].battery);
        return {k_of(n), p.full_voltage_v, p.exponential_voltage_v, p.exponential_capacity_ah, p.curve_current_a};
    }

    // Base parameters (E0, R, kappa, A, B, Q) that best fit the selected points by linear least
    // squares, Q and B on a grid, everything else as in x. Returns false if the base is not
    // entirely shared and free.
    bool linear_base_start(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
        int slot[6] = {-1, -1, -1, -1, -1, -1};
        for (size_t j = 0; j < slots_.size(); ++j) {
            if (!is_base(slots_[j].def.kind)) continue;
            if (slots_[j].log >= 0) return false;
            slot[static_cast<int>(slots_[j].def.kind)] = static_cast<int>(j);
        }
        for (int k : slot) {
            if (k < 0) return false;
        }
        // Per point: charge drawn, current, filtered current, target (measured + RC drop).
        struct Row { double it, i, fi, y, w; };
        std::vector<Row> rows;
        double floor_ah = 0;
        for (size_t t = 0; t < traces_.size(); ++t) {
            float q0 = 0;
            const ModelSpec s = spec_for(x, static_cast<int>(t), &q0);
            SimResult sim;
            simulate(traces_[t], s, options_.initial, q0, sim, true);
            for (size_t k : points_[t]) {
                if (!std::isfinite(sim.model_v[k])) continue;
                const double i = s.ext.current_sensor.gain * traces_[t].points[k].current_a + s.ext.current_sensor.offset_a;
                rows.push_back(Row{sim.used_ah[k], i, sim.filtered_a[k],
                                   static_cast<double>(traces_[t].points[k].voltage_v) + sim.rc_total_v[k], weights_[t] * weights_[t]});
                floor_ah = std::max(floor_ah, static_cast<double>(sim.used_ah[k]));
            }
        }
        if (rows.size() < 8) return false;
        floor_ah = std::max(1.01 * floor_ah, 1e-3);
        static const double kQ[] = {1.0, 1.02, 1.05, 1.1, 1.2, 1.35, 1.5, 1.75, 2.0, 3.0};
        const double q_cap = std::max(capacity_cap(0), floor_ah);
        static const double kExp[] = {0.003, 0.006, 0.01, 0.02, 0.035, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.45, 0.6};
        double best_sse = std::numeric_limits<double>::infinity();
        NaturalParams best;
        for (double qf : kQ) {
            const double q = qf * floor_ah;
            if (q > q_cap && qf > 1.0) continue;
            for (double ef : kExp) {
                const double b = 3.0 / (ef * q);
                // Columns: 1, −i, −Q/(Q−it)·(i* + it), e^(−B·it); unknowns E0, R, K, A.
                Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
                Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
                for (const Row& r : rows) {
                    const double it = std::min(r.it, q * (1 - core::TremblayModel::kMinRemainingFraction));
                    const Eigen::Vector4d c(1.0, -r.i, -(q / (q - it)) * (r.fi + it), std::exp(-b * std::max(it, 0.0)));
                    A += r.w * c * c.transpose();
                    rhs += r.w * r.y * c;
                }
                // Drop terms whose coefficient comes out with the wrong sign (R, K, A ≥ 0).
                bool keep[4] = {true, true, true, true};
                Eigen::Vector4d sol = Eigen::Vector4d::Zero();
                for (int pass = 0; pass < 4; ++pass) {
                    std::vector<int> on;
                    for (int c = 0; c < 4; ++c) {
                        if (keep[c]) on.push_back(c);
                    }
                    Eigen::MatrixXd As(on.size(), on.size());
                    Eigen::VectorXd bs(on.size());
                    for (size_t a = 0; a < on.size(); ++a) {
                        bs[a] = rhs[on[a]];
                        for (size_t c = 0; c < on.size(); ++c) As(a, c) = A(on[a], on[c]);
                    }
                    const Eigen::VectorXd z = As.ldlt().solve(bs);
                    sol.setZero();
                    for (size_t a = 0; a < on.size(); ++a) sol[on[a]] = z[a];
                    bool changed = false;
                    for (int c = 1; c < 4; ++c) {
                        if (keep[c] && !(sol[c] >= 0)) {
                            keep[c] = false;
                            changed = true;
                        }
                    }
                    if (!changed) break;
                }
                if (!sol.allFinite()) continue;
                double sse = 0;
                for (const Row& r : rows) {
                    const double it = std::min(r.it, q * (1 - core::TremblayModel::kMinRemainingFraction));
                    const double v = sol[0] - sol[1] * r.i - sol[2] * (q / (q - it)) * (r.fi + it) + sol[3] * std::exp(-b * std::max(it, 0.0));
                    sse += r.w * (r.y - v) * (r.y - v);
                }
                if (sse < best_sse) {
                    best_sse = sse;
                    best.e0_v = sol[0];
                    best.r_ohm = sol[1];
                    best.a_v = std::max(sol[3], 1e-4);
                    best.b_per_ah = b;
                    best.q_ah = q;
                    NaturalParams probe = best;
                    probe.kappa = 1.0;
                    const double k_max = k_of(probe);
                    best.kappa = k_max > 0 ? std::clamp(sol[2] / k_max, 1e-6, 1.0) : 1e-6;
                }
            }
        }
        if (!std::isfinite(best_sse)) return false;
        out = x;
        const double values[6] = {best.e0_v, best.r_ohm, best.kappa, best.a_v, best.b_per_ah, best.q_ah};
        for (int k = 0; k < 6; ++k) out[slot[k]] = std::clamp(values[k], slots_[slot[k]].def.lo, slots_[slot[k]].def.hi);
        return true;
    }

    double capacity_cap(int t) const {
        return options_.max_capacity_ah > 0 ? options_.max_capacity_ah
                                            : options_.max_capacity_factor * start_[t].battery.capacity_ah;
    }

    const std::vector<Slot>& slots() const { return slots_; }
    const std::vector<std::vector<size_t>>& points() const { return points_; }
    const std::vector<double>& weights() const { return weights_; }
    bool base_free() const { return base_free_; }

private:
    void select_points() {
        size_t total = 0;
        for (size_t t = 0; t < traces_.size(); ++t) {
            const Trace& tr = traces_[t];
            std::vector<size_t> all;
            for (size_t k = 0; k < tr.points.size(); ++k) {
                if (!in_window(tr, k, options_.window, options_.initial)) continue;
                if (options_.mask && (t >= options_.mask->size() || k >= (*options_.mask)[t].size() || !(*options_.mask)[t][k]))
                    continue;
                all.push_back(k);
            }
            std::vector<size_t> kept;
            const size_t cap = std::max<size_t>(options_.max_points_per_log, 1);
            if (all.size() <= cap) {
                kept = all;
            } else {
                // Evenly spread, deterministic thinning.
                for (size_t i = 0; i < cap; ++i) kept.push_back(all[i * all.size() / cap]);
            }
            if (kept.empty()) throw TooLittleData(tr.path, "no sample to fit: " + why_no_samples(tr));
            total += kept.size();
            points_.push_back(std::move(kept));
        }
        for (size_t t = 0; t < traces_.size(); ++t) {
            const double mean = static_cast<double>(total) / traces_.size();
            weights_.push_back(options_.equal_log_weights ? std::sqrt(mean / points_[t].size()) : 1.0);
        }
    }

    // What kept every sample of `tr` out of the objective, said in the options that change it.
    std::string why_no_samples(const Trace& tr) const {
        size_t valid = 0, flying = 0;
        double max_a = -INFINITY;
        for (const TracePoint& p : tr.points) {
            if (!p.valid) continue;
            ++valid;
            flying += p.flying;
            max_a = std::max(max_a, static_cast<double>(p.current_a));
        }
        char buf[300];
        if (valid == 0) {
            std::snprintf(buf, sizeof buf, "none of its %zu samples is valid (the config's sensor limits kept every one out)",
                          tr.points.size());
            return buf;
        }
        if (first_model_index(tr, options_.initial) < 0)
            return "the monitor never set its initial charge (it waits for a rest at the start); a log that starts "
                   "full, such as a discharge test, fits with --initial zero";
        if (options_.window == Window::Flight && flying == 0) {
            std::snprintf(buf, sizeof buf,
                          "it has no flight for --window flight: %s the flying current (monitor.min_flying_current_a, "
                          "%.3g A; the highest valid one is %.3g A)",
                          max_a >= tr.flying_current_a ? "no take-off held" : "no sample reached",
                          static_cast<double>(tr.flying_current_a), max_a);
            return std::string(buf) + "; give --window all";
        }
        if (options_.window == Window::Flight)
            return "its flight window holds no sample after the initial charge was set; give --window all";
        return "none in the samples kept for the fit";
    }

    const std::vector<Trace>& traces_;
    const FitOptions& options_;
    std::vector<ModelSpec> start_;
    std::vector<NaturalParams> natural_;
    std::vector<Slot> slots_;
    std::vector<std::vector<size_t>> points_;
    std::vector<double> weights_;
    std::vector<double> counted_ah_;
    std::vector<std::pair<int, int>> prior_of_;  // (slot, prior) pairs: the extra residual group
    static constexpr int kNoQ = -2;
    int q_slot_log_ = kNoQ;  // kNoQ: capacity not fitted; −1: shared; ≥ 0: per log
    std::map<int, int> initial_slot_;  // log → its initial-charge slot
    bool base_free_ = false;
};

// Unweighted residual statistics over the objective's points and the lag-1
// autocorrelation in time order (the priors' residuals, after the logs', are left out).
struct ObjectiveStats {
    size_t n = 0;
    double rmse_v = 0, mae_v = 0, lag1 = 0;
};

ObjectiveStats objective_stats(const Eigen::VectorXd& residuals, const std::vector<std::vector<size_t>>& points,
                               const std::vector<double>& weights) {
    double sq = 0, ab = 0, lag = 0, lag0 = 0;
    size_t n = 0, offset = 0;
    for (size_t t = 0; t < points.size(); ++t) {
        const size_t m = points[t].size();
        const double w = weights[t];
        for (size_t i = 0; i < m; ++i) {
            const double e = residuals[offset + i] / w;
            sq += e * e;
            ab += std::fabs(e);
            lag0 += e * e;
            if (i > 0) lag += e * (residuals[offset + i - 1] / w);
            ++n;
        }
        offset += m;
    }
    ObjectiveStats s;
    s.n = n;
    s.rmse_v = n ? std::sqrt(sq / n) : 0;
    s.mae_v = n ? ab / n : 0;
    s.lag1 = lag0 > 0 ? lag / lag0 : 0;
    return s;
}

}  // namespace

std::vector<std::string> known_parameter_names() {
    return {"e0", "r", "kappa", "a", "b", "q", "reaction", "rc1_r", "rc1_tau", "rc2_r", "rc2_tau", "rc3_r", "rc3_tau",
            "temp_r", "temp_k", "temp_q", "temp_e0", "thermal_rth", "thermal_tau", "hyst_m", "hyst_rate", "ocv",
            "gain", "offset", "lead"};
}

void check_parameter_name(const std::string& name, const std::string& option) {
    const std::vector<std::string> known = known_parameter_names();
    if (std::find(known.begin(), known.end(), name) != known.end()) return;
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    throw std::invalid_argument((option.empty() ? std::string() : option + ": ") + "unknown parameter \"" + name +
                                "\"; expected one of " + list);
}

std::vector<std::string> default_parameters(const ModelSpec& s) {
    std::vector<std::string> p = {"e0", "r", "kappa", "a", "b", "q"};
    for (int b = 0; b < s.ext.rc_count; ++b) {
        p.push_back("rc" + std::to_string(b + 1) + "_r");
        p.push_back("rc" + std::to_string(b + 1) + "_tau");
    }
    if (s.ext.temperature.enabled) {
        for (const char* n : {"temp_r", "temp_k", "temp_q", "temp_e0"}) p.push_back(n);
    }
    if (s.ext.thermal.enabled) {
        p.push_back("thermal_rth");
        p.push_back("thermal_tau");
    }
    if (s.ext.hysteresis.magnitude_v != 0.0f) {
        p.push_back("hyst_m");
        p.push_back("hyst_rate");
    }
    if (s.ext.ocv.count >= 2) p.push_back("ocv");
    return p;
}

std::vector<FitOptions::Prior> default_priors(const ModelSpec& spec) {
    std::vector<FitOptions::Prior> p;
    const NaturalParams n = natural_from_params(spec.battery);
    const double e0 = std::max(std::fabs(n.e0_v), 0.1);
    if (spec.ext.temperature.enabled) {
        p.push_back({"temp_e0", 0.0, 3e-4 * e0 / 3.7});
        p.push_back({"temp_q", 0.0, 0.005 * n.q_ah});
    }
    return p;
}

double near_best_cost(int params, size_t points, double lag1) {
    const double rho = std::clamp(lag1, 0.0, 0.999);
    const double n_eff = std::max(static_cast<double>(points) * (1 - rho) / (1 + rho), 1.0);
    const double p = std::max(params, 1);
    const double z95 = 1.6448536;
    const double c = 2.0 / (9.0 * p);
    const double chi2 = p * std::pow(1 - c + z95 * std::sqrt(c), 3);
    return chi2 / n_eff;
}

LogFitStats evaluate(const Trace& trace, const ModelSpec& spec, InitialMode mode, float initial_ah) {
    LogFitStats s;
    s.label = trace.label;
    s.path = trace.path;
    SimResult sim;
    simulate(trace, spec, mode, initial_ah, sim);
    s.initial_ah = sim.initial_ah;
    s.fit_all = error_stats(trace, sim.model_v, Window::All);
    s.fit_flight = error_stats(trace, sim.model_v, Window::Flight);
    if (mode == InitialMode::Monitor) {
        s.monitor_all = s.fit_all;
        s.monitor_flight = s.fit_flight;
    } else {
        simulate(trace, spec, InitialMode::Monitor, 0.0f, sim);
        s.monitor_all = error_stats(trace, sim.model_v, Window::All);
        s.monitor_flight = error_stats(trace, sim.model_v, Window::Flight);
    }
    return s;
}

FitResult fit_model(const std::vector<Trace>& traces, const std::vector<ModelSpec>& start, const FitOptions& options) {
    Problem problem(traces, start, options);
    const LmProblem lm = problem.lm_problem();
    // No fewer samples than parameters: a one-row log had "fitted" with RMSE 0 and the start
    // values as the result.
    std::size_t samples = 0;
    for (const auto& p : problem.points()) samples += p.size();
    if (lm.n_params > 0 && samples <= static_cast<std::size_t>(lm.n_params))
        throw TooLittleData(traces.size() == 1 ? traces[0].path : std::string(),
                            std::to_string(samples) + (samples == 1 ? " sample" : " samples") + " to fit " +
                                std::to_string(lm.n_params) + " parameters: too few",
                            "a longer log, or " + options.fewer_parameters_advice);
    const Eigen::VectorXd x0 = problem.start_vector();
    if (options.starts < 1) throw std::invalid_argument("starts must be at least 1");
    std::vector<Eigen::VectorXd> xs{x0};
    // Nothing to fit (an evaluation): one start; the others would be the same run.
    const int starts = lm.n_params > 0 ? options.starts : 1;
    for (Eigen::VectorXd& x : problem.spread_starts(x0, starts - 1)) xs.push_back(std::move(x));
    // The linear start belongs to start 0: both begin from the config's values. Second in
    // the list, so that it loses a tie to start 0 and wins one against the spread points.
    Eigen::VectorXd x_linear;
    const bool linear = options.linear_start && problem.linear_base_start(x0, x_linear);
    if (linear) xs.insert(xs.begin() + 1, x_linear);
    const auto rmse_of = [&](const LmResult& r) { return objective_stats(r.residuals, problem.points(), problem.weights()).rmse_v; };
    MultiStartResult ms = multi_start(lm, xs, options.lm, options.jobs, rmse_of);
    if (linear) {
        if (ms.runs[1].cost < ms.runs[0].cost) ms.runs[0] = ms.runs[1];
        ms.runs.erase(ms.runs.begin() + 1);
        if (ms.best > 0) --ms.best;
    }
    const std::vector<StartSummary>& runs = ms.runs;
    const size_t best = ms.best;
    const LmResult& res = ms.best_run;
    const Eigen::MatrixXd cov = covariance(res);

    FitResult out;
    out.iterations = res.iterations;
    out.evaluations = res.evaluations;
    out.stop_reason = res.stop_reason;
    out.best_start = static_cast<int>(best);

    const ObjectiveStats stats = objective_stats(res.residuals, problem.points(), problem.weights());
    out.points = stats.n;
    out.rmse_v = stats.rmse_v;
    out.mae_v = stats.mae_v;
    out.residual_lag1 = stats.lag1;
    const double rho = std::clamp(out.residual_lag1, 0.0, 0.999);
    const double inflation = std::sqrt((1 + rho) / (1 - rho));

    const std::vector<Slot>& slots = problem.slots();
    for (size_t j = 0; j < slots.size(); ++j) {
        ParamEstimate e;
        e.name = slots[j].def.name;
        e.log = slots[j].log >= 0 ? traces[slots[j].log].label : "";
        e.unit = slots[j].def.unit;
        e.value = res.x[j];
        e.start = x0[j];
        const double var = cov(j, j);
        e.at_bound = res.at_bound[j];
        e.sigma = e.at_bound ? std::numeric_limits<double>::quiet_NaN() : std::sqrt(var);
        e.sigma_ar1 = e.sigma * inflation;
        out.params.push_back(e);
    }
    if (runs.size() > 1) {
        out.near_best_cost = near_best_cost(lm.n_params, stats.n, stats.lag1);
        for (size_t k = 0; k < runs.size(); ++k) {
            StartOutcome o;
            o.index = static_cast<int>(k);
            o.rmse_v = runs[k].score;
            o.cost_ratio = res.cost > 0 ? runs[k].cost / res.cost : (runs[k].cost > 0 ? std::numeric_limits<double>::infinity() : 1.0);
            o.iterations = runs[k].iterations;
            o.stop_reason = runs[k].stop_reason;
            out.starts.push_back(o);
            if (!(runs[k].cost <= res.cost * (1 + out.near_best_cost))) continue;
            ++out.near_best;
            const Eigen::VectorXd x = problem.rc_branches_like(runs[k].x, res.x);
            for (size_t j = 0; j < slots.size(); ++j) {
                ParamEstimate& e = out.params[j];
                const double v = slots[j].def.kind == Kind::Q ? problem.reported_capacity(x, j) : x[j];
                e.near_best_min = std::isnan(e.near_best_min) ? v : std::min(e.near_best_min, v);
                e.near_best_max = std::isnan(e.near_best_max) ? v : std::max(e.near_best_max, v);
            }
        }
    }
    // Delta method for the derived quantities, per log when the base is per-log.
    bool per_log_base = false;
    for (const Slot& s : slots) {
        if (s.log >= 0 && is_base(s.def.kind)) per_log_base = true;
    }
    if (problem.base_free()) {
        static const char* names[] = {"k", "full_voltage_v", "exponential_voltage_v", "exponential_capacity_ah", "curve_current_a"};
        static const char* units[] = {"V/Ah", "V", "V", "Ah", "A"};
        const size_t logs = per_log_base ? traces.size() : 1;
        for (size_t t = 0; t < logs; ++t) {
            const std::vector<double> d0 = problem.derived(res.x, static_cast<int>(t));
            Eigen::MatrixXd G = Eigen::MatrixXd::Zero(d0.size(), slots.size());
            for (size_t j = 0; j < slots.size(); ++j) {
                if (!is_base(slots[j].def.kind) || (slots[j].log >= 0 && slots[j].log != static_cast<int>(t))) continue;
                const double h = 1e-6 * std::max(std::fabs(res.x[j]), slots[j].def.typical);
                Eigen::VectorXd xp = res.x, xm = res.x;
                xp[j] += h;
                xm[j] -= h;
                const std::vector<double> dp = problem.derived(xp, static_cast<int>(t));
                const std::vector<double> dm = problem.derived(xm, static_cast<int>(t));
                for (size_t i = 0; i < d0.size(); ++i) G(i, j) = (dp[i] - dm[i]) / (2 * h);
            }
            for (size_t i = 0; i < d0.size(); ++i) {
                double var = 0;
                bool infinite = false;
                for (size_t a = 0; a < slots.size(); ++a) {
                    for (size_t b = 0; b < slots.size(); ++b) {
                        if (G(i, a) == 0 || G(i, b) == 0) continue;
                        if (!std::isfinite(cov(a, b))) infinite = true;
                        else var += G(i, a) * cov(a, b) * G(i, b);
                    }
                }
                ParamEstimate e;
                e.name = names[i];
                e.unit = units[i];
                e.log = per_log_base ? traces[t].label : "";
                e.value = d0[i];
                e.sigma = infinite ? std::numeric_limits<double>::infinity() : std::sqrt(std::max(var, 0.0));
                e.sigma_ar1 = e.sigma * inflation;
                out.derived.push_back(e);
            }
        }
    }
    for (size_t t = 0; t < traces.size(); ++t) {
        float q0 = 0;
        out.specs.push_back(problem.spec_for(res.x, static_cast<int>(t), &q0));
        LogFitStats s = evaluate(traces[t], out.specs.back(), options.initial, q0);
        // The fitted charge itself (the counter's float round trip differs in the last bits).
        out.initial_ah.push_back(options.initial == InitialMode::Free ? q0 : s.initial_ah);
        out.logs.push_back(s);
    }
    // A capacity held up by the charge the logs show was drawn is reported as that floor.
    for (size_t j = 0; j < slots.size(); ++j) {
        if (slots[j].def.kind != Kind::Q) continue;
        const double effective = problem.reported_capacity(res.x, j);
        if (effective != out.params[j].value) {
            out.params[j].value = effective;
            out.params[j].at_bound = true;
            out.params[j].sigma = out.params[j].sigma_ar1 = std::numeric_limits<double>::quiet_NaN();
        }
    }
    return out;
}

const char* to_string(InitialMode m) {
    switch (m) {
        case InitialMode::Free: return "free";
        case InitialMode::Monitor: return "monitor";
        case InitialMode::Zero: return "zero";
    }
    return "free";
}

InitialMode parse_initial_mode(const std::string& s) {
    if (s == "free") return InitialMode::Free;
    if (s == "monitor") return InitialMode::Monitor;
    if (s == "zero") return InitialMode::Zero;
    throw std::invalid_argument("unknown initial mode \"" + s + "\"; expected free, monitor or zero");
}

const char* to_string(Window w) { return w == Window::All ? "all" : "flight"; }

Window parse_window(const std::string& s) {
    if (s == "all") return Window::All;
    if (s == "flight") return Window::Flight;
    throw std::invalid_argument("unknown window \"" + s + "\"; expected all or flight");
}

namespace {
nlohmann::json number_or_null(double v, int digits = 6) {
    return std::isfinite(v) ? nlohmann::json(round_sig(v, digits)) : nlohmann::json(nullptr);
}
nlohmann::json estimate_json(const ParamEstimate& e) {
    nlohmann::json j = {{"name", e.name}, {"unit", e.unit}, {"value", number_or_null(e.value, 7)},
                        {"sigma", number_or_null(e.sigma, 3)}, {"sigma_ar1", number_or_null(e.sigma_ar1, 3)}};
    if (!e.log.empty()) j["log"] = e.log;
    if (e.at_bound) j["at_bound"] = true;
    if (std::isfinite(e.near_best_min)) j["near_best_range"] = {number_or_null(e.near_best_min, 7), number_or_null(e.near_best_max, 7)};
    return j;
}
}  // namespace

nlohmann::json error_stats_to_json(const ErrorStats& s) {
    // No samples (a lab log has no flight): no error, rather than an error of 0 V.
    const auto v = [&s](double x) { return s.n > 0 ? nlohmann::json(round_sig(x, 5)) : nlohmann::json(nullptr); };
    return {{"n", s.n}, {"mean_v", v(s.mean_v)}, {"mae_v", v(s.mae_v)}, {"rmse_v", v(s.rmse_v)}, {"max_abs_v", v(s.max_abs_v)}};
}

nlohmann::json fit_result_to_json(const FitResult& r, const FitOptions& o) {
    nlohmann::json j;
    j["schema"] = "battsim.fit";
    j["schema_version"] = 1;
    j["options"] = {{"params", o.params}, {"per_log_params", o.per_log_params}, {"initial", to_string(o.initial)},
                    {"window", to_string(o.window)}, {"max_points_per_log", o.max_points_per_log},
                    {"equal_log_weights", o.equal_log_weights}, {"linear_start", o.linear_start},
                    {"max_capacity_factor", o.max_capacity_factor}, {"prior_noise_v", o.prior_noise_v},
                    {"starts", o.starts}};
    nlohmann::json priors = nlohmann::json::array();
    for (const FitOptions::Prior& p : o.priors) priors.push_back({{"name", p.name}, {"mean", p.mean}, {"sigma", p.sigma}});
    j["options"]["priors"] = priors;
    j["rmse_v"] = round_sig(r.rmse_v, 5);
    j["mae_v"] = round_sig(r.mae_v, 5);
    j["points"] = r.points;
    j["residual_lag1_autocorrelation"] = round_sig(r.residual_lag1, 4);
    j["solver"] = {{"iterations", r.iterations}, {"evaluations", r.evaluations}, {"stop", r.stop_reason}};
    if (!r.starts.empty()) {
        nlohmann::json starts = nlohmann::json::array();
        for (const StartOutcome& o : r.starts)
            starts.push_back({{"start", o.index}, {"rmse_v", round_sig(o.rmse_v, 5)}, {"cost_ratio", number_or_null(o.cost_ratio, 5)},
                              {"iterations", o.iterations}, {"stop", o.stop_reason}});
        j["solver"]["best_start"] = r.best_start;
        j["solver"]["near_best"] = r.near_best;
        j["solver"]["near_best_cost"] = round_sig(r.near_best_cost, 4);
        j["solver"]["starts"] = starts;
    }
    nlohmann::json params = nlohmann::json::array();
    for (const ParamEstimate& e : r.params) params.push_back(estimate_json(e));
    j["parameters"] = params;
    nlohmann::json derived = nlohmann::json::array();
    for (const ParamEstimate& e : r.derived) derived.push_back(estimate_json(e));
    j["derived"] = derived;
    nlohmann::json logs = nlohmann::json::array();
    for (const LogFitStats& s : r.logs) {
        logs.push_back({{"label", s.label}, {"path", s.path}, {"initial_ah", round_sig(s.initial_ah, 6)},
                        {"fit", {{"all", error_stats_to_json(s.fit_all)}, {"flight", error_stats_to_json(s.fit_flight)}}},
                        {"monitor", {{"all", error_stats_to_json(s.monitor_all)}, {"flight", error_stats_to_json(s.monitor_flight)}}}});
    }
    j["logs"] = logs;
    return j;
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
