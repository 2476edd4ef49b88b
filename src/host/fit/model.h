// The model as the fit sees it: base Tremblay parameters, the core extensions and the
// monitor's current-filter reaction time; its conversion to and from the config; and the
// simulation of the monitor's model voltage along a trace.
#pragma once
#include <vector>

#include "core/model/extensions/extended_model.h"
#include "host/config_json.h"
#include "host/fit/trace.h"

namespace battsim {
namespace host {
namespace fit {

struct ModelSpec {
    core::TremblayParams battery;
    core::ModelExtensions ext;
    float reaction_time_s = 30.0f;  // time constant of the filtered current i*
};

ModelSpec spec_from_config(const LoadedConfig& c);
// Writes the battery parameters, the extensions and the reaction time into `c`.
void spec_to_config(const ModelSpec& s, LoadedConfig& c);

// The Tremblay model's own parameters V = E0 − R·i − K·Q/(Q−it)·(i* + it) + A·e^(−B·it),
// with K written as kappa·K_max: the config's curve-point encoding can only express
// K ≤ K_max = A·e^−3·(Q − Q_exp)/(Q·Q_exp) (curve current ≥ 0), and then
// curve_current = Q_exp·(1/kappa − 1).
struct NaturalParams {
    double e0_v = 0, r_ohm = 0, kappa = 0, a_v = 0, b_per_ah = 0, q_ah = 0;
};
NaturalParams natural_from_params(const core::TremblayParams& p);
// The config's parameters for `n`; the nominal-zone point keeps `keep`'s capacity fraction
// and takes the model's voltage there. The curve current is limited so that the full and
// exponential voltages stay at or above 0.1 V (what the config accepts).
core::TremblayParams params_from_natural(const NaturalParams& n, const core::TremblayParams& keep);
double k_of(const NaturalParams& n);

enum class InitialMode {
    Free,     // charge drawn at the monitor's settle sample is given (a fit parameter)
    Monitor,  // as the monitor does it: the model inverted at the settle sample's voltage
    Zero,     // the log starts full: count from its first sample
};

struct SimResult {
    std::vector<float> model_v;  // NaN where the monitor has no model voltage
    float initial_ah = 0;        // charge drawn at the settle sample
    // Filled only with keep_states:
    std::vector<float> used_ah, filtered_a, temperature_c, rc_total_v;
};

// Runs the monitor's current filter, coulomb counter and the (extended) model along the
// trace exactly as core::Monitor does for the fixed model: without extensions and with
// InitialMode::Monitor the result equals the monitor's model_voltage_v bit for bit.
void simulate(const Trace& trace, const ModelSpec& spec, InitialMode mode, float initial_ah, SimResult& out,
              bool keep_states = false);

// Error statistics of measured − model over the selected points.
struct ErrorStats {
    size_t n = 0;
    double mean_v = 0, mae_v = 0, rmse_v = 0, max_abs_v = 0;
};
enum class Window { All, Flight };
// Points used: valid, with a model value, and inside the window (and mask, when given,
// nonzero).
ErrorStats error_stats(const Trace& trace, const std::vector<float>& model_v, Window window,
                       const std::vector<uint8_t>* mask = nullptr);
// The first sample with a model voltage: the monitor's settle sample, or with
// InitialMode::Zero the first valid sample; −1 if none.
long first_model_index(const Trace& trace, InitialMode mode);
// Sample k has a model voltage in this mode and lies inside the window.
bool in_window(const Trace& trace, size_t k, Window w, InitialMode mode);

}  // namespace fit
}  // namespace host
}  // namespace battsim
