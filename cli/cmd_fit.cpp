// battsim fit LOG...: least-squares fit of the model parameters along discharges and flights.
#include <filesystem>
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/fit/fit_job.h"

namespace battsim {
namespace cli {
namespace {

struct FitArgs {
    std::vector<std::string> logs, tests, add, params, per_log;
    std::string output, output_dir, name;
    std::string initial = "free";
    std::string window = "all";
    size_t max_points = 20000;
    int max_iterations = 100;
    StartArgs starts;
    bool sample_weights = false;
    ModelJobArgs common;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<FitArgs>();
    sub.add_option("LOG", a->logs, "Logs to fit: constant-current discharges and/or flights")->required();
    sub.add_option("-o,--output", a->output, "Write the fitted config JSON here");
    sub.add_option("--output-dir", a->output_dir, "Write one fitted config per log into this directory (needed with --per-log)");
    sub.add_option("--name", a->name, "Name of the fitted config");
    sub.add_option("--test", a->tests, "Logs to evaluate the fitted model on (not fitted)");
    sub.add_option("--add", a->add,
                   "Enable an extension before fitting: rc[:TAU_S], temperature[:REF_C], thermal[:AMBIENT_C], "
                   "hysteresis, ocv[:N], sensor, timing (repeatable; residual's names, such as rc_polarisation or self_heating, also)");
    add_list_option(sub, "--params", a->params,
                    "Parameters to fit (default: e0,r,kappa,a,b,q and those of the enabled extensions; none = no model parameter: only the initial charge with --initial free, nothing with monitor or zero)");
    add_list_option(sub, "--per-log", a->per_log, "Parameters fitted separately for each log (e.g. r,q)");
    sub.add_option("--initial", a->initial, "Initial charge at the monitor's settle sample: free (fitted per log), monitor (model inversion), zero (log starts full)")
        ->capture_default_str();
    sub.add_option("--window", a->window, "Samples in the objective: all (initialised) or flight (the summary's flight window)")
        ->capture_default_str();
    sub.add_option("--max-points", a->max_points, "At most this many samples per log in the objective (thinned evenly)")
        ->check(CLI::Range(static_cast<size_t>(20), static_cast<size_t>(100000000)))
        ->capture_default_str();
    sub.add_option("--max-iterations", a->max_iterations, "Levenberg-Marquardt iteration limit")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    add_start_options(sub, a->starts, "the fit", "Starts fitted");
    sub.add_flag("--sample-weights", a->sample_weights, "Weight logs by their sample count instead of equally");
    add_model_job_options(sub, a->common, "fit report", "Plot measured and model voltage per log (.png or .svg)");
    return [a]() -> int {
        const char* me = "battsim fit";
        host::fit::FitJob job;
        if (int rc = resolve_input(a->common.input, job.reader, job.config, me)) return rc;
        if (int rc = check_plot_option(me, a->common.plot)) return rc;
        // Before any log is read (these had come after reading them all).
        if (!a->per_log.empty() && !a->output.empty()) {
            std::cerr << me << ": with per-log parameters there is one config per log: use --output-dir, not -o\n";
            return kExitUsage;
        }
        if (!a->per_log.empty() && !a->tests.empty()) {
            std::cerr << me << ": with per-log parameters there is no single model to test on other logs\n";
            return kExitUsage;
        }
        job.logs = a->logs;
        job.options.max_capacity_factor = a->common.max_capacity_factor;
        job.test_logs = a->tests;
        job.add = a->add;
        job.output_config = a->output;
        job.output_dir = a->output_dir;
        job.name = a->name;
        job.plot_path = a->common.plot;
        std::vector<host::NamedPath> inputs{{"-c/--config", a->common.input.config, true}};
        add_named(inputs, "a log", a->logs);
        add_named(inputs, "a --test log", a->tests);
        std::vector<host::NamedPath> outputs{printed_output("--json", a->common.json),
                                             text_output("-o/--output", a->output, true),
                                             text_output("--report", a->common.report),
                                             {"--plot", a->common.plot},
                                             {"--output-dir", a->output_dir, false, host::Dash::Refused, true}};
        // One config per log: none may land on a log or the config read (a log's stem is its
        // name there), nor two logs of one stem on one file.
        if (!a->output_dir.empty()) {
            for (const std::string& log : a->logs) {
                const std::string path = host::fit::per_log_config_path(job, log);
                outputs.push_back({"--output-dir's " + std::filesystem::path(path).filename().string() + " (for " + log + ")", path});
            }
        }
        if (int rc = check_outputs(me, inputs, outputs)) return rc;
        if (int rc = check_logs_once(me, std::vector<host::NamedPath>(inputs.begin() + 1, inputs.end()))) return rc;
        job.options.params = a->params;
        job.options.per_log_params = a->per_log;
        job.options.max_points_per_log = a->max_points;
        job.options.lm.max_iterations = a->max_iterations;
        job.options.starts = a->starts.starts;
        job.options.jobs = a->starts.threads();
        job.options.equal_log_weights = !a->sample_weights;
        nlohmann::json report;
        const int rc = run_job(me, [&] {
            job.options.initial = host::fit::parse_initial_mode(a->initial);
            job.options.window = host::fit::parse_window(a->window);
            report = host::fit::run_fit_job(job, &std::cerr);
        });
        if (rc != kExitOk) return rc;
        return finish_report(me, report, a->common.report, a->common.json,
                             [&](std::ostream& out) { host::fit::print_fit_brief(report, out); }, people_out(outputs));
    };
}

const RegisterCommand reg{{"fit", "Fit the model parameters to discharges and flights (least squares)", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
