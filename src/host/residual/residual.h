// Residual tracing (`battsim residual`): what does the model miss, and does adding it help on
// data the fit did not see?
//
// The logs' window samples are cut into contiguous blocks; odd blocks are held out, the others
// (and always the last) are fitted: interleaved rather than first/last part, so neither an
// effect tied to the state of charge nor the capacity is asked to extrapolate to charge the fit
// never saw. Starting from the config as
// given, the base parameters are refitted; then every candidate effect is added in turn,
// refitted on the fit blocks and scored on the held-out blocks: the share of the held-out
// mean square error it removes (gain) and a one-sided Wilcoxon signed-rank test over the
// held-out blocks' mean square errors (does it help consistently, not in one block only?). The best significant candidate joins the model and the
// search repeats. Finally the chosen model is refitted on all samples. A candidate that does
// not pass on held-out data is reported but never added.
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/config_json.h"
#include "host/fit/fit.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {
namespace residual {

struct ResidualOptions {
    fit::Window window = fit::Window::All;
    // Free: the initial charge is fitted per log (flights); Zero: the logs start full
    // (constant-current discharges from a charged cell). The config row uses the monitor's
    // own estimate with Free.
    fit::InitialMode initial = fit::InitialMode::Free;
    int blocks = 20;          // per log; odd ones (but the last) held out
    double min_gain = 0.02;   // least share of the held-out mean square error an effect must remove
    double max_p = 0.05;      // Wilcoxon signed-rank test over held-out blocks
    int max_effects = 4;
    std::vector<std::string> candidates;  // empty = all that apply
    int max_iterations = 100;
    int starts = 1;  // starting points per refit (fit::FitOptions::starts)
    int jobs = 1;    // threads for a step's candidates and the other refits' starts; the result does not depend on it
    size_t max_points_per_log = 20000;
    double max_capacity_factor = 1.5;  // of the config's capacity (see fit::FitOptions)
    double max_capacity_ah = 0;        // set by analyse() from the factor
    double bounds_full_voltage_v = 0;  // 0: analyse() takes the spec's; the job, the config's max_voltage_v
    double bounds_capacity_ah = 0;
    std::vector<std::string> fixed;  // parameters never fitted (e.g. q measured by a slow discharge)
};

// Candidate names, in the order they are tried.
std::vector<std::string> candidate_names();

struct CandidateScore {
    std::string name;
    std::string description;
    bool applicable = true;
    std::string note;  // why not applicable
    double fit_rmse_v = 0, heldout_rmse_v = 0;
    double gain = 0;     // 1 − held-out MSE with the effect / without
    double p_value = 1;  // one-sided Wilcoxon signed-rank test over the held-out blocks
    int blocks_better = 0, blocks = 0;
    // Lag-1 autocorrelation of the held-out blocks' improvements, over neighbouring pairs
    // within a log: the test above assumes it is near 0.
    double block_lag1_r = 0;
    int block_pairs = 0;
    bool significant = false;
    std::vector<std::pair<std::string, double>> values;  // the effect's fitted parameters
};

struct StageStats {
    fit::ErrorStats all, fit, heldout;
};

struct Stage {
    std::string name;  // "config", "parameters" or the effect added
    std::string description;
    StageStats stats;
    double gain = 0, p_value = 1;  // of this step on the held-out blocks
    double block_lag1_r = 0;       // of the effect added (CandidateScore)
    int block_pairs = 0;
    std::vector<CandidateScore> candidates;  // scored at this stage (the next step chose from these)
    fit::ModelSpec spec;  // of the first log
};

struct Structure {
    size_t n = 0;
    double mean_v = 0, sd_v = 0, skewness = 0, excess_kurtosis = 0;
    std::vector<std::pair<double, double>> quantiles;      // (probability, value)
    std::vector<int> lags;                                 // in samples
    std::vector<double> lag_s;                             // the same in seconds (median dt)
    std::vector<double> acf;
    double white_band = 0;                                 // ±1.96/√n
    std::vector<double> histogram_edges_v;                 // bins + 1
    std::vector<size_t> histogram_counts;
};

struct ResidualReport {
    std::vector<std::string> logs;
    std::vector<Stage> stages;
    std::vector<std::string> effects;  // added, in order
    std::vector<fit::ModelSpec> final_specs;  // refitted on all samples (one per log; equal)
    std::vector<float> final_initial_ah;
    std::vector<fit::LogFitStats> before, after;  // per log: the config and the final model
    bool monitor_polished = false;
    fit::InitialMode initial = fit::InitialMode::Free;  // the final model was refitted with the monitor's initial charge
    Structure structure_before, structure_after;
    std::string verdict;
};

// `progress`, if given, is told each refit and each candidate tried.
ResidualReport analyse(const std::vector<fit::Trace>& traces, const fit::ModelSpec& spec, const ResidualOptions& options,
                       std::ostream* progress = nullptr);
Structure residual_structure(const std::vector<fit::Trace>& traces, const std::vector<std::vector<float>>& model_v,
                             fit::Window window, fit::InitialMode mode);

nlohmann::json report_to_json(const ResidualReport& r, const ResidualOptions& o);
void print_report(const ResidualReport& r, std::ostream& out);
// Voltage and residual before/after for each log (the first 4), the residual's autocorrelation
// and histogram over all. Returns how many logs have no panels of their own.
size_t plot_residual(const std::vector<fit::Trace>& traces, const ResidualReport& r, const fit::ModelSpec& config_spec,
                     const std::string& path);

// `battsim residual` as one call: load the logs, analyse, write the config with the effects
// found (when asked) and the plot. Returns the report JSON; `out` (optional) gets the report.
struct ResidualJob {
    std::vector<std::string> logs;
    ReaderOptions reader;
    LoadedConfig config;
    ResidualOptions options;
    std::string output_config;  // the final model written into the config
    std::string name;
    std::string plot_path;
};
nlohmann::json run_residual_job(const ResidualJob& job, ResidualReport* out = nullptr, std::ostream* progress = nullptr);

}  // namespace residual
}  // namespace host
}  // namespace battsim
