// battsim simulate SCENARIO...: fly scenarios through the truth plant and the sensor
// layer; write each log (in a format the readers take) and its truth JSON.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "command.h"
#include "common_options.h"
#include "host/io/number_text.h"
#include "host/sim/simulate.h"

namespace battsim {
namespace cli {
namespace {

struct SimulateArgs {
    std::vector<std::string> scenarios;
    std::string output;
    std::string truth;
    std::string out_dir;
    std::string format;
    std::string seed;  // empty: the scenario's own
    double cutoff = NAN;  // NaN = not given (0 had passed as "not given" unseen)
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<SimulateArgs>();
    sub.add_option("SCENARIO", a->scenarios, "Scenario JSON files, or directories of them")->required();
    sub.add_option("-o,--output", a->output, "Log file to write (one scenario only)");
    sub.add_option("--truth", a->truth, "Truth JSON to write (default: the log's name with .truth.json)");
    sub.add_option("--out-dir", a->out_dir,
                   "Write NAME.csv (NAME.bin for dataflash, NAME.ulg for ulog) and NAME.truth.json here for every scenario");
    sub.add_option("--seed", a->seed, "Override the scenario's seed");
    sub.add_option("--format", a->format,
                   "Override the log format: " + host::sim::sim_log_format_help());
    // Checked as typed: "nan" had read as the option not given (NaN is its unset value).
    sub.add_option("--cutoff-v-per-cell", a->cutoff, "Override the truth's loaded cutoff voltage per cell (default: the monitor config's min_flight_voltage_v per cell)")
        ->check(number_in(2.0, 4.5));
    return [a]() -> int {
        if (a->output.empty() == a->out_dir.empty()) {
            std::cerr << "battsim simulate: give exactly one of -o/--output (one scenario) or --out-dir\n";
            return kExitUsage;
        }
        if (!a->truth.empty() && a->output.empty()) {
            std::cerr << "battsim simulate: --truth goes with -o/--output\n";
            return kExitUsage;
        }
        std::vector<std::string> files;
        std::vector<host::sim::Scenario> scenarios;
        try {
            files = host::sim::find_scenario_files(a->scenarios);
            for (const std::string& f : files) scenarios.push_back(host::sim::load_scenario(f));
        } catch (const host::sim::ScenarioError& e) {
            std::cerr << "battsim simulate: " << e.what() << "\n";
            return kExitConfigError;
        }
        // A seed is any whole number a scenario's "seed" takes; a negative one or one past
        // 64 bits had silently meant the scenario's own, or the largest.
        uint64_t seed = 0;
        if (!a->seed.empty()) {
            if (!host::parse_whole_number(a->seed, &seed)) {
                std::cerr << "battsim simulate: --seed: expected a whole number from 0 to 18446744073709551615, found " << a->seed
                          << "\n";
                return kExitUsage;
            }
        }
        if (!a->output.empty() && scenarios.size() != 1) {
            std::cerr << "battsim simulate: -o/--output takes one scenario, " << scenarios.size()
                      << " given; use --out-dir\n";
            return kExitUsage;
        }
        // The format first: it names the --out-dir logs' extension.
        const std::string format_problem = host::sim::override_log_format(scenarios, a->format);
        if (!format_problem.empty()) {
            std::cerr << "battsim simulate: --format: " << format_problem << "\n";
            return kExitUsage;
        }
        // Where each scenario's log and truth go, checked against the scenarios and each other
        // before any is flown (two scenarios of one name in --out-dir, say).
        std::vector<std::pair<std::string, std::string>> targets;
        std::vector<host::NamedPath> inputs, outputs{{"--out-dir", a->out_dir, false, host::Dash::Refused, true}};
        add_named(inputs, "a scenario", files);
        // The monitor config each names is read too: -o or --truth over it had replaced it.
        for (const host::sim::Scenario& s : scenarios) inputs.push_back({"the monitor config of " + s.name, s.monitor_config_path});
        for (const host::sim::Scenario& s : scenarios) {
            if (!a->out_dir.empty()) {
                targets.emplace_back(a->out_dir + "/" + s.name + host::sim::sim_log_extension(host::sim::log_format_of(s)),
                                     a->out_dir + "/" + s.name + ".truth.json");
                outputs.push_back({"the log of " + s.name, targets.back().first});
                outputs.push_back({"the truth of " + s.name, targets.back().second});
            } else {
                targets.emplace_back(a->output, a->truth.empty() ? host::sim::default_truth_path(a->output) : a->truth);
                outputs.push_back({"-o/--output", targets.back().first});
                outputs.push_back({a->truth.empty() ? "the truth (-o's name with .truth.json)" : "--truth", targets.back().second});
            }
        }
        if (int rc = check_outputs("battsim simulate", inputs, outputs)) return rc;
        // As batch --out does: a directory that is not there yet is made.
        if (!a->out_dir.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(a->out_dir, ec);
            if (ec) {
                std::cerr << "battsim simulate: " << a->out_dir << ": cannot create the directory (" << ec.message() << ")\n";
                return kExitOutputError;
            }
        }
        for (size_t k = 0; k < scenarios.size(); ++k) {
            host::sim::Scenario& s = scenarios[k];
            if (!a->seed.empty()) s.seed = seed;
            if (!std::isnan(a->cutoff)) s.cutoff_v_per_cell = a->cutoff;
            host::sim::SimulationResult r;
            try {
                r = host::sim::simulate(s);
            } catch (const host::sim::ScenarioError& e) {
                std::cerr << "battsim simulate: " << e.what() << "\n";
                return kExitConfigError;
            }
            const std::string& log = targets[k].first;
            const std::string& truth = targets[k].second;
            try {
                host::sim::write_simulation(r, log, truth);
            } catch (const std::runtime_error& e) {
                std::cerr << "battsim simulate: " << e.what() << "\n";
                return kExitOutputError;
            }
            const host::sim::Truth& t = r.truth;
            if (t.sensor_stats.current_clipped > 0)
                std::cerr << "battsim simulate: note: " << s.name << ": the current sensor clipped " << t.sensor_stats.current_clipped
                          << " of " << t.sensor_stats.reads << " reads at its +-81.92 mV shunt range: the log's current is wrong there "
                          << "(the truth's current_clipped_reads)\n";
            const std::string ground = host::sim::ground_draw_note(r);
            if (!ground.empty()) std::cerr << "battsim simulate: note: " << ground << "\n";
            for (const std::string& n : {host::sim::flight_draw_note(r), host::sim::empty_cell_note(r),
                                         host::sim::log_interval_note(s)})
                if (!n.empty()) std::cerr << "battsim simulate: note: " << s.name << ": " << n << "\n";
            std::cout << s.name << ": " << t.rows << " rows -> " << log << "; flight " << t.landing_s - t.takeoff_s
                      << " s of " << t.total_flight_time_s << " s to cutoff (healthy pack " << t.healthy_total_flight_time_s
                      << " s)" << (t.landed_by_cutoff ? ", cut short by the cutoff" : "") << "\n";
        }
        return kExitOk;
    };
}

const RegisterCommand reg{{"simulate", "Simulate flights with a truth plant and the reference sensors; write logs and truth", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
