// battsim replay LOG: one log through the core monitor; series CSV and summary JSON.
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/io/atomic_file.h"
#include "host/plot/plot.h"
#include "host/replay.h"

namespace battsim {
namespace cli {
namespace {

struct ReplayArgs {
    std::string log;
    std::string series;
    std::string summary;
    std::string plot;
    bool json = false;
    double realtime = 0;
    bool realtime_flag = false;
    InputArgs input;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<ReplayArgs>();
    sub.add_option("LOG", a->log, "Log file to replay")->required();
    sub.add_option("--series", a->series, "Write the per-sample series CSV here");
    sub.add_option("--summary", a->summary, "Write the summary JSON here");
    sub.add_option("--plot", a->plot,
                   "Plot measured and model voltage, capacity and resistance estimates, flight time and cell "
                   "voltages (.png or .svg)");
    sub.add_flag("--json", a->json, "Print the summary JSON on standard output");
    sub.add_flag("--realtime", a->realtime_flag, "Pace the replay to wall-clock time (the monitor still uses the log's time stamps)");
    sub.add_option("--speed", a->realtime, "With --realtime: speed-up factor (default 1)");
    add_input_options(sub, a->input);
    return [a]() -> int {
        host::ReplayOptions opt;
        if (int rc = resolve_input(a->input, opt.reader, opt.config)) return rc;
        if (int rc = check_plot_option("battsim replay", a->plot)) return rc;
        opt.series_path = a->series;
        if (a->realtime_flag) opt.realtime_speed = a->realtime > 0 ? a->realtime : 1.0;
        nlohmann::json summary;
        host::plot::ReplaySeries plotted;
        host::SampleObserver observer;
        if (!a->plot.empty()) {
            observer = [&plotted](const core::Sample& s, const core::MonitorStatus& st) { plotted.add(s, st); };
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
        for (const auto& note : summary["input"]["notes"]) std::cerr << "battsim replay: note: " << note.get<std::string>() << "\n";
        const std::string text = summary.dump(2) + "\n";
        try {
            if (!a->summary.empty()) host::write_file_atomic(a->summary, text);
            if (!a->plot.empty()) {
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
        if (!a->json && a->summary.empty() && a->series.empty() && a->plot.empty()) print_brief(summary, std::cout);
        return kExitOk;
    };
}

const RegisterCommand reg{{"replay", "Replay a log through the monitor at its own timing", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
