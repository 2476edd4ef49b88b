// battsim make-config --cells 4 --capacity-mah 1760 -o my-pack.json, or --from-log LOG:
// a config for one's own pack, from its rating or from the autopilot's battery parameters
// recorded in the log. Values given on the command line win over the log's.
#include <cmath>
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/config_json.h"
#include "host/config_keys.h"
#include "host/export_header.h"
#include "host/io/atomic_file.h"
#include "core/sample.h"
#include "host/pack_config.h"
#include "host/report/summary.h"

namespace battsim {
namespace cli {
namespace {

struct MakeConfigArgs {
    std::string from_log;
    std::string board;
    std::string format = "auto";
    int cells = 0;
    double capacity_mah = NAN;
    double resistance_mohm = NAN;
    double cutoff_v = NAN;
    double cutoff_delay_s = NAN;
    std::string name;
    std::string chemistry = "lipo";
    std::string output = "-";
    bool list_keys = false;
    bool json = false;
};

// The config reference instead of a config: every key, from the reader itself.
int list_keys(const MakeConfigArgs& a) {
    const std::vector<host::ConfigKey> keys = host::config_keys();
    host::write_file_atomic(a.output, a.json ? host::json_text(host::config_keys_json(keys), 2) + "\n"
                                             : host::config_keys_markdown(keys));
    return kExitOk;
}

// A loaded cutoff below any LiPo pilot's (V per cell): a Li-ion cell's.
constexpr double kLiIonCutoffBelowVPerCell = 2.95;

int run(const MakeConfigArgs& a) {
    const char* me = "battsim make-config";
    if (int rc = check_outputs(me, {{"--from-log", a.from_log}, {"--board", a.board}}, {text_output("-o/--output", a.output)})) return rc;
    if (a.list_keys) {
        if (!a.from_log.empty() || !a.board.empty() || a.cells > 0 || std::isfinite(a.capacity_mah) || std::isfinite(a.resistance_mohm) ||
            std::isfinite(a.cutoff_v) || std::isfinite(a.cutoff_delay_s) || !a.name.empty() || a.chemistry != "lipo") {
            std::cerr << me << ": --list-keys lists the keys of any config; it takes no pack options\n";
            return kExitUsage;
        }
        return list_keys(a);
    }
    if (a.json) {
        std::cerr << me << ": --json goes with --list-keys (a config is JSON already)\n";
        return kExitUsage;
    }
    host::LogPack log;
    if (!a.from_log.empty()) {
        host::ReaderOptions options;
        options.format = host::parse_log_format(a.format);
        log = host::read_log_pack(a.from_log, options, a.cells);
        for (const std::string& why : log.ignored) std::cerr << me << ": note: ignored " << why << "\n";
        for (const std::string& note : log.notes) std::cerr << me << ": note: " << note << "\n";
        if (!std::isfinite(a.cutoff_v))
            for (const std::string& note : log.cutoff_notes) std::cerr << me << ": note: " << note << "\n";
    }
    host::PackRating given;
    given.name = a.name;
    given.chemistry = a.chemistry;
    given.cells = a.cells;
    given.capacity_ah = a.capacity_mah / 1000.0;
    given.resistance_ohm = a.resistance_mohm / 1000.0;
    given.cutoff_voltage_v = a.cutoff_v;
    given.cutoff_delay_s = a.cutoff_delay_s;
    const host::PackRating r = host::merge_rating(given, log);
    // Where each value came from, when a log gave some (from the command line alone it only
    // repeated what was typed); before a refusal too, which had not said what the log did give.
    for (const std::string& s : r.sources)
        if (s.find(" given") == std::string::npos) std::cerr << me << ": " << s << "\n";
    const std::string where = a.from_log.empty() ? "" : " (the log does not say)";
    if (r.cells <= 0 && log.declared_cells_beyond > 0) {
        std::cerr << me << ": the log's pack has " << log.declared_cells_beyond << " cells in series; battsim handles at most "
                  << core::kMaxCells << "\n";
        return kExitUsage;
    }
    if (r.cells <= 0) {
        std::cerr << me << ": how many cells in series? give --cells" << where << "\n";
        return kExitUsage;
    }
    if (!std::isfinite(r.capacity_ah)) {
        std::cerr << me << ": what is the rated capacity? give --capacity-mah" << where << "\n";
        return kExitUsage;
    }
    if (std::isfinite(a.resistance_mohm)) {
        const std::string per_cell = host::per_cell_resistance_note(r);
        if (!per_cell.empty()) std::cerr << me << ": note: " << per_cell << "\n";
    }
    nlohmann::json j;
    try {
        j = host::pack_config_json(r);
    } catch (const std::invalid_argument& e) {
        std::cerr << me << ": " << e.what() << "\n";
        return kExitUsage;
    }
    if (!a.board.empty()) {
        // Read before anything is written: a bad board config exits 4 with its position.
        const host::LoadedConfig board = host::load_config_file(a.board);
        std::vector<std::string> left;
        const std::vector<std::string> changed = host::apply_board(j, board, &left);
        if (!left.empty()) {
            std::string list;
            for (const std::string& key : left) list += (list.empty() ? "" : ", ") + key;
            std::cerr << me << ": note: not taken from " << a.board << ": " << list << " (measured on "
                      << board.monitor.cells_in_series << "-cell packs; the share depends on the cell count: "
                      << "calibrate this monitor on " << j["battery"]["cells_in_series"].get<int>()
                      << "-cell packs, battsim calibrate --cell-leads)\n";
        }
        if (changed.empty()) {
            std::cerr << me << ": note: " << a.board << " has the reference logger's board settings; nothing to take\n";
        } else {
            std::string list;
            for (const std::string& key : changed) list += (list.empty() ? "" : ", ") + key;
            std::cerr << me << ": from the board's config " << a.board << ": " << list << "\n";
            j["description"] = j["description"].get<std::string>() + " Board settings (" + list + ") from " + a.board + ".";
        }
    }
    // The table is a LiPo's: a cutoff under 2.95 V per cell, below any LiPo pilot's loaded
    // cutoff, is a Li-ion cell's (18650s run to 2.5 V), whose curve lies lower; read with this
    // table the Panasonic 2.9 Ah cell had ended at 5.76 Ah without a word.
    const nlohmann::json& table = j["joint"]["ocv_cell_voltage_v"];
    const double cutoff_per_cell_v = j["monitor"]["min_flight_voltage_v"].get<double>() / r.cells;
    if (a.chemistry == "lipo" && table.is_array() && !table.empty() && cutoff_per_cell_v < kLiIonCutoffBelowVPerCell) {
        std::cerr << me << ": note: the cutoff, " << host::fixed_text(cutoff_per_cell_v, 3)
                  << " V per cell, lies below the empty point of the config's OCV table ("
                  << host::fixed_text(table[0].get<double>(), 3)
                  << " V per cell), a lithium-polymer pack's: for a Li-ion pack give --chemistry li-ion (an 18650 "
                     "cell's curve), or read its own table off a slow discharge (battsim discharge LOG -c CONFIG "
                     "--config-out PACK.json); with the LiPo curve its capacity and warnings are wrong\n";
    }
    // A pack above the reference board's reach is said here, not only when its header is
    // exported: a 12S heavy-lift pack's config had been written without a word.
    const std::string bus = host::reference_bus_note(host::config_from_json(j, "make-config").monitor);
    if (!bus.empty())
        std::cerr << me << ": note: " << bus << "; battsim replays such a pack's logs from any other monitor or autopilot\n";
    host::write_file_atomic(a.output, host::json_text(j, 2) + "\n");
    return kExitOk;
}

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<MakeConfigArgs>();
    auto* from_log = sub.add_option("--from-log", a->from_log,
                   "Take what an autopilot log says about its pack: PX4 BAT1_N_CELLS, BAT1_CAPACITY, BAT1_R_INTERNAL; "
                   "ArduPilot BATT_CAPACITY, BATT_LOW_VOLT (or LOW_VOLT, FS_BATT_VOLTAGE), BATT_LOW_TIMER; the cell "
                   "count from its cell columns or how high it rests");
    sub.add_option("--board", a->board,
                   "A config written for this monitor board (e.g. by replay --config-out after a charger check): take "
                   "its board settings, not the reference logger's: the shunt calibration, the current sensor's range and "
                   "correction (battery.extensions.current_sensor), which cells' readings carry a lead, the telemetry");
    sub.add_option("--format", a->format, "Log format of --from-log (as replay)")->capture_default_str()->needs(from_log);
    sub.add_option("--cells", a->cells, "Cells in series")->check(CLI::Range(1, 12));
    sub.add_option("--capacity-mah", a->capacity_mah, "Rated capacity (mAh)")->check(number_in(0.0, 1.0e6, true));
    sub.add_option("--resistance-mohm", a->resistance_mohm,
                   "Pack internal resistance (mOhm; default: the reference pack's per cell, scaled by capacity)")
        ->check(number_in(0.0, 1.0e4, true));
    sub.add_option("--cutoff-v", a->cutoff_v,
                   "Loaded pack voltage the remaining time runs to (V; default 3.325 V per cell, Li-ion 3.0)")
        ->check(number_in(0.0, 1.0e4, true));
    sub.add_option("--cutoff-delay-s", a->cutoff_delay_s,
                   "How long the flight goes on below the cutoff before the failsafe acts (s; default 5)")
        ->check(number_in(0.0, 600.0));
    sub.add_option("--chemistry", a->chemistry,
                   "lipo, or li-ion: an 18650/21700 pack's lower, longer curve (the Samsung 30Q's, read off its C/10 "
                   "discharge), ten times the resistance per Ah, and a 3.0 V per cell cutoff")
        ->capture_default_str()
        ->check(CLI::IsMember({"lipo", "li-ion"}));
    sub.add_option("--name", a->name, "Config name (default pack-<cells>s-<mAh>)");
    sub.add_option("-o,--output", a->output, "Config JSON to write (\"-\" = standard output)")->capture_default_str();
    sub.add_flag("--list-keys", a->list_keys,
                 "Instead of a config: every key a config may hold, with its type, default, accepted range and "
                 "meaning (Markdown, as docs/config-keys.md)");
    sub.add_flag("--json", a->json, "With --list-keys: the keys as JSON");
    return [a]() -> int {
        try {
            return run(*a);
        } catch (const host::InputError& e) {
            std::cerr << "battsim make-config: " << e.what() << "\n";
            return kExitInputError;
        } catch (const host::ConfigError& e) {
            std::cerr << "battsim make-config: " << e.what() << "\n";
            return kExitConfigError;
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim make-config: " << e.what() << "\n";
            return kExitUsage;
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim make-config: " << e.what() << "\n";
            return kExitOutputError;
        }
    };
}

const RegisterCommand reg{{"make-config", "Write a config for your pack from its rating or an autopilot log's battery parameters", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
