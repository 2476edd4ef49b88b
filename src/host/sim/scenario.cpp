#include "host/sim/scenario.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "host/sim/det_math.h"

namespace battsim {
namespace host {
namespace sim {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* kSchema = "battsim.scenario";
constexpr int kVersion = 1;

// Reads one JSON object's members by name; finish() reports keys nobody asked for, so a
// misspelt key is an error instead of a silent default.
class Reader {
public:
    Reader(const json& j, std::string path, const std::string& origin) : j_(j), path_(std::move(path)), origin_(origin) {
        if (!j.is_object()) fail(path_, "expected an object");
    }
    [[noreturn]] void fail(const std::string& where, const std::string& what, bool at_key = false) const {
        throw ScenarioError(origin_, where, what, at_key);
    }
    std::string at(const char* key) const { return path_ + "." + key; }
    const json* find(const char* key) {
        used_.insert(key);
        auto it = j_.find(key);
        return it == j_.end() ? nullptr : &*it;
    }
    bool number(const char* key, double& out, double lo, double hi) {
        const json* v = find(key);
        if (!v) return false;
        if (!v->is_number()) fail(at(key), "expected a number, found " + type_name(*v));
        const double d = v->get<double>();
        if (!std::isfinite(d) || d < lo || d > hi) {
            std::ostringstream m;
            m << "expected a number in [" << lo << ", " << hi << "], found " << json_brief(*v);
            fail(at(key), m.str());
        }
        out = d;
        return true;
    }
    // A number with a whole value reads as that number however it is written (4.0, 1e3), as
    // the monitor config and the options do: "expected a whole number, found 4.0" had
    // contradicted itself.
    static bool whole(const json& v) {
        if (v.is_number_integer()) return true;
        if (!v.is_number_float()) return false;
        const double d = v.get<double>();
        return std::isfinite(d) && d == std::floor(d);
    }
    bool integer(const char* key, int& out, int lo, int hi) {
        const json* v = find(key);
        if (!v) return false;
        if (!whole(*v)) fail(at(key), "expected a whole number, found " + json_brief(*v));
        const double d = v->get<double>();  // exact for every int, the only range checked
        if (d < lo || d > hi) {
            fail(at(key), "expected a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], found " +
                              json_brief(*v));
        }
        out = static_cast<int>(d);
        return true;
    }
    bool seed(const char* key, uint64_t& out) {
        const json* v = find(key);
        if (!v) return false;
        if (v->is_number_unsigned()) {
            out = v->get<uint64_t>();
            return true;
        }
        // 2^64 itself is the first double out of range.
        constexpr double kTwoTo64 = 18446744073709551616.0;
        if (!whole(*v) || v->get<double>() < 0.0 || v->get<double>() >= kTwoTo64)
            fail(at(key), "expected a whole number from 0 to 18446744073709551615, found " + json_brief(*v));
        out = static_cast<uint64_t>(v->get<double>());
        return true;
    }
    bool string(const char* key, std::string& out) {
        const json* v = find(key);
        if (!v) return false;
        if (!v->is_string()) fail(at(key), "expected a string, found " + type_name(*v));
        out = v->get<std::string>();
        return true;
    }
    void finish() const {
        for (auto it = j_.begin(); it != j_.end(); ++it) {
            if (!used_.count(it.key())) fail(path_ + "." + it.key(), "unknown key", true);
        }
    }
    static std::string type_name(const json& v) { return std::string(v.type_name()); }

private:
    const json& j_;
    std::string path_;
    const std::string& origin_;
    std::set<std::string> used_;
};

double pow23(double x) { return x > 0.0 ? det_exp(det_log(x) * (2.0 / 3.0)) : 0.0; }

void read_pack(Reader& r, PackSpec& p) {
    r.integer("cells", p.cells, 1, kMaxCells);
    r.number("capacity_ah", p.capacity_ah, 0.01, 1000.0);
    r.number("r0_ohm", p.r0_ohm, 1e-5, 10.0);  // a pack without resistance divides the score's errors by 0
    r.number("r1_ohm", p.r1_ohm, 0.0, 10.0);
    r.number("r2_ohm", p.r2_ohm, 0.0, 10.0);
    r.number("tau1_s", p.tau1_s, 0.01, 1e5);
    r.number("tau2_s", p.tau2_s, 0.01, 1e5);
    r.number("capacity_spread", p.capacity_spread, 0.0, 0.2);
    r.number("resistance_spread", p.resistance_spread, 0.0, 0.3);
    r.number("capacity_factor", p.capacity_factor, 0.05, 2.0);
    r.number("resistance_factor", p.resistance_factor, 0.1, 20.0);
    r.number("initial_soc", p.initial_soc, 0.05, 1.0);
    r.number("activation_energy_j_per_mol", p.activation_energy_j_per_mol, 0.0, 200000.0);
    if (r.number("heat_capacity_j_per_k", p.heat_capacity_j_per_k, 0.0, 1e7) && p.heat_capacity_j_per_k == 0.0)
        r.fail(r.at("heat_capacity_j_per_k"), "0 J/K is no thermal mass: the temperature would jump without bound; "
                                              "leave the key out for the default of 30.6 J/K per cell·Ah");
    r.number("conductance_ground_w_per_k", p.conductance_ground_w_per_k, 0.0, 1e5);
    r.number("conductance_flight_w_per_k", p.conductance_flight_w_per_k, 0.0, 1e5);
}

}  // namespace

Scenario reseeded(const Scenario& s, int copy) {
    Scenario r = s;
    if (copy <= 0) return r;
    r.seed = s.seed + 7919u * static_cast<uint64_t>(copy);
    r.name = s.name + "@" + std::to_string(copy);
    return r;
}

void resolve_defaults(Scenario& s) {
    PackSpec& p = s.pack;
    const double cap = p.capacity_ah;
    // Generic high-rate LiPo: resistances inversely proportional to capacity (6.2 mΩ·Ah
    // ohmic, 1.55 and 2.3 mΩ·Ah in the two polarisation branches at 25 °C).
    if (p.r0_ohm < 0.0) p.r0_ohm = 0.0062 / cap;
    if (p.r1_ohm < 0.0) p.r1_ohm = 0.00155 / cap;
    if (p.r2_ohm < 0.0) p.r2_ohm = 0.0023 / cap;
    const double size = p.cells * cap;  // cell·Ah: mass and heat capacity scale with it
    if (p.heat_capacity_j_per_k < 0.0) p.heat_capacity_j_per_k = 30.6 * size;
    if (p.conductance_ground_w_per_k < 0.0) p.conductance_ground_w_per_k = 0.4 * pow23(size / 6.2);
    if (p.conductance_flight_w_per_k < 0.0) p.conductance_flight_w_per_k = 1.6 * pow23(size / 6.2);
    if (s.profile.mean_power_w <= 0.0) {
        const double per_cell = s.profile.kind == FlightKind::Racing ? 90.0 : 35.0;
        s.profile.mean_power_w = per_cell * p.cells * cap / 1.55;
    }
    if (!s.initial_temperature_given) s.initial_temperature_c = s.ambient_c;
}

std::string log_format_problem(const std::string& format, int cells) {
    SimLogFormat parsed;
    if (format != "auto" && !parse_sim_log_format(format, parsed)) {
        std::string names = "\"auto\"";
        const std::vector<std::string> others = sim_log_format_names();
        for (size_t i = 0; i < others.size(); ++i)
            names += (i + 1 == others.size() ? " or \"" : ", \"") + others[i] + "\"";
        return "expected " + names + ", found \"" + format + "\"";
    }
    if (format == "raw" && cells != 4)
        return "the raw logger format has exactly 4 cells; use \"csv\" for " + std::to_string(cells) + " cells";
    return std::string();
}

std::string override_log_format(std::vector<Scenario>& scenarios, const std::string& format) {
    if (format.empty()) return std::string();
    for (const Scenario& s : scenarios) {
        const std::string problem = log_format_problem(format, s.pack.cells);
        if (!problem.empty()) return s.source_path + ": " + problem;
    }
    for (Scenario& s : scenarios) s.log_format = format;
    return std::string();
}

std::string log_interval_note(const Scenario& s) {
    if (!s.log_interval_given || log_format_of(s) == SimLogFormat::Radio) return std::string();
    std::ostringstream m;
    m << "log.interval_s (" << s.log_interval_s << " s) is the edgetx radio log's interval; the "
      << sim_log_format_name(log_format_of(s))
      << " log ignores it (every sensor read is a row, or the autopilot's own rate) and the truth leaves it out";
    return m.str();
}

SimLogFormat log_format_of(const Scenario& s) {
    SimLogFormat format;
    if (parse_sim_log_format(s.log_format, format)) return format;
    return s.pack.cells == 4 ? SimLogFormat::Raw : SimLogFormat::Csv;
}

PlantParams make_plant_params(const Scenario& s, bool healthy) {
    const PackSpec& p = s.pack;
    PlantParams pp;
    pp.cells = p.cells;
    pp.activation_energy_j_per_mol = p.activation_energy_j_per_mol;
    pp.heat_capacity_j_per_k = p.heat_capacity_j_per_k;
    pp.conductance_ground_w_per_k = p.conductance_ground_w_per_k;
    pp.conductance_flight_w_per_k = p.conductance_flight_w_per_k;
    pp.ambient_c = s.ambient_c;
    // Cell spread from its own stream, drawn the same way for the healthy twin.
    Rng rng = Rng::stream(s.seed, 21);
    for (int c = 0; c < p.cells; ++c) {
        const auto draw = [&rng](double sd) {
            double z = rng.normal();
            z = z > 3.0 ? 3.0 : (z < -3.0 ? -3.0 : z);  // no negative capacities from a far tail
            return 1.0 + sd * z;
        };
        const double cap_mult = draw(p.capacity_spread);
        const double r_mult = draw(p.resistance_spread);
        CellParams& cp = pp.cell[c];
        cp.capacity_ah = p.capacity_ah * cap_mult;
        cp.r0_ohm = p.r0_ohm * r_mult;
        cp.r1_ohm = p.r1_ohm * r_mult;
        cp.r2_ohm = p.r2_ohm * r_mult;
        cp.tau1_s = p.tau1_s;
        cp.tau2_s = p.tau2_s;
        if (!healthy) {
            cp.capacity_ah *= p.capacity_factor;
            cp.r0_ohm *= p.resistance_factor;
            cp.r1_ohm *= p.resistance_factor;
            cp.r2_ohm *= p.resistance_factor;
        }
    }
    if (!healthy) {
        for (const WeakCell& w : p.weak_cells) {
            CellParams& cp = pp.cell[w.cell - 1];
            cp.capacity_ah *= w.capacity_factor;
            cp.r0_ohm *= w.resistance_factor;
            cp.r1_ohm *= w.resistance_factor;
            cp.r2_ohm *= w.resistance_factor;
        }
    }
    return pp;
}

Scenario scenario_from_json(const json& j, const std::string& origin, const std::string& base_dir,
                            const json* config_json) {
    Scenario s;
    s.source_path = origin;
    s.profile.mean_power_w = 0.0;  // derived unless given
    Reader root(j, "$", origin);
    std::string schema = kSchema;
    int version = kVersion;
    // Required, as documented: a file without them had been read as a scenario whatever it was.
    if (!root.string("schema", schema)) root.fail("$.schema", "missing: expected \"" + std::string(kSchema) + "\"");
    if (!root.integer("version", version, 0, 1000000)) root.fail("$.version", "missing: expected " + std::to_string(kVersion));
    if (schema != kSchema) root.fail("$.schema", "expected \"" + std::string(kSchema) + "\", found \"" + schema + "\"");
    if (version != kVersion) root.fail("$.version", "expected " + std::to_string(kVersion) + ", found " + std::to_string(version));
    if (!root.string("name", s.name) || s.name.empty()) root.fail("$.name", "expected a non-empty name");
    for (char ch : s.name) {
        if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.'))
            root.fail("$.name", "expected letters, digits, '-', '_' or '.' only (it names output files), found \"" + s.name + "\"");
    }
    root.string("description", s.description);
    root.seed("seed", s.seed);
    if (!root.string("monitor_config", s.monitor_config) || s.monitor_config.empty())
        root.fail("$.monitor_config", "expected the path of the monitor config for this pack");

    if (const json* v = root.find("pack")) {
        Reader r(*v, "$.pack", origin);
        PackSpec& p = s.pack;
        read_pack(r, p);
        if (const json* w = r.find("weak_cells")) {
            if (!w->is_array()) r.fail("$.pack.weak_cells", "expected an array of {cell, capacity_factor, resistance_factor}");
            for (size_t i = 0; i < w->size(); ++i) {
                Reader e((*w)[i], "$.pack.weak_cells[" + std::to_string(i) + "]", origin);
                WeakCell wc;
                if (!e.integer("cell", wc.cell, 1, p.cells))
                    e.fail("$.pack.weak_cells[" + std::to_string(i) + "].cell", "expected the cell number (1-based)");
                e.number("capacity_factor", wc.capacity_factor, 0.05, 2.0);
                e.number("resistance_factor", wc.resistance_factor, 0.1, 20.0);
                e.finish();
                // A second entry for one cell had multiplied the factors (0.8 × 0.5) unseen.
                for (const WeakCell& earlier : p.weak_cells)
                    if (earlier.cell == wc.cell)
                        e.fail("$.pack.weak_cells[" + std::to_string(i) + "].cell",
                               "cell " + std::to_string(wc.cell) + " is given twice; give each weak cell once");
                p.weak_cells.push_back(wc);
            }
        }
        r.finish();
    }
    if (const json* v = root.find("environment")) {
        Reader r(*v, "$.environment", origin);
        r.number("ambient_c", s.ambient_c, -40.0, 70.0);
        s.initial_temperature_given = r.number("initial_temperature_c", s.initial_temperature_c, -40.0, 80.0);
        r.finish();
    }
    if (const json* v = root.find("profile")) {
        Reader r(*v, "$.profile", origin);
        ProfileParams& p = s.profile;
        std::string kind = to_string(p.kind);
        r.string("kind", kind);
        if (kind == "racing") p.kind = FlightKind::Racing;
        else if (kind == "hover") p.kind = FlightKind::Hover;
        else r.fail("$.profile.kind", "expected \"racing\" or \"hover\", found \"" + kind + "\"");
        r.number("idle_before_s", p.idle_before_s, 0.0, 3600.0);
        r.number("armed_s", p.armed_s, 0.0, 600.0);
        r.number("flight_s", p.flight_s, 1.0, 36000.0);
        r.number("idle_after_s", p.idle_after_s, 0.0, 3600.0);
        r.number("idle_power_w", p.idle_power_w, 0.0, 1000.0);
        r.number("armed_power_w", p.armed_power_w, 0.0, 5000.0);
        r.number("mean_power_w", p.mean_power_w, 1.0, 100000.0);
        r.integer("lap_segments", p.lap_segments, 1, 64);
        r.number("level_sd", p.level_sd, 0.0, 2.0);
        r.number("level_max_ratio", p.level_max_ratio, 1.0, 20.0);
        r.number("min_segment_s", p.min_segment_s, 0.05, 600.0);
        r.number("max_segment_s", p.max_segment_s, 0.05, 600.0);
        r.number("lap_jitter", p.lap_jitter, 0.0, 0.5);
        r.number("takeoff_boost_s", p.takeoff_boost_s, 0.0, 600.0);
        r.number("gust_sd", p.gust_sd, 0.0, 0.5);
        r.number("gust_time_s", p.gust_time_s, 0.1, 600.0);
        r.number("response_s", p.response_s, 0.0, 10.0);
        if (p.max_segment_s < p.min_segment_s) r.fail("$.profile.max_segment_s", "must not be below min_segment_s");
        r.finish();
    }
    if (const json* v = root.find("sensor")) {
        Reader r(*v, "$.sensor", origin);
        SensorParams& p = s.sensor;
        r.number("period_ms", p.period_ms, 1.0, 10000.0);
        r.number("tap_period_ms", p.tap_period_ms, 1.0, 10000.0);
        r.number("first_read_ms", p.first_read_ms, 0.0, 600000.0);
        r.number("latency_max_ms", p.latency_max_ms, 0.1, 1000.0);
        r.number("late_read_rate_per_s", p.late_read_rate_per_s, 0.0, 100.0);
        r.number("stall_rate_per_s", p.stall_rate_per_s, 0.0, 10.0);
        r.number("stall_first_min_s", p.stall_first_min_s, 0.0, 60.0);
        r.number("stall_first_max_s", p.stall_first_max_s, 0.0, 60.0);
        r.integer("stall_more_max", p.stall_more_max, 0, 100);
        r.number("bus_noise_v", p.bus_noise_v, 0.0, 1.0);
        r.number("shunt_noise_mv", p.shunt_noise_mv, 0.0, 10.0);
        r.number("tap_noise_v", p.tap_noise_v, 0.0, 1.0);
        r.number("temperature_noise_c", p.temperature_noise_c, 0.0, 10.0);
        r.number("bus_gain_sd", p.bus_gain_sd, 0.0, 0.1);
        r.number("tap_gain_sd", p.tap_gain_sd, 0.0, 0.1);
        r.number("tap_offset_sd_v", p.tap_offset_sd_v, 0.0, 1.0);
        r.number("ground_lead_ohm", p.ground_lead_ohm, 0.0, 0.1);
        r.number("bus_lead_ohm", p.bus_lead_ohm, 0.0, 0.1);
        if (p.stall_first_max_s < p.stall_first_min_s) r.fail("$.sensor.stall_first_max_s", "must not be below stall_first_min_s");
        if (const json* u = r.find("unit")) {
            Reader ru(*u, "$.sensor.unit", origin);
            p.unit_given = true;
            ru.number("bus_gain_error", p.unit.bus_gain_error, -0.1, 0.1);
            const auto list = [&](const char* key, double* out, double lim) {
                if (const json* a = ru.find(key)) {
                    if (!a->is_array() || a->size() + 1 != static_cast<size_t>(s.pack.cells))
                        ru.fail(ru.at(key), "expected an array of " + std::to_string(s.pack.cells - 1) + " numbers (one per tap)");
                    for (size_t i = 0; i < a->size(); ++i) {
                        const json& x = (*a)[i];
                        if (!x.is_number() || !(std::fabs(x.get<double>()) <= lim))
                            ru.fail(ru.at(key) + "[" + std::to_string(i) + "]", "expected a number within ±" + std::to_string(lim));
                        out[i] = x.get<double>();
                    }
                }
            };
            list("tap_gain_error", p.unit.tap_gain_error, 0.1);
            list("tap_offset_v", p.unit.tap_offset_v, 1.0);
            ru.finish();
        }
        if (const json* f = r.find("faults")) {
            Reader rf(*f, "$.sensor.faults", origin);
            SensorFaults& q = p.faults;
            rf.number("current_offset_a", q.current_offset_a, -100.0, 100.0);
            rf.number("current_gain_error", q.current_gain_error, -0.9, 5.0);
            rf.integer("loose_tap", q.loose_tap, 0, s.pack.cells - 1);
            rf.number("loose_contact_mean_s", q.loose_contact_mean_s, 0.01, 1e6);
            rf.number("loose_ground_factor", q.loose_ground_factor, 0.01, 1e6);
            rf.number("loose_open_mean_s", q.loose_open_mean_s, 0.001, 1e6);
            rf.number("missed_probability", q.missed_probability, 0.0, 0.9);
            rf.number("missed_burst_rate_per_min", q.missed_burst_rate_per_min, 0.0, 60.0);
            rf.number("missed_burst_min_s", q.missed_burst_min_s, 0.0, 600.0);
            rf.number("missed_burst_max_s", q.missed_burst_max_s, 0.0, 600.0);
            if (q.missed_burst_max_s < q.missed_burst_min_s) rf.fail("$.sensor.faults.missed_burst_max_s", "must not be below missed_burst_min_s");
            rf.finish();
        }
        r.finish();
    }
    bool cutoff_given = false;
    if (const json* v = root.find("truth")) {
        cutoff_given = v->is_object() && v->contains("cutoff_v_per_cell");
        Reader r(*v, "$.truth", origin);
        r.number("cutoff_v_per_cell", s.cutoff_v_per_cell, 2.0, 4.5);
        r.number("cutoff_filter_s", s.cutoff_filter_s, 0.0, 600.0);
        r.number("decimation_s", s.decimation_s, 0.01, 600.0);
        r.number("step_s", s.step_s, 0.0002, 0.02);
        r.number("max_continuation_s", s.max_continuation_s, 1.0, 86400.0);
        r.finish();
    }
    if (const json* v = root.find("log")) {
        Reader r(*v, "$.log", origin);
        r.string("format", s.log_format);
        const std::string problem = log_format_problem(s.log_format, s.pack.cells);
        if (!problem.empty()) r.fail("$.log.format", problem);
        s.log_interval_given = r.number("interval_s", s.log_interval_s, 0.05, 60.0);
        r.finish();
    }
    root.finish();
    for (const WeakCell& w : s.pack.weak_cells) {
        if (w.cell > s.pack.cells) root.fail("$.pack.weak_cells", "cell " + std::to_string(w.cell) + " does not exist");
    }

    // The monitor config this pack is judged with.
    fs::path cfg = s.monitor_config;
    if (cfg.is_relative() && !base_dir.empty()) cfg = fs::path(base_dir) / cfg;
    s.monitor_config_path = cfg.lexically_normal().string();
    try {
        s.config = config_json ? config_from_json(*config_json, origin + " (embedded monitor config)")
                               : load_config_file(s.monitor_config_path);
    } catch (const ConfigError& e) {
        // An embedded config's paths are paths in this scenario; a config file's message
        // already names its own file, line and column.
        if (config_json && e.has_path())
            throw ScenarioError(origin, "$.monitor_config" + e.where().substr(1), e.detail(), e.at_key());
        throw ScenarioError(origin, "$.monitor_config", e.what());
    }
    if (s.config.monitor.cells_in_series != s.pack.cells) {
        throw ScenarioError(origin, "$.monitor_config",
                            "the config is for " + std::to_string(s.config.monitor.cells_in_series) +
                                " cells, the pack has " + std::to_string(s.pack.cells));
    }
    if (!cutoff_given) {
        // The truth runs to the cutoff the monitor is asked about: a fixed one graded every
        // column against a flight of another length than the one it predicts.
        const double v = static_cast<double>(s.config.monitor.flight_time.min_flight_voltage_v) / s.pack.cells;
        if (!(v >= 2.0 && v <= 4.5)) {
            throw ScenarioError(origin, "$.monitor_config",
                                "its min_flight_voltage_v gives " + std::to_string(v) +
                                    " V per cell as the truth's cutoff, outside 2..4.5; set $.truth.cutoff_v_per_cell");
        }
        s.cutoff_v_per_cell = v;
    }
    resolve_defaults(s);
    // The reference sensors' ranges: the INA226 bus reads up to 40.96 V and each INA3221 tap
    // up to 32.76 V; beyond, every reading clips and the log is wrong without a word.
    constexpr double kFullCellV = 4.2, kMaxBusV = 40.96, kMaxTapV = 32.76;
    if (s.pack.cells * kFullCellV > kMaxBusV || (s.pack.cells - 1) * kFullCellV > kMaxTapV)
        throw ScenarioError(origin, "$.pack.cells",
                            std::to_string(s.pack.cells) + " cells read up to " + std::to_string(s.pack.cells * kFullCellV) +
                                " V, beyond the reference sensors' 40.96 V bus and 32.76 V taps: they would clip; at most 8 cells");
    // The pack's temperature is stepped forward explicitly: a step longer than half its
    // thermal time constant (heat capacity / conductance) oscillates and runs away.
    const double g = std::max(s.pack.conductance_ground_w_per_k, s.pack.conductance_flight_w_per_k);
    if (s.step_s * g > 0.5 * s.pack.heat_capacity_j_per_k)
        throw ScenarioError(origin, "$.pack.heat_capacity_j_per_k",
                            "the pack's thermal time constant (heat capacity " + std::to_string(s.pack.heat_capacity_j_per_k) +
                                " J/K over conductance " + std::to_string(g) + " W/K) is under twice the step of " +
                                std::to_string(s.step_s) + " s: the temperature would run away; raise the heat capacity or "
                                "lower the conductance or the step");
    return s;
}

Scenario load_scenario(const std::string& path) {
    std::string text;
    const json j = load_json_document<ScenarioError>(path, "scenario file", "a scenario JSON object", text);
    const std::string base = fs::path(path).parent_path().string();
    try {
        return scenario_from_json(j, path, base);
    } catch (const ScenarioError& e) {
        throw located(e, JsonLocator(text));
    }
}

json scenario_to_json(const Scenario& s) {
    const PackSpec& p = s.pack;
    json weak = json::array();
    for (const WeakCell& w : p.weak_cells)
        weak.push_back({{"cell", w.cell}, {"capacity_factor", w.capacity_factor}, {"resistance_factor", w.resistance_factor}});
    const ProfileParams& f = s.profile;
    const SensorParams& q = s.sensor;
    json j;
    j["schema"] = kSchema;
    j["version"] = kVersion;
    j["name"] = s.name;
    if (!s.description.empty()) j["description"] = s.description;
    j["seed"] = s.seed;
    j["monitor_config"] = s.monitor_config;
    j["pack"] = {{"cells", p.cells},
                 {"capacity_ah", p.capacity_ah},
                 {"r0_ohm", p.r0_ohm},
                 {"r1_ohm", p.r1_ohm},
                 {"r2_ohm", p.r2_ohm},
                 {"tau1_s", p.tau1_s},
                 {"tau2_s", p.tau2_s},
                 {"capacity_spread", p.capacity_spread},
                 {"resistance_spread", p.resistance_spread},
                 {"capacity_factor", p.capacity_factor},
                 {"resistance_factor", p.resistance_factor},
                 {"weak_cells", weak},
                 {"initial_soc", p.initial_soc},
                 {"activation_energy_j_per_mol", p.activation_energy_j_per_mol},
                 {"heat_capacity_j_per_k", p.heat_capacity_j_per_k},
                 {"conductance_ground_w_per_k", p.conductance_ground_w_per_k},
                 {"conductance_flight_w_per_k", p.conductance_flight_w_per_k}};
    j["environment"] = {{"ambient_c", s.ambient_c}, {"initial_temperature_c", s.initial_temperature_c}};
    j["profile"] = {{"kind", to_string(f.kind)},
                    {"idle_before_s", f.idle_before_s},
                    {"armed_s", f.armed_s},
                    {"flight_s", f.flight_s},
                    {"idle_after_s", f.idle_after_s},
                    {"idle_power_w", f.idle_power_w},
                    {"armed_power_w", f.armed_power_w},
                    {"mean_power_w", f.mean_power_w},
                    {"lap_segments", f.lap_segments},
                    {"level_sd", f.level_sd},
                    {"level_max_ratio", f.level_max_ratio},
                    {"min_segment_s", f.min_segment_s},
                    {"max_segment_s", f.max_segment_s},
                    {"lap_jitter", f.lap_jitter},
                    {"takeoff_boost_s", f.takeoff_boost_s},
                    {"gust_sd", f.gust_sd},
                    {"gust_time_s", f.gust_time_s},
                    {"response_s", f.response_s}};
    json sensor = {{"period_ms", q.period_ms},
                   {"tap_period_ms", q.tap_period_ms},
                   {"first_read_ms", q.first_read_ms},
                   {"latency_max_ms", q.latency_max_ms},
                   {"late_read_rate_per_s", q.late_read_rate_per_s},
                   {"stall_rate_per_s", q.stall_rate_per_s},
                   {"stall_first_min_s", q.stall_first_min_s},
                   {"stall_first_max_s", q.stall_first_max_s},
                   {"stall_more_max", q.stall_more_max},
                   {"bus_noise_v", q.bus_noise_v},
                   {"shunt_noise_mv", q.shunt_noise_mv},
                   {"tap_noise_v", q.tap_noise_v},
                   {"temperature_noise_c", q.temperature_noise_c},
                   {"bus_gain_sd", q.bus_gain_sd},
                   {"tap_gain_sd", q.tap_gain_sd},
                   {"tap_offset_sd_v", q.tap_offset_sd_v}};
    if (q.ground_lead_ohm > 0.0) sensor["ground_lead_ohm"] = q.ground_lead_ohm;  // omitted at its default of 0
    if (q.bus_lead_ohm > 0.0) sensor["bus_lead_ohm"] = q.bus_lead_ohm;
    if (q.unit_given) {
        json gains = json::array(), offsets = json::array();
        for (int k = 0; k + 1 < p.cells; ++k) {
            gains.push_back(q.unit.tap_gain_error[k]);
            offsets.push_back(q.unit.tap_offset_v[k]);
        }
        sensor["unit"] = {{"bus_gain_error", q.unit.bus_gain_error}, {"tap_gain_error", gains}, {"tap_offset_v", offsets}};
    }
    const SensorFaults& x = q.faults;
    sensor["faults"] = {{"current_offset_a", x.current_offset_a},
                        {"current_gain_error", x.current_gain_error},
                        {"loose_tap", x.loose_tap},
                        {"loose_contact_mean_s", x.loose_contact_mean_s},
                        {"loose_ground_factor", x.loose_ground_factor},
                        {"loose_open_mean_s", x.loose_open_mean_s},
                        {"missed_probability", x.missed_probability},
                        {"missed_burst_rate_per_min", x.missed_burst_rate_per_min},
                        {"missed_burst_min_s", x.missed_burst_min_s},
                        {"missed_burst_max_s", x.missed_burst_max_s}};
    j["sensor"] = sensor;
    j["truth"] = {{"cutoff_v_per_cell", s.cutoff_v_per_cell},
                  {"cutoff_filter_s", s.cutoff_filter_s},
                  {"decimation_s", s.decimation_s},
                  {"step_s", s.step_s},
                  {"max_continuation_s", s.max_continuation_s}};
    j["log"] = {{"format", s.log_format}};
    if (s.log_format == "edgetx") j["log"]["interval_s"] = s.log_interval_s;
    return j;
}

std::vector<std::string> find_scenario_files(const std::vector<std::string>& paths) {
    std::vector<std::string> out;
    for (const std::string& p : paths) {
        std::error_code ec;
        const fs::file_status st = fs::status(p, ec);
        if (ec || !fs::exists(st)) throw ScenarioError(p + ": no such scenario file or directory");
        if (fs::is_directory(st)) {
            std::vector<std::string> found;
            for (const auto& e : fs::directory_iterator(p)) {
                if (e.is_regular_file() && e.path().extension() == ".json") found.push_back(e.path().string());
            }
            std::sort(found.begin(), found.end());
            if (found.empty()) throw ScenarioError(p + ": the directory holds no *.json scenario files");
            out.insert(out.end(), found.begin(), found.end());
        } else {
            out.push_back(p);
        }
    }
    if (out.empty()) throw ScenarioError("no scenario files given");
    return out;
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
