// battsim discharge LOG: constant-current discharge → lookup tables, zones, plot.
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/config_json.h"
#include "host/discharge/discharge.h"
#include "host/io/atomic_file.h"
#include "host/plot/plot.h"

namespace battsim {
namespace cli {
namespace {

struct DischargeArgs {
    std::string log, table, curve, summary, plot, config_out;
    double min_v = 0, max_v = 0, reaction_s = 0, alpha = 0;
    int decimate = 1;
    int ocv_points = 21;
    bool json = false;
    InputArgs input;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<DischargeArgs>();
    sub.add_option("LOG", a->log, "Discharge log (any supported format)")->required();
    // Above 0: 0 is their unset value, and a typed 0 had read as the config's.
    sub.add_option("--min-voltage", a->min_v, "Battery connected above this; bottom of the tables (default: the config's min_voltage_v)")
        ->check(number_in(0.0, host::discharge::kMaxTableVoltage_v, true));
    sub.add_option("--max-voltage", a->max_v, "Top of the tables (default: the config's max_voltage_v)")
        ->check(number_in(0.0, host::discharge::kMaxTableVoltage_v, true));
    sub.add_option("--reaction", a->reaction_s, "Smoothing: moving-average (exponential) time constant in s; 0 = none")->check(number_in(0.0, 1.0e6))->capture_default_str();
    CLI::Option* reaction = sub.get_option("--reaction");
    sub.add_option("--alpha", a->alpha, "Smoothing: fixed per-sample constant in (0, 1] instead of --reaction")
        ->check(number_in(0.0, 1.0, true))
        ->excludes(reaction);
    sub.add_option("--decimate", a->decimate, "Average every x samples")->capture_default_str();
    sub.add_option("--table", a->table, "Write the voltage -> mAh/mWh lookup table CSV here (10 mV rows, max to min)");
    sub.add_option("--curve", a->curve, "Write the smoothed, decimated curve with its gradient (CSV)");
    sub.add_option("--summary", a->summary, "Write the summary JSON (with the table) here");
    sub.add_option("--plot", a->plot, "Plot the curve and its gradient with the zone ends (.png or .svg)");
    sub.add_option("--config-out", a->config_out,
                   "Write a starting config with the Tremblay points read off the curve and the joint estimator's OCV table");
    sub.add_option("--ocv-points", a->ocv_points,
                   "Points of the joint estimator's OCV table (per cell, SOC 0..1, I*R added back with the config's "
                   "resistance); 0 = none")
        ->check(CLI::IsMember({0}) | CLI::Range(2, 21))
        ->capture_default_str();
    sub.add_flag("--json", a->json, "Print the summary JSON (with the table) on standard output");
    add_input_options(sub, a->input);
    return [a]() -> int {
        host::discharge::DischargeOptions opt;
        host::LoadedConfig config;
        if (int rc = resolve_input(a->input, opt.reader, config, "battsim discharge")) return rc;
        opt.reader.shunt = config.monitor.shunt;
        opt.loaded_current_a = config.monitor.flying.min_flying_current_a;
        // The built-in config's 1.55 Ah 4S pack says nothing of a log's pack.
        if (!a->input.config.empty()) {
            opt.rated_capacity_ah = config.monitor.battery.capacity_ah;
            opt.reader.clock_step_capacity_ah = opt.rated_capacity_ah;
        }
        opt.min_voltage_v = a->min_v > 0 ? a->min_v : config.monitor.min_voltage_v;
        opt.max_voltage_v = a->max_v > 0 ? a->max_v : config.monitor.max_voltage_v;
        opt.reaction_s = a->reaction_s;
        opt.alpha = a->alpha;
        opt.decimate = a->decimate;
        if (int rc = check_plot_option("battsim discharge", a->plot)) return rc;
        const std::vector<host::NamedPath> outputs{printed_output("--json", a->json),
                                                   text_output("--table", a->table),
                                                   text_output("--curve", a->curve),
                                                   text_output("--summary", a->summary),
                                                   {"--plot", a->plot},
                                                   text_output("--config-out", a->config_out, true)};
        if (int rc = check_outputs("battsim discharge", {{"the log", a->log}, {"-c/--config", a->input.config, true}}, outputs))
            return rc;
        std::ostream& people = people_out(outputs);
        host::discharge::DischargeResult result;
        try {
            result = host::discharge::process_discharge(a->log, opt);
        } catch (const host::InputError& e) {
            std::cerr << "battsim discharge: " << e.what() << "\n";
            return kExitInputError;
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim discharge: " << e.what() << "\n";
            return kExitUsage;
        }
        for (const auto& note : result.info.notes) std::cerr << "battsim discharge: note: " << note << "\n";
        if (!result.ended_early.empty()) std::cerr << "battsim discharge: note: " << result.ended_early << "\n";
        nlohmann::json summary = host::discharge::discharge_to_json(result, true);
        // A config for another pack reads the curve per cell of its own count: the built-in
        // 4S config on one Samsung cell had written a config of 0.63-1.04 V per cell, silently.
        host::LogFacts facts;
        facts.resting_voltage_v = result.first_voltage_v;
        facts.path = a->log;
        nlohmann::json other_pack = nlohmann::json::array();
        for (const std::string& note : host::config_notes(config.monitor, facts)) {
            if (!host::is_other_pack_note(note)) continue;
            std::cerr << "battsim discharge: note: " << note << "\n";
            other_pack.push_back(note);
        }
        if (!other_pack.empty()) summary["config_notes"] = other_pack;
        if (!other_pack.empty() && !a->config_out.empty()) {
            std::cerr << "battsim discharge: --config-out: the config is for another pack than the log's (above), so its "
                         "OCV table and curve points would be per cell of the wrong count; give -c a config for this pack\n";
            return kExitConfigError;
        }
        host::discharge::OcvTableRead ocv;
        const bool with_ocv = a->ocv_points != 0 && result.ended_early.empty();  // part of a discharge: no SOC scale
        if (with_ocv) {
            try {
                ocv = host::discharge::ocv_table_from_discharge(result, config.monitor.cells_in_series,
                                                                config.monitor.battery.internal_resistance_ohm, a->ocv_points);
            } catch (const std::invalid_argument& e) {
                // The options are checked above: what is left is the log (no charge drawn).
                std::cerr << "battsim discharge: " << a->log << ": " << e.what() << "\n";
                return kExitInputError;
            }
            for (const auto& note : ocv.notes) std::cerr << "battsim discharge: note: " << note << "\n";
            summary["ocv_table"] = host::discharge::ocv_table_to_json(ocv);
        } else {
            summary["ocv_table"] = nullptr;  // the key is always there (it had been left out)
        }
        // The start config first: a discharge it cannot be read off (no zones) fails before
        // any output is written, not after the table and the summary.
        std::string config_text;
        if (!a->config_out.empty()) {
            try {
                const host::LoadedConfig out =
                    host::discharge::start_config_from_discharge(result, config, with_ocv ? &ocv : nullptr);
                config_text = host::json_text(host::config_to_json(out), 2) + "\n";
            } catch (const std::invalid_argument& e) {
                std::cerr << "battsim discharge: " << e.what() << "\n";
                return kExitInputError;
            }
        }
        try {
            if (!a->table.empty()) host::write_file_atomic(a->table, host::discharge::table_csv(result));
            if (!a->curve.empty()) host::write_file_atomic(a->curve, host::discharge::curve_csv(result));
            if (!a->summary.empty()) host::write_file_atomic(a->summary, host::json_text(summary, 2) + "\n");
            if (!a->plot.empty()) host::discharge::plot_discharge(result, a->plot);
            if (!a->config_out.empty()) host::write_file_atomic(a->config_out, config_text);
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim discharge: " << e.what() << "\n";
            return kExitInputError;
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim discharge: " << e.what() << "\n";
            return kExitOutputError;
        }
        if (a->json) {
            std::cout << host::json_text(summary, 2) << "\n";
            return kExitOk;
        }
        people << a->log << ": " << result.samples_kept << " of " << result.samples_read << " samples above "
               << opt.min_voltage_v << " V, " << summary["duration_s"] << " s\n";
        people << "  " << summary["capacity_mah"] << " mAh, " << summary["energy_mwh"] << " mWh at a mean "
               << summary["mean_current_a"] << " A (" << host::discharge::c_rate_text(result) << "); "
               << summary["first_voltage_v"] << " -> " << summary["last_voltage_v"] << " V\n";
        if (with_ocv) {
            people << "  OCV table (" << ocv.cell_voltage_v.size() << " points per cell, SOC 0 -> 1): "
                   << summary["ocv_table"]["cell_voltage_v"].front() << " ... " << summary["ocv_table"]["cell_voltage_v"].back()
                   << " V\n";
        }
        if (result.zones.found) {
            people << "  exponential zone ends at " << summary["zones"]["exponential_end"]["capacity_ah"] << " Ah, "
                   << summary["zones"]["exponential_end"]["voltage_v"] << " V; nominal zone ends at "
                   << summary["zones"]["nominal_end"]["capacity_ah"] << " Ah, " << summary["zones"]["nominal_end"]["voltage_v"]
                   << " V\n";
        } else {
            people << "  zones not found: " << result.zones.note << "\n";
        }
        return kExitOk;
    };
}

const RegisterCommand reg{{"discharge", "Process a constant-current discharge: lookup tables, zones, plot", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
