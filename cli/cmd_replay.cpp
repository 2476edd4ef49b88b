// battsim replay LOG: one log through the core monitor; series CSV and summary JSON; with
// --charged-mah, the current sensor checked against the charger's count; with --mavlink/--tlog, what the
// monitor's telemetry UART sends.
#include <cmath>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "command.h"
#include "common_options.h"
#include "host/io/atomic_file.h"
#include "host/config_json.h"
#include "host/plot/plot.h"
#include "host/replay.h"
#include "host/report/brief.h"
#include "host/report/charger_check.h"
#include "host/report/config_out.h"
#include "host/report/telemetry_writer.h"

namespace battsim {
namespace cli {
namespace {

struct ReplayArgs {
    std::string log;
    std::string series;
    std::string summary;
    std::string plot;
    std::string mavlink;
    std::string tlog;
    bool json = false;
    bool said = false;
    double realtime = 0;
    bool realtime_flag = false;
    double charged_mah = 0;
    double charger_tolerance = 0.03;
    std::string config_out;
    InputArgs input;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<ReplayArgs>();
    sub.add_option("LOG", a->log, "Log file to replay")->required();
    sub.add_option("--series", a->series, "Write the per-sample series CSV here (\"-\" = standard output)");
    sub.add_option("--summary", a->summary, "Write the summary JSON here (\"-\" = standard output)");
    sub.add_option("--plot", a->plot,
                   "Plot measured and model voltage, capacity and resistance estimates, flight time and cell "
                   "voltages (.png or .svg)");
    sub.add_option("--mavlink", a->mavlink,
                   "Write the MAVLink stream the monitor's telemetry UART sends for this log (raw bytes; "
                   "docs/telemetry.md)");
    sub.add_option("--tlog", a->tlog, "Write that stream as a .tlog, which ground stations open to replay");
    sub.add_flag("--json", a->json, "Print the summary JSON on standard output");
    sub.add_flag("--said", a->said,
                 "List what a ground station would show and speak for this log: the monitor's MAVLink texts "
                 "(warnings, and verdicts withdrawn) with their times (summary `said`)");
    auto* realtime = sub.add_flag("--realtime", a->realtime_flag, "Pace the replay to wall-clock time (the monitor still uses the log's time stamps)");
    sub.add_option("--speed", a->realtime, "With --realtime: speed-up factor (default 1)")->check(number_in(1.0e-3, 1.0e6))->needs(realtime);
    auto* charged = sub.add_option("--charged-mah", a->charged_mah,
                                   "What the charger put back after this log (the pack charged full before it): "
                                   "checks the current sensor against it (summary `charger_check`)")
                        ->check(number_in(1.0, 1.0e7));  // refused before the replay, not after it; under 1 mAh is no charge
    sub.add_option("--charger-tolerance", a->charger_tolerance,
                   "With --charged-mah: a count off by more than this fraction is a sensor fault (default 0.03)")
        ->check(number_in(0.0, 1.0, true))
        ->needs(charged);
    sub.add_option("--config-out", a->config_out,
                   "Write the config with the current-sensor corrections this replay found here: the gain "
                   "--charged-mah suggests (battery.extensions.current_sensor.gain), the offset learnt on the ground "
                   "when it was a sensor fault (battery.extensions.current_sensor.offset_a); none found: exit 1, nothing written");
    add_input_options(sub, a->input);
    return [a, charged]() -> int {
        host::ReplayOptions opt;
        if (int rc = resolve_input(a->input, opt.reader, opt.config, "battsim replay")) return rc;
        if (int rc = check_plot_option("battsim replay", a->plot)) return rc;
        // The texts may go to standard output ("-"), one of them; the MAVLink stream, the
        // tlog and the plot are binary (or drawn by gnuplot) and need a file.
        const std::vector<host::NamedPath> outputs{printed_output("--json", a->json),
                                                   text_output("--series", a->series),
                                                   text_output("--summary", a->summary),
                                                   {"--plot", a->plot},
                                                   {"--mavlink", a->mavlink},
                                                   {"--tlog", a->tlog},
                                                   text_output("--config-out", a->config_out, true)};
        if (int rc = check_outputs("battsim replay", {{"the log", a->log}, {"-c/--config", a->input.config, true}}, outputs))
            return rc;
        std::ostream& people = people_out(outputs);
        opt.series_path = a->series;
        if (a->realtime_flag) opt.realtime_speed = a->realtime > 0 ? a->realtime : 1.0;
        nlohmann::json summary;
        host::plot::ReplaySeries plotted;
        host::SampleObserver observer;
        std::unique_ptr<host::TelemetryWriter> stream;
        try {
            if (!a->mavlink.empty() || !a->tlog.empty() || a->said)
                stream = std::make_unique<host::TelemetryWriter>(a->mavlink, a->tlog, opt.config.telemetry, opt.config.monitor);
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim replay: " << e.what() << "\n";
            return kExitOutputError;
        }
        if (!a->plot.empty() || stream) {
            const bool plot = !a->plot.empty();
            observer = [&plotted, &stream, plot](const core::Sample& s, const core::MonitorStatus& st) {
                if (plot) plotted.add(s, st);
                if (stream) stream->add(s, st);
            };
        }
        try {
            summary = host::replay_log(a->log, opt, observer);
        } catch (const host::InputError& e) {
            std::cerr << "battsim replay: " << e.what() << "\n";
            return kExitInputError;
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim replay: " << e.what() << "\n";
            return kExitOutputError;
        }
        if (a->said) {
            const nlohmann::json& flight = summary["flight"];
            const double start_s = flight.is_object() && flight["start_s"].is_number() ? flight["start_s"].get<double>() : NAN;
            summary["said"] = host::said_json(stream->said(), start_s);
        }
        for (const auto& note : summary["input"]["notes"]) std::cerr << "battsim replay: note: " << note.get<std::string>() << "\n";
        for (const auto& note : summary.value("config_notes", nlohmann::json::array()))
            std::cerr << "battsim replay: note: " << note.get<std::string>() << "\n";
        // The config --config-out writes is the file's, not this run's --estimator.
        host::LoadedConfig filed;
        try {
            filed = host::filed_config(opt.config, a->input.config, !a->input.estimator.empty());
        } catch (const host::ConfigError& e) {  // changed since it was read at the start
            std::cerr << "battsim replay: config: " << e.what() << "\n";
            return kExitConfigError;
        }
        // Nothing valid to report (a config for another pack kept every sample out): the outputs
        // are written all the same, to show it, but the run fails (exit 1), as batch's row does.
        const std::string no_valid = host::no_valid_samples_text(summary);
        // Given at all (a zero or negative count is refused below, not taken as "none"); without a
        // valid sample there is no charge to check (it had exited 2, as for a bad count).
        const bool check = charged->count() > 0 && no_valid.empty();
        if (check) {
            try {
                host::add_charger_check(summary, a->charged_mah, a->charger_tolerance, opt.config.monitor);
            } catch (const std::invalid_argument& e) {
                std::cerr << "battsim replay: --charged-mah: " << e.what() << "\n";
                return kExitUsage;
            }
            for (const auto& note : summary["charger_check"]["notes"])
                std::cerr << "battsim replay: charger check: " << note.get<std::string>() << "\n";
        }
        const host::ConfigCorrections corrected = host::with_corrections(filed, summary);
        const bool refuse_config = !a->config_out.empty() && !corrected.found();
        const std::string text = host::json_text(summary, 2) + "\n";
        try {
            if (!a->summary.empty()) host::write_file_atomic(a->summary, text);
            if (stream) stream->commit();
            if (!a->config_out.empty() && !refuse_config)
                host::write_file_atomic(a->config_out, host::json_text(host::config_to_json(corrected.config), 2) + "\n");
            if (!a->plot.empty() && no_valid.empty()) {  // no sample to draw
                const std::string title = "battsim replay: " + a->log + " (config " + summary["config"].get<std::string>() +
                                          ", " + summary["estimator"].get<std::string>() + " estimator)";
                host::plot::plot_replay(plotted, title, a->plot);
            }
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim replay: " << e.what() << "\n";  // e.g. no valid sample to draw
            return kExitInputError;
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim replay: " << e.what() << "\n";
            return kExitOutputError;
        }
        if (a->json) std::cout << text;
        if (!a->json && a->summary.empty() && a->series.empty() && a->plot.empty() && a->mavlink.empty() && a->tlog.empty())
            host::print_brief(summary, people);
        if (!a->json && a->said) host::print_said(summary["said"], summary["flight"], people);
        if (!a->json && summary.contains("charger_check")) host::print_charger_check(summary["charger_check"], people);
        if (!no_valid.empty())
            std::cerr << "battsim replay: no valid samples: " << no_valid
                      << (a->plot.empty() ? "" : "; --plot not drawn")
                      << (charged->count() > 0 ? "; --charged-mah not checked" : "") << " (exit 1)\n";
        if (refuse_config) {
            std::cerr << "battsim replay: --config-out: no correction found ("
                      << (check                  ? "the charger check suggests no gain, see its notes; "
                          : charged->count() > 0 ? "no charger check without a valid sample; "
                                                 : "no --charged-mah; ")
                      << "no current-sensor offset learnt as a sensor fault); " << a->config_out << " not written\n";
            return kExitFailure;
        }
        if (!a->config_out.empty() && corrected.offset_taken_a != 0.0)
            std::cerr << "battsim replay: --config-out: extensions.current_sensor.offset_a "
                      << corrected.config.monitor.extensions.current_sensor.offset_a << " A (the " << corrected.offset_taken_a
                      << " A offset learnt on the ground taken out) in " << a->config_out << "\n";
        return no_valid.empty() ? kExitOk : kExitFailure;
    };
}

const RegisterCommand reg{{"replay", "Replay a log through the monitor at its own timing", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
