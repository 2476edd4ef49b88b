// battsim score [SCENARIO|DIR...]: fly the scenario suite, run every estimator column
// over each log, print the scoreboard (text or --json).
#include <algorithm>
#include <iostream>
#include <memory>
#include <thread>

#include "command.h"
#include "common_options.h"
#include "host/io/atomic_file.h"
#include "host/io/sample_reader.h"
#include "host/score/scoreboard.h"
#include "host/sim/scenario.h"

namespace battsim {
namespace cli {
namespace {

struct ScoreArgs {
    std::vector<std::string> paths;
    bool json = false;
    std::string output;
    int jobs = 0;
    std::string logs_dir;
    std::string columns;
    int copies = 1;
    std::string log_format;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<ScoreArgs>();
    sub.add_option("SCENARIOS", a->paths, "Scenario files or directories (default: configs/scenarios)");
    sub.add_flag("--json", a->json, "Print the scoreboard as JSON (with per-flight detail)");
    sub.add_option("-o,--output", a->output, "Write the table (or JSON) to this file instead of standard output");
    sub.add_option("-j,--jobs", a->jobs, "Flights scored in parallel (default or 0: the machine's cores); the output does not depend on it")
        ->check(CLI::Range(0, 1024));
    sub.add_option("--logs", a->logs_dir,
                   "Read each flight's log from DIR/NAME.csv (.bin, .ulg for those formats; written by `battsim simulate "
                   "--out-dir` from the scenarios as they are now: another seed's log is refused) instead of simulating it in memory");
    sub.add_option("--copies", a->copies,
                   "Fly the suite this many times: as written, then with other seeds (gusts, cell spreads, sensor "
                   "noise; copy k adds 7919 k to each seed); figures pool every copy, with the copies' range beside them")
        ->check(CLI::Range(1, 100));
    sub.add_option("--log-format", a->log_format,
                   "Fly every scenario with this log format instead of its own, as `battsim simulate --format`: " +
                       host::sim::sim_log_format_help())
        ->check(CLI::IsMember(host::sim::sim_log_format_names()));
    sub.add_option("--columns", a->columns, "Estimator columns to run, comma-separated (default: all but the diagnostic solve-truth)");
    return [a]() -> int {
        std::vector<std::string> paths = a->paths;
        if (paths.empty()) paths.push_back("configs/scenarios");
        std::vector<host::sim::Scenario> scenarios;
        try {
            for (const std::string& f : host::sim::find_scenario_files(paths)) scenarios.push_back(host::sim::load_scenario(f));
        } catch (const host::sim::ScenarioError& e) {
            std::cerr << "battsim score: " << e.what() << "\n";
            return kExitConfigError;
        }
        // The format first: it names the --logs files' extension.
        const std::string format_problem = host::sim::override_log_format(scenarios, a->log_format);
        if (!format_problem.empty()) {
            std::cerr << "battsim score: --log-format: " << format_problem << "\n";
            return kExitUsage;
        }
        std::vector<host::NamedPath> inputs;
        for (const host::sim::Scenario& s : scenarios) {
            inputs.push_back({"a scenario", s.source_path});
            // The monitor config it names is read too (-o over it had replaced it with the table).
            inputs.push_back({"the monitor config of " + s.name, s.monitor_config_path});
            const std::string log = s.name + host::sim::sim_log_extension(host::sim::log_format_of(s));
            if (!a->logs_dir.empty()) inputs.push_back({"--logs' " + log, a->logs_dir + "/" + log});
        }
        if (int rc = check_outputs("battsim score", inputs, {text_output("-o/--output", a->output)})) return rc;
        {
            std::vector<host::NamedPath> files;
            for (const host::sim::Scenario& s : scenarios) files.push_back({"a scenario", s.source_path});
            if (int rc = check_logs_once("battsim score", files)) return rc;
        }
        std::vector<host::score::EstimatorColumn> columns;
        try {
            columns = host::score::select_columns(a->columns);
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim score: --columns: " << e.what() << "\n";
            return kExitUsage;
        }
        host::score::ScoreOptions opt;
        opt.jobs = a->jobs > 0 ? a->jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
        opt.logs_dir = a->logs_dir;
        opt.copies = a->copies;
        host::score::ScoreResult result;
        try {
            result = host::score::score_scenarios(scenarios, columns, opt);
        } catch (const host::sim::ScenarioError& e) {
            std::cerr << "battsim score: " << e.what() << "\n";
            return kExitConfigError;
        } catch (const host::InputError& e) {
            std::cerr << "battsim score: " << e.what() << "\n";
            return kExitInputError;
        } catch (const std::invalid_argument& e) {  // options the library refuses (--copies with --logs)
            std::cerr << "battsim score: " << e.what() << "\n";
            return kExitUsage;
        }
        for (const auto& f : result.flights)
            for (const std::string& n : f.notes) std::cerr << "battsim score: note: " << f.name << ": " << n << "\n";
        const std::string text = a->json ? host::json_text(host::score::to_json(result), 2) + "\n" : host::score::format_table(result);
        if (a->output.empty()) {
            std::cout << text;
            return kExitOk;
        }
        try {
            host::write_file_atomic(a->output, text);
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim score: " << e.what() << "\n";
            return kExitOutputError;
        }
        return kExitOk;
    };
}

const RegisterCommand reg{{"score", "Score the estimators on simulated flights with known truth", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
