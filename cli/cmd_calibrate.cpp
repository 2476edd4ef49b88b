// battsim calibrate LOG... -c CFG [-o OUT.json]: the health filter's slow polarisation share
// for a pack, from its own flights (the in-flight capacity against the rests'); with
// --cell-leads, the monitor's lead cells' share of their resistance, from healthy packs' flights.
#include <iomanip>
#include <iostream>
#include <sstream>

#include "command.h"
#include "common_options.h"
#include "host/fit/lead_calibration.h"
#include "host/fit/shape_calibration.h"
#include "host/io/number_text.h"

namespace battsim {
namespace cli {
namespace {

struct CalibrateArgs {
    std::vector<std::string> logs;
    std::string output;
    bool json = false;
    bool cell_leads = false;
    host::ShapeCalibrationOptions options;
    std::vector<std::string> shares;  // as typed; empty = the options' own
    InputArgs input;
};

void print_table(const host::ShapeCalibration& c, std::ostream& os) {
    os << "battsim calibrate: " << c.logs.size() << " flight(s) with a rest; capacity from the rests:";
    for (double v : c.rest_ah) os << " " << std::fixed << std::setprecision(3) << v;
    os << " Ah\n  slow share  mean |final/rest - 1|  final capacity (Ah)\n";
    for (const host::ShapeCandidate& k : c.candidates) {
        os << "  " << std::setw(10) << std::setprecision(2) << k.slow_share << "  " << std::setw(19)
           << std::setprecision(1) << 100.0 * k.mean_abs_error << " %";
        for (double v : k.final_ah) os << "  " << std::setprecision(3) << v;
        os << "\n";
    }
    os << std::setprecision(2) << "  chosen " << c.chosen_share
       << (c.changed ? " (changed from " : " (kept: the configured ") << c.configured_share << ")\n";
    for (const std::string& f : c.logs_without_rest) os << "  no rest after a flight, not used: " << f << "\n";
}

void print_leads(const host::LeadCalibration& c, std::ostream& os) {
    os << "battsim calibrate --cell-leads: " << c.flights.size() << " flight(s); each lead cell's short-lag resistance "
       << "over the others' median, less one (1.3: it reads 2.3 x the others)\n";
    for (const host::LeadCalibrationFlight& f : c.flights) {
        os << "  " << f.log << " (" << f.source << (f.used ? "" : ", left out") << "):";
        for (double r : f.cell_resistance_ohm) os << " " << std::fixed << std::setprecision(2) << 1000.0 * r;
        os << " mOhm";
        if (f.has_first) os << "; cell 1 " << std::showpos << std::setprecision(3) << f.first_excess << std::noshowpos;
        if (c.last_lead) os << "; last cell " << std::showpos << std::setprecision(3) << f.last_excess << std::noshowpos;
        os << "\n";
    }
    const auto line = [&](const char* key, double excess, double spread) {
        if (excess < 0.0) return;
        os << "  joint." << key << " " << std::setprecision(3) << excess << " (spread " << spread << ")\n";
    };
    os << "  pooled: " << c.flights_used << " flight(s) read by the short-lag fit\n";
    line("first_cell_lead_excess", c.first_excess, c.first_spread);
    line("last_cell_lead_excess", c.last_excess, c.last_spread);
    if (c.first_excess >= 0.0 || c.last_excess >= 0.0)
        os << "  joint.cell_lead_excess_sigma " << std::setprecision(3) << c.sigma << "\n";
    for (const std::string& f : c.logs_without_cells) os << "  no per-cell resistance, not used: " << f << "\n";
}

// --cell-leads: replay, pool, write the config with the keys set.
int run_cell_leads(const CalibrateArgs& a, host::ReplayOptions& opt, const std::vector<host::NamedPath>& outputs) {
    const char* const command = "battsim calibrate --cell-leads";
    host::LeadCalibration c;
    if (int rc = run_job(command, [&] { c = host::calibrate_cell_leads(a.logs, opt); })) return rc;
    for (const std::string& note : c.notes) std::cerr << command << ": note: " << note << "\n";
    if (c.flights.empty()) {
        std::cerr << command << ": no log gave per-cell resistances to calibrate from (" << a.logs.size()
                  << " given; each needs three or more cell columns, as many as the config's cells, and a flight the "
                  << "cell check measured)\n";
        return kExitFailure;
    }
    if (c.steps_only) {
        if (!a.json) print_leads(c, std::cerr);
        std::cerr << command << ": every flight was read by the big current steps alone (a hover's throttle never "
                  << "readies the short-lag fit), which see less of the wiring than the short-lag fit the check judges "
                  << "by: a share from them would blame healthy cells. Calibrate on flights with throttle changes "
                  << "(racing, aggressive climbs)\n";
        return kExitFailure;
    }
    if (!a.output.empty()) {
        host::LoadedConfig out = opt.config;
        host::apply_lead_calibration(c, out);
        if (int rc = write_tuned_config(out, a.output, command, "lead cells calibrated on ",
                                        std::to_string(c.flights_used) + " flight(s) by battsim calibrate --cell-leads"))
            return rc;
    }
    if (a.json) std::cout << host::json_text(host::to_json(c), 2) << "\n";
    else print_leads(c, people_out(outputs));
    return kExitOk;
}

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<CalibrateArgs>();
    sub.add_option("LOG", a->logs, "Logs of one pack (each with a rest after its flight); with --cell-leads, flights of healthy packs on one monitor")->required();
    sub.add_option("-o,--output", a->output, "Write the config with the calibrated share here (JSON)");
    sub.add_flag("--json", a->json, "Print the calibration JSON on standard output");
    std::ostringstream defaults;
    for (size_t i = 0; i < a->options.slow_shares.size(); ++i) defaults << (i ? "," : "") << a->options.slow_shares[i];
    const CLI::Validator share = number_in(0.0, 1.0);
    CLI::Option* shares = add_list_option(sub, "--shares", a->shares, "Candidate slow shares (0..1), comma-separated [" + defaults.str() + "]",
                    [share](const std::string& item) {
                        std::string text = item;
                        return share(text);
                    });
    CLI::Option* tolerance = sub.add_option("--tolerance", a->options.tolerance,
                                            "Keep the configured share while its mean |final/rest - 1| is within this")
                                 ->check(number_in(0.0, 1.0))
                                 ->capture_default_str();
    sub.add_flag("--cell-leads", a->cell_leads,
                 "Calibrate the monitor's lead cells instead (joint.first_cell_includes_lead, last_cell_includes_lead): "
                 "what the wiring adds to their resistance over the other cells' median, so that they are judged for "
                 "resistance too; from flights of healthy packs flown with this monitor")
        ->excludes(tolerance)
        ->excludes(shares);
    add_input_options(sub, a->input);
    return [a]() -> int {
        if (a->input.estimator == "reference") {
            std::cerr << "battsim calibrate: --estimator: the calibration is of the joint estimator's "
                      << (a->cell_leads ? "cell check" : "health filter") << "\n";
            return kExitUsage;
        }
        const char* const command = "battsim calibrate";
        if (!a->shares.empty()) {
            a->options.slow_shares.clear();
            for (const std::string& text : a->shares) {
                double v = 0.0;
                host::parse_finite_number(text, &v);  // checked by --shares' own validator
                a->options.slow_shares.push_back(v);
            }
        }
        host::ReplayOptions opt;
        if (int rc = resolve_input(a->input, opt.reader, opt.config, command)) return rc;
        host::ShapeCalibration c;
        std::vector<host::NamedPath> inputs{{"-c/--config", a->input.config, true}};
        add_named(inputs, "a log", a->logs);
        const std::vector<host::NamedPath> outputs{printed_output("--json", a->json), text_output("-o/--output", a->output, true)};
        if (int rc = check_outputs(command, inputs, outputs)) return rc;
        // A flight given twice weighs twice in the shares' mean error.
        if (int rc = check_logs_once(command, std::vector<host::NamedPath>(inputs.begin() + 1, inputs.end()))) return rc;
        // A log that cannot be read is said first (a missing one had been answered with the
        // default config's missing table, exit 1).
        if (int rc = run_job(command, [&] {
                for (const std::string& log : a->logs) host::open_reader(log, opt.reader);
            }))
            return rc;
        if (a->cell_leads) {
            const core::CellAnalyzer::Config& ca = opt.config.monitor.cell_analysis;
            if (!ca.first_cell_includes_lead && !ca.last_cell_includes_lead) {
                std::cerr << command << " --cell-leads: the config reads no cell across a lead "
                          << "(joint.first_cell_includes_lead and last_cell_includes_lead are false): every cell is "
                          << "judged as it is, and there is nothing to calibrate\n";
                return kExitFailure;
            }
            return run_cell_leads(*a, opt, outputs);
        }
        // Without a table the joint estimator's capacity is off by far more than any
        // polarisation shape moves it: the best share would be a fit to that error (on flight
        // 30 with the built-in config: 76 % off the rests' capacity at the edge of the shares).
        if (opt.config.monitor.joint.ocv.points < 2) {
            std::cerr << command << ": the config has no OCV table (joint.ocv_cell_voltage_v), so the joint estimator's "
                      << "capacity is off by more than the polarisation shape moves it; give -c a config with one "
                      << "(battsim discharge --ocv-points N, or battsim fit-ocv)\n";
            return kExitFailure;
        }
        if (int rc = run_job(command, [&] { c = host::calibrate_slow_share(a->logs, opt, a->options); })) return rc;
        for (const std::string& note : c.notes) std::cerr << command << ": note: " << note << "\n";
        if (c.logs.empty()) {
            std::cerr << command << ": no log has a rest after a flight to read the capacity from (" << a->logs.size()
                      << " given)\n";
            return kExitFailure;
        }
        if (!a->output.empty()) {
            host::LoadedConfig out = opt.config;
            out.monitor.joint.health.polarisation_slow_share = static_cast<float>(c.chosen_share);
            if (int rc = write_tuned_config(out, a->output, command, "health filter's slow share ",
                                            std::string(c.changed ? "calibrated" : "checked") + " on " +
                                                std::to_string(c.logs.size()) + " flight(s) by battsim calibrate"))
                return rc;
        }
        if (a->json) std::cout << host::json_text(host::to_json(c), 2) << "\n";
        else print_table(c, people_out(outputs));
        return kExitOk;
    };
}

const RegisterCommand reg{{"calibrate",
                           "Calibrate a pack's polarisation shape from its flights' rests, or (--cell-leads) a monitor's lead cells",
                           setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
