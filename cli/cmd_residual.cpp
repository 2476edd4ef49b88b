// battsim residual LOG... --config CFG: trace what the model misses, effect by effect.
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/residual/residual.h"

namespace battsim {
namespace cli {
namespace {

struct ResidualArgs {
    std::vector<std::string> logs, candidates, fixed;
    std::string output, name;
    std::string window = "all";
    std::string initial = "free";
    int blocks = 20, max_effects = 4, max_iterations = 100;
    double min_gain = 0.02, max_p = 0.05;
    StartArgs starts;
    ModelJobArgs common;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<ResidualArgs>();
    sub.add_option("LOG", a->logs, "Logs to analyse (one model for all of them)")->required();
    sub.add_option("-o,--output", a->output, "Write the config with the effects found, refitted, here");
    sub.add_option("--name", a->name, "Name of the written config");
    add_list_option(sub, "--candidates", a->candidates,
                   "Effects to try (default all): rc_polarisation, temperature, self_heating, soc_shape, current_sensor, "
                   "hysteresis, sample_timing (fit --add's rc, thermal, ocv, sensor, timing also)");
    add_list_option(sub, "--fixed", a->fixed, "Parameters kept at the config's values (e.g. q when a slow discharge measured it)");
    sub.add_option("--window", a->window, "Samples analysed: all (initialised) or flight")->capture_default_str();
    sub.add_option("--initial", a->initial, "Initial charge: free (fitted per log; flights) or zero (logs start full: constant-current discharges)")
        ->check(CLI::IsMember({"free", "zero"}))
        ->capture_default_str();
    sub.add_option("--blocks", a->blocks, "Blocks per log; odd ones (but the last) are held out, the others fitted")->check(CLI::Range(4, 1000))->capture_default_str();
    sub.add_option("--max-effects", a->max_effects, "Most effects added")->check(CLI::Range(0, 20))->capture_default_str();
    sub.add_option("--min-gain", a->min_gain, "Least share of the held-out error variance an effect must remove")->check(number_in(0.0, 1.0))->capture_default_str();
    sub.add_option("--max-p", a->max_p, "Significance level of the Wilcoxon signed-rank test over the held-out blocks")->check(number_in(0.0, 1.0, true))->capture_default_str();
    sub.add_option("--max-iterations", a->max_iterations, "Levenberg-Marquardt iterations per refit")->check(CLI::Range(1, 100000))->capture_default_str();
    add_start_options(sub, a->starts, "every refit", "Candidate effects, and the starts of the refits between them, fitted");
    add_model_job_options(sub, a->common, "report", "Plot voltage, residual before/after, autocorrelation, histogram (.png or .svg)");
    return [a]() -> int {
        const char* me = "battsim residual";
        host::residual::ResidualJob job;
        if (int rc = resolve_input(a->common.input, job.reader, job.config, me)) return rc;
        std::vector<host::NamedPath> inputs{{"-c/--config", a->common.input.config, true}};
        add_named(inputs, "a log", a->logs);
        const std::vector<host::NamedPath> outputs{printed_output("--json", a->common.json),
                                                   text_output("-o/--output", a->output, true),
                                                   text_output("--report", a->common.report),
                                                   {"--plot", a->common.plot}};
        if (int rc = check_outputs(me, inputs, outputs)) return rc;
        if (int rc = check_plot_option(me, a->common.plot)) return rc;
        if (int rc = check_logs_once(me, std::vector<host::NamedPath>(inputs.begin() + 1, inputs.end()))) return rc;
        job.logs = a->logs;
        job.options.max_capacity_factor = a->common.max_capacity_factor;
        job.output_config = a->output;
        job.name = a->name;
        job.plot_path = a->common.plot;
        job.options.candidates = a->candidates;
        job.options.fixed = a->fixed;
        job.options.blocks = a->blocks;
        job.options.max_effects = a->max_effects;
        job.options.min_gain = a->min_gain;
        job.options.max_p = a->max_p;
        job.options.max_iterations = a->max_iterations;
        job.options.starts = a->starts.starts;
        job.options.jobs = a->starts.threads();
        host::residual::ResidualReport report;
        nlohmann::json j;
        const int rc = run_job(me, [&] {
            job.options.window = host::fit::parse_window(a->window);
            job.options.initial = host::fit::parse_initial_mode(a->initial);
            j = host::residual::run_residual_job(job, &report, &std::cerr);
        });
        if (rc != kExitOk) return rc;
        return finish_report(me, j, a->common.report, a->common.json,
                             [&](std::ostream& out) {
                                 host::residual::print_report(report, out);
                                 if (j.contains("plot_note")) out << "plot: " << j["plot_note"].get<std::string>() << "\n";
                             },
                             people_out(outputs));
    };
}

const RegisterCommand reg{{"residual", "Trace the model's residual to effects, add them, refit (held-out checked)", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
