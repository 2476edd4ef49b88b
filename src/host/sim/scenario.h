// One simulated flight, fully described: pack (cells, capacity, resistances, spread,
// ageing, weak cells, charge at take-off), environment, load profile, sensor hardware and
// faults, the truth's cutoff rule, and the monitor config that matches the pack.
// JSON schema "battsim.scenario", version 1; unknown keys are errors. Defaults describe a
// healthy generic 1.55 Ah LiPo pack; powers and thermal mass scale with cells × capacity.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/config_json.h"
#include "host/sim/plant.h"
#include "host/sim/profile.h"
#include "host/sim/sensor.h"

namespace battsim {
namespace host {
namespace sim {

// Bad scenario file or value: the message names the file, the line and column (when read
// from a file) and the JSON path.
class ScenarioError : public JsonValueError {
public:
    using JsonValueError::JsonValueError;
};

struct WeakCell {
    int cell = 1;  // 1-based
    double capacity_factor = 1.0;
    double resistance_factor = 1.0;
};

struct PackSpec {
    int cells = 4;
    double capacity_ah = 1.55;  // healthy cell capacity, empty (3.3 V rest) to full (4.2 V)
    // Per-cell resistances at 25 °C; unset (< 0) = derived from the capacity (a generic
    // high-rate LiPo); 0 = no such branch (a plant without polarisation is a valid control).
    double r0_ohm = -1.0, r1_ohm = -1.0, r2_ohm = -1.0;
    double tau1_s = 1.5, tau2_s = 40.0;
    double capacity_spread = 0.015;    // cell-to-cell relative standard deviation (seeded)
    double resistance_spread = 0.04;
    double capacity_factor = 1.0;      // ageing of every cell
    double resistance_factor = 1.0;
    std::vector<WeakCell> weak_cells;
    double initial_soc = 1.0;
    double activation_energy_j_per_mol = 20000.0;
    // Unset (< 0) = derived from the size; a conductance of 0 is an insulated pack (0 had
    // silently meant the default), a heat capacity of 0 is refused (no thermal mass).
    double heat_capacity_j_per_k = -1.0;       // unset: 30.6 J/K per cell·Ah
    double conductance_ground_w_per_k = -1.0;  // unset: 0.4 W/K × (cells·Ah/6.2)^(2/3)
    double conductance_flight_w_per_k = -1.0;  // unset: 1.6 W/K × (cells·Ah/6.2)^(2/3)
};

struct Scenario {
    std::string name;
    std::string description;
    std::string source_path;         // the scenario file ("" when built in code)
    uint64_t seed = 1;
    std::string monitor_config;      // as written (relative to the scenario file)
    std::string monitor_config_path; // resolved
    LoadedConfig config;             // the monitor config for this pack
    PackSpec pack;
    double ambient_c = 20.0;
    double initial_temperature_c = 0.0;
    bool initial_temperature_given = false;  // false: the pack starts at ambient
    ProfileParams profile;           // mean_power_w <= 0: 90 W (racing) or 35 W (hover) per cell × Ah/1.55
    SensorParams sensor;
    // Loaded, on the low-passed pack voltage. Unless $.truth sets it: the monitor config's
    // min_flight_voltage_v per cell, so the truth answers the question the monitor is asked.
    double cutoff_v_per_cell = 3.3;
    double cutoff_filter_s = 5.0;
    double decimation_s = 1.0;       // truth series spacing
    double step_s = 0.002;           // plant integration step
    double max_continuation_s = 3600.0;
    std::string log_format = "auto";  // auto (raw for 4 cells, csv otherwise), raw, csv, edgetx
    double log_interval_s = 0.2;      // edgetx: the radio's log interval
    bool log_interval_given = false;  // $.log.interval_s set (only edgetx uses it)
};

Scenario load_scenario(const std::string& path);
// `origin` names the source in messages; `base_dir` resolves the monitor config path
// ("" = current directory). `config_json`, when not null, is used instead of reading the
// monitor config file (a truth file carries its config).
Scenario scenario_from_json(const nlohmann::json& j, const std::string& origin, const std::string& base_dir,
                            const nlohmann::json* config_json = nullptr);
// Every value, defaults filled in, so a truth file says exactly what was simulated.
nlohmann::json scenario_to_json(const Scenario& s);

// Scenario files named by `paths`: files as given, directories for their *.json files
// sorted by name. Throws ScenarioError if a path does not exist or nothing is found.
std::vector<std::string> find_scenario_files(const std::vector<std::string>& paths);

// Copy k of a scenario (k >= 1): the same pack, load, faults and config with other random
// draws (gusts, cell spread, sensor noise): seed + 7919·k, named NAME@k. k = 0 returns it
// unchanged. `battsim score --copies` and scripts/joint-search.py --reseed use the same rule.
Scenario reseeded(const Scenario& s, int copy);

// Fills every value left unset (resistances and thermal constants < 0, mean power <= 0)
// from the pack's size. Idempotent; load_scenario() calls it.
void resolve_defaults(Scenario& s);
// The plant for this scenario (resolve_defaults() first). `healthy`: the same pack
// (same seeded cell spread) without its ageing and weak cells, the reference a
// degraded flight's length is compared with.
PlantParams make_plant_params(const Scenario& s, bool healthy);
SimLogFormat log_format_of(const Scenario& s);
// Why `format` cannot be the log format of a pack of `cells` cells, "" if it can: it must
// be auto, raw, csv or edgetx, and the raw logger's rows hold exactly 4 cells. The scenario
// files and the commands that override the format (simulate, score) ask this one question.
std::string log_format_problem(const std::string& format, int cells);
// A command's override: every scenario's log format set to `format` (none when empty). "" when
// all take it, else "PATH: why" for the first that cannot (and none is changed).
// When $.log.interval_s is set but the log format is not edgetx, which ignores it (as does
// the truth's filled-in scenario): what to say; "" otherwise.
std::string log_interval_note(const Scenario& s);
std::string override_log_format(std::vector<Scenario>& scenarios, const std::string& format);

}  // namespace sim
}  // namespace host
}  // namespace battsim
