#include "host/fit/fit_job.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "host/fit/effect_names.h"
#include "host/io/atomic_file.h"
#include "host/io/number_text.h"
#include "host/plot/plot.h"
#include "host/report/summary.h"

namespace battsim {
namespace host {
namespace fit {

namespace {

double parse_number(const std::string& what, const std::string& text) {
    double v = 0;
    if (!parse_finite_number(text, &v))
        throw std::invalid_argument("--add " + what + ": expected a number after ':', found \"" + text + "\"");
    return v;
}

// The value after ':' within the range the config reader accepts for its key: outside it
// (thermal:-300, temperature:1e300) the fit had written a config no command could load.
double parse_in(const std::string& what, const std::string& text, double lo, double hi, const char* unit) {
    const double v = parse_number(what, text);
    if (!(v >= lo && v <= hi)) {
        char range[96];
        std::snprintf(range, sizeof range, "%g to %g %s", lo, hi, unit);
        throw std::invalid_argument("--add " + what + ": expected " + range + " after ':', found \"" + text + "\"");
    }
    return v;
}

std::string join_labels(const std::vector<Trace>& traces) {
    std::string s;
    for (const Trace& t : traces) s += (s.empty() ? "" : "+") + t.label;
    return s;
}

}  // namespace

std::vector<std::string> enable_extension(ModelSpec& s, const std::string& what) {
    const size_t colon = what.find(':');
    const std::string name = extension_name(what.substr(0, colon));
    const bool has_arg = colon != std::string::npos;
    const std::string arg = has_arg ? what.substr(colon + 1) : "";
    if (name == "rc") {
        if (s.ext.rc_count >= core::kMaxRcBranches)
            throw std::invalid_argument("--add rc: at most " + std::to_string(core::kMaxRcBranches) + " RC branches");
        static const float kDefaultTau[core::kMaxRcBranches] = {2.0f, 20.0f, 200.0f};
        const int b = s.ext.rc_count;
        s.ext.rc[b].time_constant_s = has_arg ? static_cast<float>(parse_in(what, arg, 1e-3, 1e9, "s")) : kDefaultTau[b];
        // A quarter of the ohmic resistance: the right order for LiPo polarisation and
        // large enough for the time constant to have a gradient.
        s.ext.rc[b].resistance_ohm = std::max(0.25f * s.battery.internal_resistance_ohm, 1e-4f);
        s.ext.rc_count = static_cast<uint8_t>(b + 1);
        const std::string p = "rc" + std::to_string(b + 1);
        return {p + "_r", p + "_tau"};
    }
    if (name == "temperature") {
        s.ext.temperature.enabled = true;
        if (has_arg) s.ext.temperature.reference_c = static_cast<float>(parse_in(what, arg, -100, 200, "degC"));
        return {"temp_r", "temp_k", "temp_q", "temp_e0"};
    }
    if (name == "thermal") {
        s.ext.thermal.enabled = true;
        if (has_arg) s.ext.thermal.ambient_c = static_cast<float>(parse_in(what, arg, -100, 200, "degC"));
        // Without a temperature measurement only the product of thermal resistance and
        // activation is identified, so the resistance stays as configured.
        return {"thermal_tau"};
    }
    // The other effects take no value: "hysteresis:5" had dropped its 5 without a word.
    if (has_arg && (name == "hysteresis" || name == "sensor" || name == "timing"))
        throw std::invalid_argument("--add " + what + ": " + name + " takes no value after ':'");
    if (name == "hysteresis") {
        if (s.ext.hysteresis.magnitude_v == 0.0f) s.ext.hysteresis.magnitude_v = 1e-3f;
        return {"hyst_m", "hyst_rate"};
    }
    if (name == "ocv") {
        const int n = has_arg ? static_cast<int>(parse_number(what, arg)) : 8;
        if (n < 2 || n > core::kMaxOcvPoints)
            throw std::invalid_argument("--add ocv: between 2 and " + std::to_string(core::kMaxOcvPoints) + " points");
        s.ext.ocv.count = static_cast<uint8_t>(n);
        s.ext.ocv.span_ah = s.battery.capacity_ah;
        for (int j = 0; j < core::kMaxOcvPoints; ++j) s.ext.ocv.delta_v[j] = 0.0f;
        return {"ocv"};
    }
    if (name == "sensor") return {"gain", "offset"};
    if (name == "timing") return {"lead"};
    throw std::invalid_argument("--add: unknown extension \"" + name +
                                "\"; expected rc, temperature, thermal, hysteresis, ocv, sensor or timing (or residual's names: rc_polarisation, self_heating, soc_shape, current_sensor, sample_timing)");
}

std::string per_log_config_path(const FitJob& job, const std::string& log) {
    return job.output_dir + "/" + (job.name.empty() ? std::string("fitted") : job.name) + "-" + trace_label(log) + ".json";
}

namespace {
// How far the logs determine a fitted parameter, for programs as for the brief: "at_bound",
// "not_moved" (no standard error: the error does not depend on it), "barely" (its standard
// error over a third of its value), "determined", or "signed" (a correction or an initial
// charge that sits near 0 by nature, against which any error is large: not judged). The JSON
// had carried only the numbers: a fit of a log on the ground read q = 0.041 ± 0.018 Ah with no
// word outside the brief.
std::string determination(const nlohmann::json& p) {
    if (p.contains("at_bound")) return "at_bound";
    const std::string name = p["name"].get<std::string>();
    const bool signed_near_zero = name == "initial" || name.compare(0, 3, "ocv") == 0 || name == "gain" || name == "offset" ||
                                  name == "lead" || name == "temp_e0";
    if (signed_near_zero) return "signed";
    if (p["sigma"].is_null()) return "not_moved";
    return p["sigma"].get<double>() > std::fabs(p["value"].get<double>()) / 3.0 ? "barely" : "determined";
}
}  // namespace

nlohmann::json run_fit_job(const FitJob& job, std::ostream* progress) {
    if (job.logs.empty()) throw std::invalid_argument("no logs to fit");
    // Names checked before the logs are read: a misspelt --params after minutes of reading
    // long logs had cost those minutes.
    {
        ModelSpec probe = spec_from_config(job.config);
        for (const std::string& a : job.add) enable_extension(probe, a);
        for (const auto& [option, names] : {std::make_pair("--params", &job.options.params),
                                             std::make_pair("--per-log", &job.options.per_log_params)})
            for (const std::string& n : *names)
                if (n != "none") check_parameter_name(n, option);
    }
    // The logs in the order of their paths, so the same set gives the same fit (the pooled
    // sums' order had moved a fit stopped at its iteration limit in the fifth digit).
    std::vector<std::string> logs = job.logs;
    std::sort(logs.begin(), logs.end());
    std::vector<Trace> traces;
    for (const std::string& path : logs) {
        if (progress) *progress << "battsim fit: reading " << path << "\n";
        traces.push_back(load_trace(path, job.reader, job.config));
        say_notes("battsim fit", traces.back(), progress);
    }
    ModelSpec start = spec_from_config(job.config);
    FitOptions options = job.options;
    std::vector<std::string> added;
    for (const std::string& a : job.add) {
        for (const std::string& p : enable_extension(start, a)) added.push_back(p);
    }
    const bool none = options.params.size() == 1 && options.params[0] == "none";
    if (none) {
        options.params.clear();  // evaluate only (with --initial monitor or zero: nothing is fitted)
    } else if (options.params.empty()) {
        options.params = default_parameters(start);
        for (const std::string& p : added) {
            if (std::find(options.params.begin(), options.params.end(), p) == options.params.end()) options.params.push_back(p);
        }
    }
    if (options.priors.empty()) options.priors = default_priors(start);
    // The extensions' plausibility bounds scale with the pack's charged voltage, not with the
    // curve-point encoding's full_voltage_v, which a fitted config may hold at two to four
    // times it (49 V for the 25.2 V Matrice 100 pack had let OCV corrections reach 7.4 V).
    if (options.bounds_full_voltage_v <= 0) options.bounds_full_voltage_v = job.config.monitor.max_voltage_v;
    // A parameter listed per log is not also shared.
    for (const std::string& p : options.per_log_params) {
        options.params.erase(std::remove(options.params.begin(), options.params.end(), p), options.params.end());
    }
    // Temperature terms fitted along a log without a temperature run at their reference
    // temperature throughout: they move nothing, stay at their start with no standard error,
    // and the config written would claim a dependence nothing measured. Refused, not noted: the
    // note would stand beside a config written as if fitted. A lumped thermal state drives them
    // without a measurement (residual's self_heating).
    const auto fitted = [&](const std::string& name) {
        return std::find(options.params.begin(), options.params.end(), name) != options.params.end() ||
               std::find(options.per_log_params.begin(), options.per_log_params.end(), name) != options.per_log_params.end();
    };
    const bool temperature_fitted = start.ext.temperature.enabled && !start.ext.thermal.enabled &&
                                    (fitted("temp_r") || fitted("temp_k") || fitted("temp_q") || fitted("temp_e0"));
    for (const Trace& t : traces) {
        if (!temperature_fitted || t.has_temperature) continue;
        char buf[400];
        std::snprintf(buf, sizeof buf,
                      "the log has no temperature, so the temperature terms to be fitted (--add temperature, or the "
                      "config's: temp_r, temp_k, temp_q, temp_e0) would run at %.3g degC throughout and move nothing: "
                      "give its temperature column (--temperature-col NAME), fit without them (--params), or let a "
                      "lumped thermal state drive them (--add thermal)",
                      static_cast<double>(start.ext.temperature.reference_c));
        throw InputError(t.path, 0, 0, buf);
    }
    const bool per_log = !options.per_log_params.empty();
    if (per_log && !job.output_config.empty())
        throw std::invalid_argument("with per-log parameters there is one config per log: use --output-dir, not -o");
    if (per_log && !job.test_logs.empty())
        throw std::invalid_argument("with per-log parameters there is no single model to test on other logs");

    if (progress) *progress << "battsim fit: fitting " << options.params.size() << " shared parameter(s) on " << traces.size() << " log(s)\n";
    const FitResult result = fit_model(traces, {start}, options);
    nlohmann::json report = fit_result_to_json(result, options);
    for (auto& p : report["parameters"]) p["determined"] = determination(p);
    report["battsim_version"] = BATTSIM_VERSION;
    report["config_start"] = job.config.name;
    report["extensions_added"] = job.add;

    // Baseline: the starting config as the monitor runs it, for the before/after numbers.
    nlohmann::json before = nlohmann::json::array();
    const ModelSpec as_given = spec_from_config(job.config);
    for (const Trace& t : traces) {
        const LogFitStats s = evaluate(t, as_given, options.initial == InitialMode::Zero ? InitialMode::Zero : InitialMode::Monitor, 0.0f);
        before.push_back({{"label", t.label}, {"all", error_stats_to_json(s.fit_all)}, {"flight", error_stats_to_json(s.fit_flight)}});
    }
    report["start_monitor"] = before;

    std::vector<Trace> tests;
    nlohmann::json test_json = nlohmann::json::array();
    for (const std::string& path : job.test_logs) {
        if (progress) *progress << "battsim fit: testing on " << path << "\n";
        tests.push_back(load_trace(path, job.reader, job.config));
        say_notes("battsim fit", tests.back(), progress);
        // A test log starts like the fitted ones: full (zero) or as the monitor finds it.
        const InitialMode mode = options.initial == InitialMode::Zero ? InitialMode::Zero : InitialMode::Monitor;
        const LogFitStats s = evaluate(tests.back(), result.specs[0], mode, 0.0f);
        const LogFitStats s0 = evaluate(tests.back(), as_given, mode, 0.0f);
        test_json.push_back({{"label", s.label}, {"path", s.path}, {"initial_ah", round_sig(s.initial_ah, 6)},
                             {"initial", to_string(mode)},
                             {"monitor", {{"all", error_stats_to_json(s.fit_all)}, {"flight", error_stats_to_json(s.fit_flight)}}},
                             {"start_monitor", {{"all", error_stats_to_json(s0.fit_all)}, {"flight", error_stats_to_json(s0.fit_flight)}}}});
    }
    report["test"] = test_json;

    // Configs: the start config with the fitted model written in.
    auto make_config = [&](const ModelSpec& spec, const std::string& name) {
        LoadedConfig c = job.config;
        spec_to_config(spec, c);
        c.name = name;
        c.description = "Fitted by battsim fit " BATTSIM_VERSION " on " + join_labels(traces) +
                               " (initial " + to_string(options.initial) + ", window " + to_string(options.window) +
                               ", RMSE " + std::to_string(round_sig(result.rmse_v, 4)) + " V) from " + job.config.name;
        return c;
    };
    nlohmann::json written = nlohmann::json::array();
    if (!job.output_config.empty()) {
        const std::string name = job.name.empty() ? "fitted-" + join_labels(traces) : job.name;
        write_file_atomic(job.output_config, json_text(config_to_json(make_config(result.specs[0], name)), 2) + "\n");
        written.push_back(job.output_config);
    }
    if (!job.output_dir.empty()) {
        // As batch --out and simulate --out-dir: a directory not there yet is made.
        std::error_code ec;
        std::filesystem::create_directories(job.output_dir, ec);
        if (ec) throw std::runtime_error(job.output_dir + ": cannot create the directory (" + ec.message() + ")");
        for (size_t t = 0; t < traces.size(); ++t) {
            const std::string name = (job.name.empty() ? std::string("fitted") : job.name) + "-" + traces[t].label;
            const std::string path = per_log_config_path(job, traces[t].path);
            write_file_atomic(path, json_text(config_to_json(make_config(result.specs[t], name)), 2) + "\n");
            written.push_back(path);
        }
    }
    report["configs_written"] = written;

    if (!job.plot_path.empty()) {
        std::vector<plot::ModelTraceSeries> series;
        for (size_t t = 0; t < traces.size(); ++t) {
            SimResult sim;
            simulate(traces[t], result.specs[t], options.initial, result.initial_ah[t], sim);
            series.push_back(plot::model_series(traces[t], sim.model_v, "fit"));
        }
        for (size_t t = 0; t < tests.size(); ++t) {
            SimResult sim;
            simulate(tests[t], result.specs[0], options.initial == InitialMode::Zero ? InitialMode::Zero : InitialMode::Monitor,
                     0.0f, sim);
            series.push_back(plot::model_series(tests[t], sim.model_v, "test"));
        }
        const size_t left_out = plot::plot_model_fit(series, "battsim fit: measured and fitted model voltage", job.plot_path);
        report["plot"] = job.plot_path;
        if (left_out > 0)
            report["plot_note"] = std::to_string(left_out) + " of the " + std::to_string(series.size()) +
                                  " logs are not in the plot (8 panels at most, up to 4 of them test logs)";
    }
    return report;
}

void print_fit_brief(const nlohmann::json& r, std::ostream& out) {
    // No standard error (a parameter the data cannot move): a dash, not "null".
    const auto sigma = [](const nlohmann::json& s) { return s.is_null() ? std::string("–") : s.dump(); };
    out << "fit: RMSE " << r["rmse_v"] << " V, MAE " << r["mae_v"] << " V over " << r["points"] << " points ("
        << r["solver"]["iterations"] << " iterations, " << r["solver"]["stop"].get<std::string>() << ")\n";
    if (r["solver"].contains("starts")) {
        const auto& starts = r["solver"]["starts"];
        // Start 0's excess as a share of the sum of squares the fit minimises (its RMSE alone
        // can be the lower one when the logs weigh equally, not by their samples).
        const auto percent = [](double fraction) {
            char buf[32];
            std::snprintf(buf, sizeof buf, 100 * fraction >= 100 ? "%.0f" : "%.2g", 100 * fraction);
            return std::string(buf);
        };
        const double first = starts[0]["cost_ratio"].get<double>() - 1;
        const int best = r["solver"]["best_start"].get<int>();
        out << "  " << starts.size() << " starts: the best from start " << best
            << (best == 0       ? std::string(" (the config's values)")
                : first < 1e-5 ? std::string(" (start 0, the config's values, ended within 0.001 % of its sum of squares)")
                               : " (start 0, the config's values, ended " + percent(first) + " % above its sum of squares)")
            << "; " << r["solver"]["near_best"] << " of them, the best included, the logs cannot tell apart (sum of squares within "
            << percent(r["solver"]["near_best_cost"].get<double>()) << " % of the best's: the approximate 95 % confidence region)\n";
    }
    for (const auto& p : r["parameters"]) {
        out << "  " << p["name"].get<std::string>();
        if (p.contains("log")) out << "[" << p["log"].get<std::string>() << "]";
        out << " = " << p["value"] << " " << p["unit"].get<std::string>() << " ± " << sigma(p["sigma"])
            << " (AR(1)-corrected ± " << sigma(p["sigma_ar1"]) << ")" << (p.contains("at_bound") ? " at bound" : "")
            << "\n";
    }
    for (const auto& p : r["derived"]) {
        out << "  " << p["name"].get<std::string>();
        if (p.contains("log")) out << "[" << p["log"].get<std::string>() << "]";
        out << " = " << p["value"] << " " << p["unit"].get<std::string>() << " ± " << sigma(p["sigma"]) << "\n";
    }
    const bool zero = r["options"]["initial"] == "zero";
    out << (zero ? "  per log, the start config -> the fitted model (logs start full):\n"
                 : "  per log, the start config -> the fitted model, both with the initial charge the monitor would set "
                   "(in brackets: with the fitted initial charge):\n");
    for (size_t i = 0; i < r["logs"].size(); ++i) {
        const auto& l = r["logs"][i];
        const auto& b = r["start_monitor"][i];
        const auto& a = zero ? l["fit"] : l["monitor"];
        out << "  " << l["label"].get<std::string>() << ": MAE all " << b["all"]["mae_v"] << " -> " << a["all"]["mae_v"] << " V";
        if (!zero) out << " (" << l["fit"]["all"]["mae_v"] << " V)";
        if (b["flight"]["n"].get<size_t>() > 0) {
            out << ", flight " << b["flight"]["mae_v"] << " -> " << a["flight"]["mae_v"] << " V";
            if (!zero) out << " (" << l["fit"]["flight"]["mae_v"] << " V)";
        }
        out << "\n";
    }
    for (const auto& l : r["test"]) {
        out << "  test " << l["label"].get<std::string>() << ": MAE all " << l["start_monitor"]["all"]["mae_v"] << " -> "
            << l["monitor"]["all"]["mae_v"] << " V";
        // A test log without a flight (a lab discharge) has no flight error, not one of 0 V.
        if (l["start_monitor"]["flight"]["n"].get<size_t>() > 0)
            out << ", flight " << l["start_monitor"]["flight"]["mae_v"] << " -> " << l["monitor"]["flight"]["mae_v"] << " V";
        out << "\n";
    }
    if (r.contains("plot_note")) out << "  plot: " << r["plot_note"].get<std::string>() << "\n";
    // What to try next when the fit did not settle, rather than a result that only looks like one.
    size_t at_bound = 0;
    for (const auto& p : r["parameters"]) at_bound += p.contains("at_bound") ? 1 : 0;
    const bool limit = r["solver"]["stop"] == "iteration limit";
    if (limit || at_bound > 0) {
        out << "  not settled:";
        if (limit) out << " the iteration limit (" << r["solver"]["iterations"] << ", --max-iterations) was reached";
        if (limit && at_bound > 0) out << ";";
        if (at_bound > 0) out << " " << at_bound << " parameter(s) at a bound";
        if (r["options"]["initial"] == "free") out << "; a log that starts full and at rest (a bench discharge) fits better with --initial zero";
        out << "\n";
    }
    // A fit that settled can still leave parameters the logs do not determine: 20 rows of a
    // 3 Ah cell's discharge "fitted" q = 0.031 ± 0.020 Ah without a word. Named, so a value
    // is not read as a measurement.
    std::string loose, idle;
    for (const auto& p : r["parameters"]) {
        const std::string d = determination(p);
        std::string name = p["name"].get<std::string>();
        if (p.contains("log")) name += "[" + p["log"].get<std::string>() + "]";
        if (d == "not_moved")
            idle += (idle.empty() ? "" : ", ") + name;
        else if (d == "barely")
            loose += (loose.empty() ? "" : ", ") + name;
    }
    // Fits the logs cannot tell from the best that put a parameter elsewhere: the logs leave
    // it freer than its standard error (the curvature at the best fit alone) says.
    std::string spread;
    for (const auto& p : r["parameters"]) {
        if (!p.contains("near_best_range") || r["solver"]["near_best"].get<int>() < 2) continue;
        const auto& range = p["near_best_range"];
        if (range[0].is_null() || range[1].is_null()) continue;
        const double lo = range[0].get<double>(), hi = range[1].get<double>();
        const double value = p["value"].get<double>();
        const bool wide = p["sigma"].is_null() ? hi - lo > 1e-3 * std::max(std::fabs(value), 1e-9) : hi - lo > 2 * p["sigma"].get<double>();
        if (!wide) continue;
        std::string name = p["name"].get<std::string>();
        if (p.contains("log")) name += "[" + p["log"].get<std::string>() + "]";
        char buf[96];
        std::snprintf(buf, sizeof buf, " %.4g–%.4g", lo, hi);
        spread += (spread.empty() ? "" : ", ") + name + buf + (p["unit"].get<std::string>().empty() ? "" : " " + p["unit"].get<std::string>());
    }
    if (!spread.empty())
        out << "  left free by these logs (fits they cannot tell apart put them further apart than 2 standard errors): " << spread << "\n";
    if (!loose.empty()) out << "  barely determined by these logs (standard error over a third of the value): " << loose << "\n";
    if (!idle.empty()) out << "  not moved by these logs (no standard error: the error does not depend on them): " << idle << "\n";
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
