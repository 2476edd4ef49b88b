#include "common_options.h"

#include <algorithm>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <stdexcept>
#include <thread>

#include "command.h"
#include "host/batch/inputs.h"
#include "host/batch/manifest.h"
#include "host/config_reader.h"
#include "host/io/atomic_file.h"
#include "host/io/sample_reader.h"
#include "host/io/number_text.h"
#include "host/plot/plot.h"
#include "host/replay.h"
#include "host/report/summary.h"

namespace battsim {
namespace cli {

CLI::Validator number_in(double lo, double hi, bool above_lo) {
    const auto figure = [](double v) {
        std::ostringstream o;
        o << v;
        return o.str();
    };
    const std::string range = (above_lo ? "(" : "[") + figure(lo) + ", " + figure(hi) + "]";
    return CLI::Validator(
        [=](std::string& text) -> std::string {
            double v = 0.0;
            const bool ok = host::parse_finite_number(text, &v) && (above_lo ? v > lo : v >= lo) && v <= hi;
            return ok ? std::string() : "expected a number in " + range + ", found " + text;
        },
        "NUMBER in " + range);
}

namespace {
std::vector<std::string> split_list(const std::string& text) {
    std::vector<std::string> items;
    size_t from = 0;
    while (true) {
        const size_t comma = text.find(',', from);
        std::string item = text.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
        const size_t first = item.find_first_not_of(" \t");
        item = first == std::string::npos ? std::string() : item.substr(first, item.find_last_not_of(" \t") - first + 1);
        items.push_back(item);
        if (comma == std::string::npos) return items;
        from = comma + 1;
    }
}
}  // namespace

CLI::Option* add_list_option(CLI::App& sub, const std::string& flags, std::vector<std::string>& items,
                             const std::string& help, const std::function<std::string(const std::string&)>& check_item) {
    CLI::Option* o = sub.add_option_function<std::vector<std::string>>(
        flags,
        [&items](const std::vector<std::string>& values) {
            items.clear();
            for (const std::string& v : values)
                for (std::string& item : split_list(v)) items.push_back(std::move(item));
        },
        help);
    o->type_size(1)->allow_extra_args(false);
    o->check(CLI::Validator(
        [check_item](std::string& v) -> std::string {
            if (v.empty()) return std::string();  // main's empty-value check says so
            for (const std::string& item : split_list(v)) {
                if (item.empty()) return "expected a comma-separated list, found an empty item in \"" + v + "\"";
                if (check_item) {
                    const std::string why = check_item(item);
                    if (!why.empty()) return why;
                }
            }
            return std::string();
        },
        "LIST"));
    return o;
}

void add_input_options(CLI::App& sub, InputArgs& a) {
    sub.add_option("-c,--config", a.config, "Battery and monitor config JSON (default: built in, the same as configs/reference-modified.json: the dissertation's 1.55 Ah 4S pack and logger)");
    sub.add_option("--format", a.format, host::log_format_help())
        ->capture_default_str();
    sub.add_option("--current-source", a.current_source, "Raw logs: current from 'current' (logged mA) or 'shunt' (shunt mV through the config's calibration)")
        ->capture_default_str();
    sub.add_option("--time-col", a.time_col, "CSV: name of the time column");
    sub.add_option("--time-unit", a.time_unit, "CSV: unit of the time column (s, ms, us); overrides the unit its name implies (time_ms)");
    sub.add_option("--voltage-col", a.voltage_col, "CSV: name of the pack voltage column (V)");
    sub.add_option("--current-col", a.current_col, "CSV: name of the current column");
    sub.add_option("--current-unit", a.current_unit, "CSV: unit of the current column (A, mA); overrides the unit its name implies (current_ma)");
    add_list_option(sub, "--cell-cols", a.cell_cols, "CSV: names of the cell voltage columns, cell 1 first, comma-separated");
    sub.add_option("--temperature-col", a.temperature_col, "CSV: name of the temperature column (degC)");
    sub.add_option("--estimator", a.estimator, "Estimator: reference (the dissertation's) or joint (the newer one); default from the config");
    sub.add_flag("--negative-discharge", a.negative_discharge, "CSV: the log's current is negative while discharging");
    sub.add_flag("--no-temperature", a.no_temperature,
                 "Leave the log's temperature out (any format): for a config whose temperature terms its self-heating "
                 "state drives (battery.extensions.thermal), fitted on logs without one");
    sub.add_option("--average-ms", a.average_ms,
                   "Average the samples over windows this long (ms) before the monitor sees them: for logs sampled "
                   "faster than the joint estimator's resistance lags reach (blackbox logs)")
        // Checked as given: 0 stands for "not given" inside, and must not pass silently as that.
        ->check(CLI::Validator(
            [](std::string& text) -> std::string {
                double ms = 0.0;
                if (!host::parse_finite_number(text, &ms)) return "expected a number of milliseconds, found " + text;
                try {
                    host::average_window_ms(ms);
                } catch (const std::invalid_argument& e) {
                    return e.what();
                }
                return std::string();
            },
            "MS"));
}

int StartArgs::threads() const { return jobs > 0 ? jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

void add_start_options(CLI::App& sub, StartArgs& a, const std::string& each_fit, const std::string& parallel) {
    sub.add_option("--starts", a.starts,
                   "Starting points of " + each_fit + ": 1 = the config's values; more adds seeded points spread around them, keeps "
                   "the best fit and reports how far the fits the logs cannot tell from it put each parameter")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    sub.add_option("-j,--jobs", a.jobs, parallel + " in parallel (default or 0: the machine's cores); the result does not depend on it")
        ->check(CLI::Range(0, 1024));
}

void add_model_job_options(CLI::App& sub, ModelJobArgs& a, const std::string& report, const std::string& plot_help) {
    sub.add_option("--max-capacity-factor", a.max_capacity_factor,
                   "The fitted capacity stays at or below this x the config's (and above the charge drawn)")
        ->check(number_in(1.0, 100.0))
        ->capture_default_str();
    sub.add_option("--report", a.report, "Write the " + report + " JSON here");
    sub.add_option("--plot", a.plot, plot_help);
    sub.add_flag("--json", a.json, "Print the " + report + " JSON on standard output");
    add_input_options(sub, a.input);
}

int resolve_input(const InputArgs& a, host::ReaderOptions& reader, host::LoadedConfig& config, const std::string& command) {
    // Read by the same code as batch's command line and a manifest's fields, so that each
    // option accepts and means the same everywhere (each quantity only its own units: a
    // shared table had read "--current-unit us" as 1e-6 A).
    host::LogSettings settings;
    try {
        settings = host::settings_from_strings(setting_strings(a));
    } catch (const std::invalid_argument& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitUsage;
    }
    reader = settings.reader_options(reader);
    try {
        config = a.config.empty() ? host::builtin_config() : host::load_config_file(a.config);
    } catch (const host::ConfigError& e) {
        std::cerr << command << ": config: " << e.what() << "\n";
        return kExitConfigError;
    }
    if (settings.estimator) config.monitor.estimator = *settings.estimator;
    return kExitOk;
}

host::LogSettingStrings setting_strings(const InputArgs& a) {
    host::LogSettingStrings s;
    s.config = a.config;
    s.format = a.format;
    s.current_source = a.current_source;
    s.time_col = a.time_col;
    s.time_unit = a.time_unit;
    s.voltage_col = a.voltage_col;
    s.current_col = a.current_col;
    s.current_unit = a.current_unit;
    s.temperature_col = a.temperature_col;
    s.cell_cols = a.cell_cols;
    s.negative_discharge = a.negative_discharge;
    s.no_temperature = a.no_temperature;
    s.average_ms = a.average_ms;
    s.estimator = a.estimator;
    return s;
}

int run_job(const std::string& command, const std::function<void()>& job) {
    try {
        job();
    } catch (const host::ConfigError& e) {  // a config a manifest names, say
        std::cerr << command << ": config: " << e.what() << "\n";
        return kExitConfigError;
    } catch (const host::InputError& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitInputError;
    } catch (const std::invalid_argument& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitUsage;
    } catch (const std::runtime_error& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitOutputError;
    }
    return kExitOk;
}

int finish_report(const std::string& command, const nlohmann::json& report, const std::string& path, bool json,
                  const std::function<void(std::ostream&)>& brief, std::ostream& people) {
    const std::string text = host::json_text(report, 2) + "\n";
    try {
        if (!path.empty()) host::write_file_atomic(path, text);
    } catch (const std::runtime_error& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitOutputError;
    }
    if (json) {
        std::cout << text;
    } else {
        brief(people);
    }
    return kExitOk;
}

int check_plot_option(const std::string& command, const std::string& path) {
    if (path.empty()) return kExitOk;
    try {
        host::plot::check_plot_path(path);
    } catch (const std::invalid_argument& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitUsage;
    }
    if (!host::plot::gnuplot_on_path()) {
        std::cerr << command << ": --plot " << path
                  << ": gnuplot is not on PATH (Debian: apt-get install gnuplot-nox); nothing was run\n";
        return kExitOutputError;
    }
    return kExitOk;
}

int check_outputs(const std::string& command, const std::vector<host::NamedPath>& inputs,
                  const std::vector<host::NamedPath>& outputs) {
    try {
        host::check_output_paths(inputs, outputs);
    } catch (const std::invalid_argument& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitUsage;
    }
    // Said before the work: a run that fails at its last output had thrown the work away,
    // and had already replaced the outputs written before it.
    std::string what, path;
    const std::string why = host::first_unwritable_output(outputs, &what, &path);
    if (!why.empty()) {
        std::cerr << command << ": " << what << ": cannot write " << path << ": " << why << "\n";
        return kExitOutputError;
    }
    return kExitOk;
}

int check_logs_once(const std::string& command, const std::vector<host::NamedPath>& logs) {
    std::map<std::string, const host::NamedPath*> seen;
    for (const host::NamedPath& log : logs) {
        if (log.path.empty() || log.path == "-") continue;
        const auto [it, fresh] = seen.emplace(host::log_file_key(log.path), &log);
        if (fresh) continue;
        const host::NamedPath& first = *it->second;
        std::cerr << command << ": " << log.what << " \"" << log.path << "\" names the same file as " << first.what
                  << " \"" << first.path << "\"; give each once (twice, it would count twice)\n";
        return kExitUsage;
    }
    return kExitOk;
}

host::NamedPath text_output(const std::string& what, const std::string& path, bool config) {
    return {what, path, config, host::Dash::StandardOutput};
}

host::NamedPath printed_output(const std::string& flag, bool given) {
    return text_output(flag, given ? "-" : "");
}

std::ostream& people_out(const std::vector<host::NamedPath>& outputs) {
    for (const host::NamedPath& out : outputs)
        if (host::names_standard_output(out.path)) return std::cerr;
    return std::cout;
}

void add_named(std::vector<host::NamedPath>& to, const std::string& what, const std::vector<std::string>& paths) {
    for (const std::string& p : paths) to.push_back({what, p});
}

int write_tuned_config(host::LoadedConfig config, const std::string& path, const char* command, const std::string& marker,
                       const std::string& rest) {
    std::string& d = config.description;
    const size_t at = d.find(marker);
    if (at != std::string::npos) {  // the notes are joined by "; " and hold none themselves
        const size_t end = d.find("; ", at);
        const size_t from = at >= 2 && d.compare(at - 2, 2, "; ") == 0 ? at - 2 : at;
        d.erase(from, end == std::string::npos ? std::string::npos : (from == at ? end + 2 : end) - from);
    }
    d += (d.empty() ? "" : "; ") + marker + rest;
    const bool switched = config.monitor.estimator != core::EstimatorKind::Joint;
    config.monitor.estimator = core::EstimatorKind::Joint;
    if (int rc = run_job(command, [&] { host::write_file_atomic(path, host::json_text(host::config_to_json(config), 2) + "\n"); }))
        return rc;
    if (switched)
        std::cerr << command << ": note: the written config selects the joint estimator (\"estimator\": \"joint\"), "
                  << "whose settings this tunes; the config given ran the reference one\n";
    return kExitOk;
}

}  // namespace cli
}  // namespace battsim
