#include "common_options.h"

#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <stdexcept>

#include "command.h"
#include "host/batch/inputs.h"
#include "host/batch/manifest.h"
#include "host/config_reader.h"
#include "host/io/atomic_file.h"
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

void add_input_options(CLI::App& sub, InputArgs& a) {
    sub.add_option("-c,--config", a.config, "Battery and monitor config JSON (default: built in, the same as configs/reference-modified.json: the dissertation's 1.55 Ah 4S pack and logger)");
    sub.add_option("--format", a.format, "Log format: auto, raw, csv, dataflash-text, dataflash-bin, ulog")
        ->capture_default_str();
    sub.add_option("--current-source", a.current_source, "Raw logs: current from 'current' (logged mA) or 'shunt' (shunt mV through the config's calibration)")
        ->capture_default_str();
    sub.add_option("--time-col", a.time_col, "CSV: name of the time column");
    sub.add_option("--time-unit", a.time_unit, "CSV: unit of the time column (s, ms, us); overrides the unit its name implies (time_ms)");
    sub.add_option("--voltage-col", a.voltage_col, "CSV: name of the pack voltage column (V)");
    sub.add_option("--current-col", a.current_col, "CSV: name of the current column");
    sub.add_option("--current-unit", a.current_unit, "CSV: unit of the current column (A, mA); overrides the unit its name implies (current_ma)");
    sub.add_option("--cell-cols", a.cell_cols, "CSV: names of the cell voltage columns, cell 1 first")->delimiter(',');
    sub.add_option("--temperature-col", a.temperature_col, "CSV: name of the temperature column (degC)");
    sub.add_option("--estimator", a.estimator, "Estimator: reference (the dissertation's) or joint (the newer one); default from the config");
    sub.add_flag("--negative-discharge", a.negative_discharge, "CSV: the log's current is negative while discharging");
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
    try {
        if (!path.empty()) host::plot::check_plot_path(path);
    } catch (const std::invalid_argument& e) {
        std::cerr << command << ": " << e.what() << "\n";
        return kExitUsage;
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

namespace {
std::string fixed(const nlohmann::json& v, int decimals, double scale = 1.0) {
    return host::fixed_text(v, decimals, "n/a", scale);
}

// When in the flight a time since the take-off falls: in it, or after its landing (a text or
// a warning can come once the drone is down, and "157.7 s into" a 150.2 s flight misleads).
std::string when_in_flight(const nlohmann::json& flight_time_s, const nlohmann::json& duration_s) {
    const double t = flight_time_s.get<double>();
    if (duration_s.is_number() && t > duration_s.get<double>())
        return fixed(t - duration_s.get<double>(), 1) + " s after the landing";
    return fixed(flight_time_s, 1) + " s into the flight";
}

// What a warning's summary entry says beyond its name and time: when in the flight, the
// cause, the cell, what was measured, and whether it still held at the end of the log.
std::string warning_detail(const nlohmann::json& w, const nlohmann::json& duration_s) {
    std::string d;
    const auto add = [&d](const std::string& part) { d += (d.empty() ? "" : "; ") + part; };
    if (w.contains("flight_time_s"))
        add(w["flight_time_s"].is_number() ? when_in_flight(w["flight_time_s"], duration_s) : "before the take-off");
    if (w.contains("cell")) add("cell " + std::to_string(w["cell"].get<int>()));
    if (w.contains("finding")) add(w["finding"].get<std::string>());
    for (const auto& c : w.value("cause", nlohmann::json::array())) {
        const std::string cause = c.get<std::string>();
        if (cause == "sample_gap" && w.contains("sample_gaps")) {
            const auto& g = w["sample_gaps"];
            add(std::to_string(g["count"].get<uint64_t>()) + (g["count"] == 1 ? " gap" : " gaps") +
                " between samples, longest " + fixed(g["longest_s"], 2) + " s");
        } else if (cause == "current_offset" && w.contains("current_offset_a")) {
            add("current sensor offset " + fixed(w["current_offset_a"], 2) + " A");
        } else if (cause == "reading") {
            add("readings outside the sensor limits");
        } else if (cause == "cells") {
            add("cell readings outside the limits");
        } else {
            add(cause);
        }
    }
    if (!w.value("active_at_end", false)) add("cleared before the end");
    return d.empty() ? d : " (" + d + ")";
}
// A warning that went off and on again: each time it was on (a few; the count says the rest).
std::string warning_spells(const nlohmann::json& w) {
    const uint64_t count = w.value("spell_count", uint64_t{0});
    if (count < 2 || !w.contains("spells")) return "";
    constexpr size_t kShown = 4;
    std::string d = "\n      on ";
    size_t shown = 0;
    for (const auto& sp : w["spells"]) {
        if (shown == kShown) break;
        d += (shown++ ? ", " : "") + fixed(sp["from_s"], 1) + "–" +
             (sp["to_s"].is_number() ? fixed(sp["to_s"], 1) + " s" : "the end");
        std::string causes;
        for (const auto& c : sp.value("cause", nlohmann::json::array())) causes += (causes.empty() ? "" : ", ") + c.get<std::string>();
        if (!causes.empty()) d += " (" + causes + ")";
    }
    if (count > shown) d += ", and " + std::to_string(count - shown) + " more";
    return d;
}

// The flight's lines of the brief: its length, capacity, resistance, model error, and the
// remaining time at 20 %.
void print_flight_brief(const nlohmann::json& s, std::ostream& out) {
    const auto& f = s["flight"];
    const auto& cap = f["capacity_ah"];
    out << "  flight " << fixed(f["duration_s"], 1) << " s";
    // Two hops are one window, the ground between them in it; say so rather than read as one flight.
    if (f.value("take_offs", 1) > 1) out << " (" << f["take_offs"] << " take-offs: from the first to the last landing)";
    out << "; capacity ";
    const char* end = f.value("landed", true) ? "at the landing" : "at the end of the log (still flying)";
    // The joint estimator's standard error: a flight that draws little of the pack says little.
    if (cap.contains("final_sigma") && !cap["final_sigma"].is_null()) {
        out << fixed(cap["final"], 3) << " +/- " << fixed(cap["final_sigma"], 3) << " Ah " << end << " (mean "
            << fixed(cap["mean"], 3) << ", first 20 %: " << fixed(cap["first20_mean"], 3) << ")";
    } else {
        out << "mean " << fixed(cap["mean"], 3) << " Ah (first 20 %: " << fixed(cap["first20_mean"], 3) << ", " << end << " "
            << fixed(cap["final"], 3) << ")";
    }
    out << "; resistance mean " << fixed(f["resistance_ohm"]["mean"], 2, 1000.0) << " mOhm; model MAE "
        << fixed(f["voltage_error_v"]["model"]["mean_abs"], 3) << " V";
    // The joint estimator's own model (its tracking filter, one step ahead) is what it
    // compares with the measurement; the configured curve's error says how far the config is.
    if (s["estimator"] == "joint") out << " (the estimator's own: " << fixed(f["voltage_error_v"]["adapted"]["mean_abs"], 3) << " V)";
    out << "\n";
    const auto& at20 = f["remaining_time_s"]["at20"];
    out << "  remaining time 20 % into the flight: " << (at20.is_number() ? fixed(at20, 1) + " s" : "not known yet") << "\n";
    // The battery states a ground station shows (not warnings): a remaining time of 0 s beside
    // "warnings: none" had read as a contradiction.
    const auto began = [&](const char* key) -> std::string {
        const auto& t = f["remaining_time_s"].value(key, nlohmann::json());
        if (!t.is_number()) return std::string();
        // On the landing sample itself (flight 29's last solve: 64 s to 57.6 s as it landed),
        // "145.1 s into the flight" of a 145.1 s flight had read as a state flown in.
        if (f["end_s"].is_number() && t.get<double>() >= f["end_s"].get<double>())
            return fixed(t, 1) + " s (at the landing)";
        return fixed(t, 1) + " s (" + fixed(t.get<double>() - f["start_s"].get<double>(), 1) + " s into the flight)";
    };
    const std::string low = began("low_from_s"), critical = began("critical_from_s");
    if (!low.empty()) {
        out << "  battery state (telemetry.low_time_s, critical_time_s): LOW from " << low;
        if (!critical.empty()) out << ", CRITICAL from " << critical;
        out << "\n";
    }
}
}  // namespace

void print_brief(const nlohmann::json& s, std::ostream& out) {
    out << s["input"]["path"].get<std::string>() << ": " << s["samples"]["total"] << " samples, "
        << fixed(s["duration_s"], 1) << " s\n";
    // Samples the config's sensor limits kept out: a config for another pack (a 3S config on
    // a 4S log) rejects much of a flight, and the figures below would not say so.
    const std::string kept_out = host::kept_out_text(s);
    if (!kept_out.empty()) out << "  kept out by the config's sensor limits: " << kept_out << "\n";
    const auto& f = s["flight"];
    if (f.is_null() && s["samples"]["valid"] == 0) {
        out << "  no valid sample (every one kept out, above): no flight, no estimate\n";
    } else if (f.is_null()) {
        out << "  no flight (the current never stayed above the flying threshold long enough for a take-off)\n";
    } else {
        print_flight_brief(s, out);
    }
    // Warnings on the ground count too (a sample gap or a current offset on a bench log).
    out << "  warnings:";
    if (s["warnings"].empty()) out << " none";
    const nlohmann::json duration_s = f.is_object() ? f["duration_s"] : nlohmann::json();
    for (const auto& w : s["warnings"]) {
        out << "\n    " << w["name"].get<std::string>() << " at " << fixed(w["first_time_s"], 1) << " s"
            << warning_detail(w, duration_s);
        out << warning_spells(w);
    }
    out << "\n";
}

void print_said(const nlohmann::json& said, const nlohmann::json& flight, std::ostream& out) {
    out << "  said (ground station):" << (said.empty() ? " nothing" : "") << "\n";
    const nlohmann::json duration_s = flight.is_object() ? flight["duration_s"] : nlohmann::json();
    for (const auto& t : said) {
        const std::string when = t["flight_time_s"].is_number() ? when_in_flight(t["flight_time_s"], duration_s)
                                                               : fixed(t["time_s"], 1) + " s, on the ground";
        out << "    " << when << "  " << (t["severity"] == "notice" ? "notice " : "warning") << "  "
            << t["text"].get<std::string>() << "\n";
    }
}

void select_joint_estimator(host::LoadedConfig& config, const char* command) {
    if (config.monitor.estimator == core::EstimatorKind::Joint) return;
    config.monitor.estimator = core::EstimatorKind::Joint;
    std::cerr << command << ": note: the written config selects the joint estimator (\"estimator\": \"joint\"), "
              << "whose settings this tunes; the config given ran the reference one\n";
}

void print_charger_check(const nlohmann::json& c, std::ostream& out) {
    const nlohmann::json& fault = c["fault"];
    out << "  charger check: counted " << fixed(c["counted_ah"], 3) << " Ah against " << fixed(c["charged_ah"], 3)
        << " Ah charged (x" << fixed(c["ratio"], 4) << "): "
        << (fault.is_null() ? "no verdict" : fault.get<bool>() ? "current sensor fault" : "within tolerance");
    if (c["suggested_current_gain"].is_number())
        out << (fault.is_boolean() && !fault.get<bool>() ? "; no change needed (the gain it implies: "
                                                           : "; suggested extensions.current_sensor.gain ")
            << fixed(c["suggested_current_gain"], 4) << (fault.is_boolean() && !fault.get<bool>() ? ")" : "");
    out << "\n";
}

}  // namespace cli
}  // namespace battsim
