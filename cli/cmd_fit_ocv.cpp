// battsim fit-ocv LOG... -c CFG [-o OUT.json]: the joint estimator's OCV table stitched from
// a fleet's ordinary flights (each starting at its own state of charge), for packs nobody
// discharged slowly on a bench.
#include <iomanip>
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/batch/batch.h"
#include "host/fit/ocv_stitch.h"
#include "host/plot/plot.h"

namespace battsim {
namespace cli {
namespace {

struct FitOcvArgs {
    std::vector<std::string> logs, test_logs;
    std::string manifest;
    unsigned test_every = 0;
    std::string output, report, plot;
    bool json = false;
    host::fit::OcvStitchOptions options;
    InputArgs input;
};

void print_brief(const host::fit::OcvStitch& s, std::ostream& os) {
    size_t fitted = 0, tested = 0;
    for (const auto& f : s.flights) (f.test ? tested : fitted) += 1;
    os << std::fixed << "battsim fit-ocv: " << fitted << " flight(s) fitted" << (tested ? ", " + std::to_string(tested) + " tested" : "")
       << "; SOC span " << std::setprecision(2) << s.soc_min << " .. " << s.soc_max << " of " << std::setprecision(3)
       << s.capacity_ah << " Ah; " << s.iterations << " iterations; polarisation low-passes " << std::setprecision(1) << s.fast_time_s << " s and "
       << s.slow_time_s << " s\n";
    os << "  SOC    config V   fitted V   samples\n";
    const size_t n = s.table_v.size();
    for (size_t j = n; j-- > 0;) {
        os << "  " << std::setprecision(2) << std::setw(4) << static_cast<double>(j) / static_cast<double>(n - 1) << "  "
           << std::setprecision(4) << std::setw(8) << s.prior_v[j] << "  " << std::setw(9) << s.table_v[j] << "  "
           << std::setprecision(0) << std::setw(8) << s.support[j] << "\n";
    }
    os << std::setprecision(4) << "  pack resistance (flights' median ohmic / fast / slow), config curve: " << s.resistance_before_ohm << " / "
       << s.fast_before_ohm << " / " << s.slow_before_ohm << " ohm; fitted: " << s.resistance_ohm << " / " << s.fast_ohm
       << " / " << s.slow_ohm << " ohm\n";
    os << std::setprecision(1) << "  rms error per cell: config curve " << 1000.0 * s.rms_before_v << " mV, fitted "
       << 1000.0 * s.rms_v << " mV";
    if (tested)
        os << "; test flights " << 1000.0 * s.test_rms_before_v << " mV -> " << 1000.0 * s.test_rms_v << " mV";
    os << "\n";
}

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<FitOcvArgs>();
    sub.add_option("LOG", a->logs, "Flight logs of one pack model (starting at different states of charge)");
    sub.add_option("--test", a->test_logs, "Logs evaluated with the fitted table, not fitted");
    sub.add_option("-m,--manifest", a->manifest,
                   "A fleet manifest (as for battsim batch): its logs, each read with its own settings; LOGs given "
                   "too take the settings of the entry naming the same file");
    sub.add_option("--test-every", a->test_every, "Hold out every Kth log, from the 2nd on (the 2nd, (K+2)th, (2K+2)th, ...), as a test log")
        ->check(CLI::Range(2u, 1000000u));
    sub.add_option("-o,--output", a->output, "Write the config with the fitted table here (JSON)");
    sub.add_option("--report", a->report, "Write the fit report here (JSON, schema battsim.ocv_stitch)");
    sub.add_flag("--json", a->json, "Print the report on standard output");
    sub.add_option("--plot", a->plot, "Draw the table, the config's curve and each flight's voltage with the sag added back (.png or .svg)");
    sub.add_option("--points,--ocv-points", a->options.points, "Table points from empty to full")->check(CLI::Range(2, 21))->capture_default_str();
    // The sigmas from 1 µV, below any measurement: at 1e-300 V the fit's weights overflowed to a
    // singular system reported as "the logs hold too little current".
    sub.add_option("--prior-sigma", a->options.prior_sigma_v,
                   "Per cell, V: how far the table may leave the config's curve where no flight reaches")
        ->check(number_in(1.0e-6, 1.0e6))
        ->capture_default_str();
    sub.add_option("--smooth-sigma", a->options.smooth_sigma_v, "Per cell, V: second difference of that distance")
        ->check(number_in(1.0e-6, 1.0e6))
        ->capture_default_str();
    sub.add_option("--fast-time", a->options.fast_time_s, "Seconds: the fast polarisation's low-pass of the current")
        ->check(number_in(0.0, 1.0e6, true))
        ->capture_default_str();
    sub.add_option("--slow-time", a->options.slow_time_s, "Seconds: the slow polarisation's low-pass of the current (0: the best fit of 20, 30, 45, 60, 90)")
        ->check(number_in(0.0, 1.0e6))
        ->capture_default_str();
    sub.add_option("--empty-sigma", a->options.empty_sigma_v,
                   "Per cell, V: how far the empty point (SOC 0) may leave the config's (its minimum voltage)")
        ->check(number_in(1.0e-6, 1.0e6))
        ->capture_default_str();
    sub.add_option("--rest-weight", a->options.rest_weight, "Weight of a sample at rest (|I| < 1 A) against one in flight")
        ->check(number_in(0.0, 1.0e6, true))
        ->capture_default_str();
    sub.add_option("--iterations,--max-iterations", a->options.iterations, "Most rounds of the joint Levenberg-Marquardt step (20 alternating rounds come first)")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    sub.add_flag("!--ignore-table", a->options.prior_from_table,
                 "Start from the config's model curve even when it has a table (to check a table against the flights)");
    sub.add_flag("!--no-fullest-is-full", a->options.fullest_is_full,
                 "Do not take the fullest flight's start as a full pack (only the config's curve then pins the axis)");
    add_input_options(sub, a->input);
    return [a]() -> int {
        const char* const command = "battsim fit-ocv";
        if (int rc = check_plot_option(command, a->plot)) return rc;
        host::ReaderOptions reader;
        host::LoadedConfig config;
        if (a->logs.empty() && a->manifest.empty()) {
            std::cerr << command << ": expected logs or --manifest FILE\n";
            return kExitUsage;
        }
        if (int rc = resolve_input(a->input, reader, config, command)) return rc;
        std::vector<host::fit::OcvStitchLog> logs;
        std::vector<host::BatchItem> items;  // from the manifest
        if (a->manifest.empty()) {
            for (const std::string& p : a->logs) logs.push_back({p, reader, false});
        } else {
            // The manifest's reading settings per log; the command line's config (else the
            // manifest's default one, loaded by the plan) is the one pack model fitted.
            host::BatchPlanRequest plan;
            plan.paths = a->logs;
            plan.manifest = a->manifest;
            if (int rc = run_job(command, [&] {
                    plan.command_line = host::settings_from_strings(setting_strings(a->input));
                    items = host::plan_batch(plan);
                }))
                return rc;
            for (const host::BatchItem& it : items) {
                if (!it.error.empty()) {
                    std::cerr << command << ": " << it.path << ": " << it.error << "\n";
                    return kExitInputError;
                }
                logs.push_back({it.path, it.replay.reader, false});
            }
            if (a->input.config.empty() && !items.empty()) config = items.front().replay.config;
        }
        // After the plan, which names the manifest's logs.
        std::vector<host::NamedPath> inputs{{"-c/--config", a->input.config, true}, {"-m/--manifest", a->manifest}};
        for (const host::fit::OcvStitchLog& l : logs) inputs.push_back({"a log", l.path});
        add_named(inputs, "a --test log", a->test_logs);
        // The configs the manifest names are inputs too; only the one fitted (the first
        // log's, when -c is not given) may be written back over (with -c, that one had been
        // too, and a config of the fleet's replaced by another's table).
        for (size_t k = 0; k < items.size(); ++k)
            inputs.push_back({"the config of " + items[k].path, items[k].config_path, k == 0 && a->input.config.empty()});
        const std::vector<host::NamedPath> outputs{printed_output("--json", a->json),
                                                   text_output("-o/--output", a->output, true),
                                                   text_output("--report", a->report),
                                                   {"--plot", a->plot}};
        if (int rc = check_outputs(command, inputs, outputs)) return rc;
        // A held-out log that is also fitted tests nothing: its "test" error was the fit's own.
        for (const std::string& t : a->test_logs)
            for (const host::fit::OcvStitchLog& l : logs)
                if (host::same_output_file(t, l.path)) {
                    std::cerr << command << ": " << t << " is both fitted and held out (--test): give it once\n";
                    return kExitUsage;
                }
        {
            std::vector<host::NamedPath> all_logs;
            for (const host::fit::OcvStitchLog& l : logs) all_logs.push_back({"a log", l.path});
            add_named(all_logs, "a --test log", a->test_logs);
            if (int rc = check_logs_once(command, all_logs)) return rc;
        }
        host::fit::hold_out_every(logs, a->test_every);
        for (const std::string& p : a->test_logs) logs.push_back({p, reader, true});
        host::fit::OcvStitch s;
        if (int rc = run_job(command, [&] { s = host::fit::stitch_ocv(logs, config, a->options, &std::cerr); })) return rc;
        if (!a->output.empty()) {
            host::LoadedConfig out = host::fit::with_stitched_table(config, s);
            size_t fitted = 0;
            for (const host::fit::OcvStitchFlight& f : s.flights) fitted += !f.test;
            if (int rc = write_tuned_config(out, a->output, command, "joint OCV table fitted by battsim fit-ocv on ",
                                            std::to_string(fitted) + " flight(s)"))
                return rc;
        }
        if (!a->plot.empty())
            if (int rc = run_job(command, [&] { host::plot::plot_ocv_stitch(s, "battsim fit-ocv", a->plot); })) return rc;
        return finish_report(command, host::fit::to_json(s), a->report, a->json, [&](std::ostream& os) { print_brief(s, os); },
                             people_out(outputs));
    };
}

const RegisterCommand reg{{"fit-ocv", "Fit the joint estimator's OCV table to a fleet's flights", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
