// `battsim fit` as one library call: load the logs, enable the requested extensions, fit,
// evaluate on held-out logs, write the fitted config(s), the report and the plot.
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
namespace fit {

// Enables one extension in `spec` with neutral starting values. `what` is one of
//   rc[:TAU_S]         another RC branch (default time constants 2, 20, 200 s by branch)
//   temperature[:REF_C] temperature dependence around REF_C (default 25)
//   thermal[:AMBIENT_C] lumped thermal state (default ambient 25 °C)
//   hysteresis         hysteresis with a small starting magnitude
//   ocv[:N]            OCV correction with N points (default 8) over the capacity
//   sensor             current-sensor gain and offset
//   timing             current-to-voltage timing skew
// and returns the parameter names it makes fittable. Throws std::invalid_argument.
std::vector<std::string> enable_extension(ModelSpec& spec, const std::string& what);

struct FitJob {
    std::vector<std::string> logs;
    std::vector<std::string> test_logs;  // evaluated with the fitted model, not fitted
    ReaderOptions reader;
    LoadedConfig config;              // start values and everything not fitted
    std::vector<std::string> add;       // enable_extension() arguments
    FitOptions options;                 // params empty = default_parameters()
    std::string output_config;          // fitted config (shared parameters only)
    std::string output_dir;             // one config per log (required with per-log parameters)
    std::string name;                   // config name; default derived from the logs
    std::string plot_path;              // measured vs model per log, .png or .svg
};

// Where `job.output_dir` takes the config fitted to `log`: DIR/<name, else "fitted">-<log's
// label>.json. The CLI checks these against the inputs before the fit.
std::string per_log_config_path(const FitJob& job, const std::string& log);

// Runs the job; returns the report (schema battsim.fit). Throws InputError (logs),
// std::invalid_argument (options) and std::runtime_error (outputs).
nlohmann::json run_fit_job(const FitJob& job, std::ostream* progress = nullptr);

// A few human-readable lines about a fit report.
void print_fit_brief(const nlohmann::json& report, std::ostream& out);

}  // namespace fit
}  // namespace host
}  // namespace battsim
