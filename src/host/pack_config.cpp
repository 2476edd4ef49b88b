#include "host/pack_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <stdexcept>

#include "core/config.h"
#include "host/config_json.h"

namespace battsim {
namespace host {
namespace {

using json = nlohmann::json;

// The reference pack, per cell and per rated amp-hour (configs/sim-4s.json: 4S, 1.55 Ah).
constexpr double kRefCapacityAh = 1.55;
constexpr int kRefCells = 4;
constexpr double kFullV = 4.2, kExponentialV = 3.815, kNominalZoneV = 3.6875, kNominalV = 3.7, kMinV = 3.325;
constexpr double kExponentialAh = 0.3, kNominalZoneAh = 1.5;  // at the reference capacity
constexpr double kCellResistanceOhm = 0.005;                   // at the reference capacity
constexpr double kCurveCurrentA = 7.0;                          // the curve's C-rate is kept
constexpr double kVarianceV = 0.05, kAveragePowerW = 79.0, kMaxPackV = 5.25;
constexpr double kCutoffDelayS = 5.0;
constexpr double kGroundPowerW = 3.0;  // a small craft's electronics on the ground, at most
// The estimators' current thresholds (their defaults are the core's, set for the reference
// pack) and the power of the pack's size they scale with (a bar on squared currents: 2). The
// ground's and the rest's bars are set apart, with the take-off bar.
struct CurrentKey {
    const char* key;
    int power;
};
constexpr CurrentKey kJointCurrentKeys[] = {
    {"offset_fault_a", 1},           {"resistance_min_step_a", 1},        {"resistance_min_excitation_a2", 2},
    {"hover_resistance_min_step_a", 1}, {"hover_resistance_min_excitation_a2", 2}, {"cell_min_charge_ah", 1},
    {"cell_current_ridge_a2", 2},    {"cell_slow_current_ridge_a2", 2},   {"cell_step_min_a", 1},
    {"cell_step_band_a", 1},         {"cell_resistance_min_step_a", 1},   {"cell_resistance_min_excitation_a2", 2},
};
// The simulator's healthy LiPo cell at rest, empty to full in 5 % steps (read off a C/5
// discharge by scripts/suite-ocv-tables.py; normalised to the rated capacity).
constexpr double kOcvCellV[] = {3.3271, 3.5607, 3.6542, 3.6925, 3.7166, 3.7358, 3.7506, 3.7655, 3.7803, 3.7952, 3.8105,
                                3.8302, 3.8503, 3.8749, 3.9009, 3.9296, 3.9605, 3.9951, 4.035,  4.0898, 4.1999};
// A Li-ion cell, per cell and per rated amp-hour: the Samsung INR18650-30Q of the shared lab
// data, its curve read off the C/10 discharge (`battsim discharge
// ../shared/data/samsung-30q/Q30_S001_C10.csv --negative-discharge -c ONE_CELL.json
// --config-out X.json`, ONE_CELL from `make-config --cells 1 --capacity-mah 3000 --cutoff-v
// 2.5`: 2.969 Ah, I*R added back) and its resistance from `battsim fit` (29.2 mOhm at 3.04 Ah,
// configs/fitted/samsung-30q.json). Empty at 2.5 V, where the discharges stop; flown to 3.0 V
// per cell under load by default, where long-range pilots land.
constexpr double kLiIonOcvCellV[] = {2.5082, 2.9791, 3.1627, 3.3006, 3.4072, 3.4637, 3.5169, 3.5774, 3.6159, 3.6544, 3.6996,
                                     3.7442, 3.788,  3.8336, 3.8791, 3.9255, 3.9832, 4.0334, 4.0516, 4.07,   4.1417};
constexpr double kLiIonFullV = 4.1419, kLiIonExponentialV = 4.0877, kLiIonNominalZoneV = 3.4108, kLiIonNominalV = 3.6;
constexpr double kLiIonExponentialShare = 0.0211, kLiIonNominalZoneShare = 0.7955;  // of the capacity
constexpr double kLiIonEmptyV = 2.5, kLiIonCutoffV = 3.0;
constexpr double kLiIonCellOhmAh = 0.0885;  // 29.2 mOhm x 3.036 Ah
constexpr double kLiIonCurveCRate = 0.1;
// A per-cell cutoff outside this is not one anybody flies to: a typo or another unit.
constexpr double kCutoffMinV = 2.5, kCutoffMaxV = 3.9;
// Below this per cell a cutoff is a Li-ion pack's, not the LiPo's the config describes (whose
// rest curve ends at 3.33 V): from a log, more likely a level set for another cell count
// (ArduCopter 3's default LOW_VOLT, 10.5 V, is 3.5 V per cell on 3S and 2.62 V on 4S), and
// the remaining time runs to it. The band the level would fit as a LiPo's loaded cutoff:
constexpr double kLipoCutoffMinV = 3.0, kLipoCutoffLowV = 3.2, kLipoCutoffHighV = 3.7;
// Where a charged or part-charged lithium cell rests, and the part of it a pack takes off from.
constexpr double kRestMinCellV = 3.45, kTakeoffRestMinCellV = 3.6, kRestMaxCellV = 4.40;

// Rounded so the file reads like a hand-written one and the same rating gives the same bytes.
// v to a multiple of step, as the nearest double to its decimal text: 15.26, not the
// 15.260000000000002 that round(v / step) * step leaves in the written config.
double round_to(double v, double step) {
    const double r = std::round(v / step);
    const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, r * step);
    return std::strtod(buf, nullptr);
}

// v to `digits` significant digits (values of any size, e.g. 3.666e-05), as round_to does.
double round_significant(double v, int digits) {
    if (!(v != 0.0) || !std::isfinite(v)) return v;
    return round_to(v, std::pow(10.0, std::floor(std::log10(std::fabs(v))) - (digits - 1)));
}

std::string number_text(double v, const char* format) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

// The first positive value among `names` (an autopilot marks "unset" with 0 or -1).
bool first_positive(const SourceInfo& info, std::initializer_list<const char*> names, double* value, std::string* from) {
    for (const char* name : names) {
        const double v = log_parameter(info, name);
        if (std::isfinite(v) && v > 0.0) {
            *value = v;
            *from = std::string(name) + " " + number_text(v, "%g");
            return true;
        }
    }
    return false;
}

// The one count whose per-cell voltage lies in [min_cell_v, max_cell_v]; 0 when none or more.
int only_count_between(double voltage_v, double min_cell_v, double max_cell_v) {
    int found = 0;
    for (int n = 1; n <= core::kMaxCells; ++n) {
        const double per_cell_v = voltage_v / n;
        if (per_cell_v >= min_cell_v && per_cell_v <= max_cell_v) {
            if (found != 0) return 0;  // two counts fit: the voltage cannot tell
            found = n;
        }
    }
    return found;
}

}  // namespace

int cells_from_resting_voltage(double voltage_v) {
    if (!(voltage_v > 0.0) || !std::isfinite(voltage_v)) return 0;
    // A pack resting below 3.6 V per cell is nearly empty, and nobody takes off with one:
    // a count that puts it there loses to one in the take-off band (the Matrice 100 at
    // 24.22 V is 4.04 V per cell as 6S; as 7S, 3.46 V, it had made the count a tie).
    if (const int n = only_count_between(voltage_v, kTakeoffRestMinCellV, kRestMaxCellV)) return n;
    return only_count_between(voltage_v, kRestMinCellV, kRestMaxCellV);
}

json pack_config_json(const PackRating& r) {
    if (r.cells < 1 || r.cells > core::kMaxCells)
        throw std::invalid_argument("cells: expected 1.." + std::to_string(core::kMaxCells) + ", found " + std::to_string(r.cells));
    if (!(r.capacity_ah >= 0.05 && r.capacity_ah <= 1000.0))
        throw std::invalid_argument("capacity: expected 50 mAh .. 1000 Ah, found " + number_text(r.capacity_ah * 1000.0, "%g mAh"));
    if (std::isfinite(r.resistance_ohm) && !(r.resistance_ohm > 0.0 && r.resistance_ohm <= 10.0))
        throw std::invalid_argument("resistance: expected above 0 and at most 10 ohm, found " + number_text(r.resistance_ohm, "%g ohm"));
    const double n = r.cells;
    if (std::isfinite(r.cutoff_voltage_v) && !(r.cutoff_voltage_v / n >= kCutoffMinV && r.cutoff_voltage_v / n <= kCutoffMaxV))
        throw std::invalid_argument("cutoff: expected " + number_text(kCutoffMinV, "%.1f") + ".." + number_text(kCutoffMaxV, "%.1f") +
                                    " V per cell, found " + number_text(r.cutoff_voltage_v / n, "%.4g V") +
                                    " (it is the pack's voltage: " + std::to_string(r.cells) + " cells x the per-cell figure)");
    if (std::isfinite(r.cutoff_delay_s) && !(r.cutoff_delay_s >= 0.0 && r.cutoff_delay_s <= 600.0))
        throw std::invalid_argument("cutoff delay: expected 0..600 s, found " + number_text(r.cutoff_delay_s, "%g s"));

    if (r.chemistry != "lipo" && r.chemistry != "li-ion")
        throw std::invalid_argument("chemistry: expected lipo or li-ion, found \"" + r.chemistry + "\"");
    const bool li_ion = r.chemistry == "li-ion";
    const double k = r.capacity_ah / kRefCapacityAh;
    const double resistance_ohm =
        std::isfinite(r.resistance_ohm) ? r.resistance_ohm
        : li_ion                        ? round_to(kLiIonCellOhmAh * n / r.capacity_ah, 1e-5)
                                        : round_to(kCellResistanceOhm * n / k, 1e-5);
    const double cutoff_v = std::isfinite(r.cutoff_voltage_v) ? r.cutoff_voltage_v : (li_ion ? kLiIonCutoffV : kMinV) * n;
    const long mah = std::lround(r.capacity_ah * 1000.0);
    std::string description = std::to_string(r.cells) + "S " + std::to_string(mah) +
                              (li_ion ? " mAh lithium-ion pack" : " mAh lithium polymer pack") + ", written by battsim make-config";
    if (!r.sources.empty()) {
        description += " (";
        for (size_t i = 0; i < r.sources.size(); ++i) description += (i ? "; " : "") + r.sources[i];
        description += ")";
    }
    description +=
        ": the reference pack (configs/sim-4s.json) scaled per cell and by capacity (capacities x capacity, resistance "
        "/ capacity unless given, the curve's current at the same C-rate; below 1.55 Ah the estimators' current "
        "thresholds too, the take-off bar no lower than 3 W of ground electronics; below 4S the filters' voltage sigma "
        "per cell; the filters' polarisation ohms with the pack's resistance, their spread with its square root), ";
    description += li_ion ? "with a Li-ion cell's curve, OCV table and resistance per Ah (88.5 mOhm Ah per cell): the Samsung "
                            "INR18650-30Q's, read off its C/10 discharge to 2.5 V; cutoff 3.0 V per cell. Another cell's "
                            "curve lies tens of mV away: read your own off a slow discharge (battsim discharge)."
                          : "with the simulator's LiPo rest curve as the OCV table.";
    description += " Not fitted to this pack: battsim fit, fit-ocv and calibrate make it its own.";

    json battery = li_ion ? json{
        {"cells_in_series", r.cells},
        {"full_voltage_v", round_to(kLiIonFullV * n, 1e-4)},
        {"exponential_voltage_v", round_to(kLiIonExponentialV * n, 1e-4)},
        {"exponential_capacity_ah", round_to(kLiIonExponentialShare * r.capacity_ah, 1e-4)},
        {"nominal_zone_voltage_v", round_to(kLiIonNominalZoneV * n, 1e-4)},
        {"nominal_zone_capacity_ah", round_to(kLiIonNominalZoneShare * r.capacity_ah, 1e-4)},
        {"capacity_ah", round_to(r.capacity_ah, 1e-4)},
        {"internal_resistance_ohm", resistance_ohm},
        {"curve_current_a", round_to(kLiIonCurveCRate * r.capacity_ah, 1e-3)},
        {"nominal_voltage_v", round_to(kLiIonNominalV * n, 1e-4)},
        {"max_voltage_v", round_to(kFullV * n, 1e-4)},
        {"min_voltage_v", round_to(std::min(kLiIonEmptyV * n, cutoff_v), 1e-4)},
    } : json{
        {"cells_in_series", r.cells},
        {"full_voltage_v", round_to(kFullV * n, 1e-4)},
        {"exponential_voltage_v", round_to(kExponentialV * n, 1e-4)},
        {"exponential_capacity_ah", round_to(kExponentialAh * k, 1e-4)},
        {"nominal_zone_voltage_v", round_to(kNominalZoneV * n, 1e-4)},
        {"nominal_zone_capacity_ah", round_to(kNominalZoneAh * k, 1e-4)},
        {"capacity_ah", round_to(r.capacity_ah, 1e-4)},
        {"internal_resistance_ohm", resistance_ohm},
        {"curve_current_a", round_to(kCurveCurrentA * k, 1e-3)},
        {"nominal_voltage_v", round_to(kNominalV * n, 1e-4)},
        {"max_voltage_v", round_to(kFullV * n, 1e-4)},
        // The curve's floor no higher than the cutoff: a Li-ion pack flown to 2.5 V per cell
        // (and its bench discharge, which stops at this floor) had been cut at 3.325 V.
        {"min_voltage_v", round_to(std::min(kMinV * n, cutoff_v), 1e-4)},
    };
    json monitor = {
        {"reaction_time_s", 30},
        {"min_flight_voltage_v", round_to(cutoff_v, 1e-4)},
        {"capacity_step_fraction", 0.01},
        {"max_voltage_variance_v", round_to(kVarianceV * n, 1e-4)},
        {"variance_persistence_updates", 5},
        {"short_average_time_s", 180},
        {"long_average_time_s", 1800},
        // Only the first flight's guess before its own power is known: a bigger pack flies a bigger drone.
        {"remembered_average_power_w", round_to(kAveragePowerW * n * k, 0.1)},
        {"min_flying_current_a", 1.0},
        {"landed_hold_s", 1.0},
        {"takeoff_confirm_s", 0.5},
        {"max_resting_current_a", 1.0},
        {"stabilisation_time_s", 5.0},
    };
    json j = {
        {"schema", "battsim.config"},
        {"version", 1},
        {"name", r.name.empty() ? "pack-" + std::to_string(r.cells) + "s-" + std::to_string(mah) : r.name},
        {"description", description},
        {"estimator", "joint"},
        {"battery", battery},
        {"monitor", monitor},
        // The reference logger's shunt calibration (a raw log's shunt column only).
        {"sensor", {{"shunt_offset_ma", -982.8158579}, {"shunt_scale_mv_per_10a", 3.7834625},
                    {"max_pack_voltage_v", round_to(kMaxPackV * n, 1e-4)},
                    {"min_pack_voltage_v", round_to(kGlitchFloorCellV * n, 1e-4)}}},
        {"joint",
         {{"first_cell_includes_lead", true},
          {"cutoff_delay_s", std::isfinite(r.cutoff_delay_s) ? r.cutoff_delay_s : kCutoffDelayS},
          {"ocv_cell_voltage_v", li_ion ? json(kLiIonOcvCellV) : json(kOcvCellV)}}},
    };
    // A pack smaller than the reference flies a smaller drone at the same C-rates: the
    // estimators' current thresholds shrink with it. With the reference's 3 A as the ground's
    // bar, a 450 mAh pack hovering at 2.7 A never left "the ground" and its capacity was never
    // learnt (docs/estimator.md, thirty-ninth session). Larger packs keep the reference's bars,
    // which the Matrice 100's 4.5 Ah fleet was measured with.
    const double s = std::min(1.0, k);
    if (s < 1.0) {
        const json defaults = config_to_json(default_config())["joint"];
        for (const CurrentKey& c : kJointCurrentKeys)
            j["joint"][c.key] = round_to(defaults.at(c.key).get<double>() * std::pow(s, c.power), c.power == 2 ? 1e-2 : 1e-3);
        // What the electronics draw on the ground (flight controller, receiver, video) does
        // not shrink with the pack: the take-off bar stays above kGroundPowerW (a 1S pack
        // idling at 1.5 W, 0.39 A, under a 0.29 A bar had "taken off" 52 times in 5 minutes on
        // the ground), and the ground's bar only a quarter above it: a 1S racer's throttle
        // dips to 1.2 A, which under a 1.6 A bar had counted as ground and left its capacity
        // 25 % high at the landing.
        const double flying_a =
            round_to(std::max(j["monitor"]["min_flying_current_a"].get<double>() * s, kGroundPowerW / (kNominalV * n)), 1e-3);
        j["monitor"]["min_flying_current_a"] = flying_a;
        j["monitor"]["max_resting_current_a"] = flying_a;
        j["joint"]["rest_capacity_max_current_a"] = flying_a;
        j["joint"]["offset_learn_max_current_a"] =
            round_to(std::max(defaults.at("offset_learn_max_current_a").get<double>() * s, 1.25 * flying_a), 1e-3);
    }
    // The filters' voltage σ is the model's error, which is each cell's: a 1S pack's is a
    // quarter of the reference's in volts. At the 4S σ a 1S whoop's voltage was trusted a
    // quarter as much as it deserves and its capacity at 20 % of the flight stayed near the
    // rating (docs/estimator.md, fortieth session). Not raised for more cells: the defaults
    // were tuned on 3S, 4S and 6S flights alike, and 6S read no better at 1.5 x.
    if (r.cells < kRefCells) {
        const json defaults = config_to_json(default_config())["joint"];
        const double c = n / kRefCells;
        j["joint"]["voltage_sigma_v"] = round_to(defaults.at("voltage_sigma_v").get<double>() * c, 1e-5);
        for (const char* filter : {"health_filter", "verdict_filter"})
            j["joint"][filter]["voltage_sigma_v"] = round_to(defaults.at(filter).at("voltage_sigma_v").get<double>() * c, 1e-5);
    }
    // The filters' polarisation (its prior, spread and drift) is in ohms, set for the reference
    // pack's 20 mOhm. A pack's polarisation scales with its impedance (the simulator's branches
    // are fixed fractions of R0), so the prior scales with the pack's resistance; its spread and
    // drift by the square root, as a rating's resistance is a guess: at the full ratio the
    // ArduPilot log underpowered.log (3S 4 Ah, rated 5.8 mOhm, sagging like 61 mOhm, its R0
    // unmeasurable at 1 s samples) lost its filter. Left at the reference's ohms, an 8S 22 Ah
    // pack (2.8 mOhm) read every sag as charge gone: capacity at 20 % of a flight near the
    // rating at -25 %, 1 of 4 short flights warned (configs/scenarios-large/README.md).
    const double reference_ohm = kCellResistanceOhm * kRefCells;
    const double kr = resistance_ohm / reference_ohm;
    if (std::fabs(kr - 1.0) > 1e-3) {
        const json defaults = config_to_json(default_config())["joint"];
        for (const char* filter : {"", "health_filter", "verdict_filter"}) {
            const json& from = *filter ? defaults.at(filter) : defaults;
            json& to = *filter ? j["joint"][filter] : j["joint"];
            to["polarisation_initial_ohm"] = round_significant(from.at("polarisation_initial_ohm").get<double>() * kr, 4);
            for (const char* key : {"polarisation_sigma0_ohm", "polarisation_process_ohm_per_sqrt_s"})
                to[key] = round_significant(from.at(key).get<double>() * std::sqrt(kr), 4);
        }
    }
    config_from_json(j, "make-config");  // the same checks as any config file; throws ConfigError
    return j;
}

// The lead calibration belongs to the monitor's wiring, not to the pack.
const char* const kBoardKeys[11] = {"/sensor/shunt_offset_ma",
                                    "/sensor/shunt_scale_mv_per_10a",
                                    "/sensor/max_current_a",
                                    "/sensor/min_current_a",
                                    "/battery/extensions/current_sensor",
                                    "/joint/first_cell_includes_lead",
                                    "/joint/last_cell_includes_lead",
                                    "/joint/first_cell_lead_excess",
                                    "/joint/last_cell_lead_excess",
                                    "/joint/cell_lead_excess_sigma",
                                    "/telemetry"};

std::vector<std::string> apply_board(json& config, const LoadedConfig& board, std::vector<std::string>* left) {
    // Effective values on both sides: a config that leaves a key out means its default.
    const json from = config_to_json(board);
    const json was = config_to_json(config_from_json(config, "make-config"));
    // A lead cell's share is measured at one cell count: where the taps lag the bus it grows
    // with the cells below the last, so it is not carried to another.
    const bool other_cells = from.value(json::json_pointer("/battery/cells_in_series"), 0) !=
                             was.value(json::json_pointer("/battery/cells_in_series"), 0);
    std::vector<std::string> changed;
    for (const char* key : kBoardKeys) {
        const json::json_pointer at(key);
        std::string dotted = std::string(key).substr(1);
        std::replace(dotted.begin(), dotted.end(), '/', '.');
        if (other_cells && dotted.find("_lead_excess") != std::string::npos) {
            const bool share = dotted.find("sigma") == std::string::npos;
            if (share && left && from.contains(at) && from.at(at).is_number() && from.at(at).get<double>() >= 0.0)
                left->push_back(dotted);
            continue;
        }
        const bool has = from.contains(at);
        if (has == was.contains(at) && (!has || from.at(at) == was.at(at))) continue;
        if (has) {
            config[at] = from.at(at);
        } else if (config.contains(at)) {  // an optional section the board's config goes without
            config[at.parent_pointer()].erase(at.back());
        }
        changed.push_back(dotted);
    }
    config_from_json(config, "make-config");  // still a valid config; throws ConfigError
    return changed;
}

std::string per_cell_resistance_note(const PackRating& r) {
    if (r.cells < 2 || !std::isfinite(r.resistance_ohm) || !(r.capacity_ah > 0.0)) return "";
    // The reference LiPo scaled to this rating, per cell; a pack figure under 1.5 of those is
    // closer to one cell's than to the pack's.
    const double typical_cell_ohm = kCellResistanceOhm / (r.capacity_ah / kRefCapacityAh);
    if (r.resistance_ohm >= 1.5 * typical_cell_ohm) return "";
    return "--resistance-mohm is the whole pack's: " + number_text(r.resistance_ohm * 1e3, "%.3g") + " mOhm is " +
           number_text(r.resistance_ohm * 1e3 / r.cells, "%.2g") + " mOhm per cell on " + std::to_string(r.cells) +
           " cells, where the reference LiPo scaled to this rating has " + number_text(typical_cell_ohm * 1e3, "%.2g") +
           " mOhm per cell. If your charger showed it per cell, give the sum of the cells' (e.g. " + std::to_string(r.cells) +
           " x " + number_text(r.resistance_ohm * 1e3, "%.3g") + " = " +
           number_text(r.resistance_ohm * 1e3 * r.cells, "%.3g") + ")";
}

PackRating merge_rating(const PackRating& given, const LogPack& log) {
    PackRating r;
    r.name = given.name;
    r.chemistry = given.chemistry;
    if (given.cells > 0) {
        r.cells = given.cells;
        r.sources.push_back("cells given");
    } else if (log.cells > 0) {
        r.cells = log.cells;
        r.sources.push_back(std::to_string(log.cells) + " cells from " + log.cells_from);
    }
    const auto pick = [&r](double given_value, const char* given_text, double logged, const std::string& logged_from,
                           double* out) {
        if (std::isfinite(given_value)) {
            *out = given_value;
            r.sources.push_back(given_text);
        } else if (std::isfinite(logged)) {
            *out = logged;
            r.sources.push_back(logged_from);
        }
    };
    pick(given.capacity_ah, "capacity given", log.capacity_ah, "capacity from " + log.capacity_from, &r.capacity_ah);
    pick(given.resistance_ohm, "resistance given", log.resistance_ohm, "resistance from " + log.resistance_from,
         &r.resistance_ohm);
    pick(given.cutoff_voltage_v, "cutoff given", log.cutoff_voltage_v, "cutoff from " + log.cutoff_from,
         &r.cutoff_voltage_v);
    pick(given.cutoff_delay_s, "cutoff delay given", log.cutoff_delay_s, "cutoff delay from " + log.cutoff_delay_from,
         &r.cutoff_delay_s);
    return r;
}

LogPack log_pack(const SourceInfo& info, double resting_voltage_v, int cells_given) {
    LogPack p;
    double v = NAN;
    std::string from;
    // PX4 says how many cells; ArduPilot does not, and a log's cell columns do.
    const bool declared = first_positive(info, {"BAT1_N_CELLS", "BAT_N_CELLS"}, &v, &from);
    if (declared && v > core::kMaxCells) {
        // Not guessed from the voltage instead: a 14S pack at rest reads as 12 cells at 4.2 V.
        p.declared_cells_beyond = static_cast<int>(v);
        p.ignored.push_back(from + ": more cells than battsim handles (" +
                            std::to_string(core::kMaxCells) + ")");
    } else if (!declared && info.cells_beyond_kept > core::kMaxCells) {
        // Not the first twelve taken for the pack: a 14S log's config had been written as 12S.
        p.declared_cells_beyond = info.cells_beyond_kept;
        p.ignored.push_back("the log's " + std::to_string(info.cells_beyond_kept) + " cell voltages: more cells than battsim handles (" +
                            std::to_string(core::kMaxCells) + ")");
    } else if (declared) {
        p.cells = static_cast<int>(v);
        p.cells_from = "the log's " + from;
        p.cells_declared = true;
    } else if (info.cell_count > 0) {
        p.cells = info.cell_count;
        p.cells_from = "the log's " + std::to_string(info.cell_count) + " cell voltages";
    } else if (const int n = cells_from_resting_voltage(resting_voltage_v)) {
        p.cells = n;
        p.cells_from = "the pack resting at " + number_text(resting_voltage_v, "%.2f V") + " (" +
                       number_text(resting_voltage_v / n, "%.2f V") + " per cell)";
    }
    // A count given against a log that rests outside a lithium cell's band on it: said before
    // the config is written (replay said it only later, of every flight).
    if (cells_given > 0 && std::isfinite(resting_voltage_v) && resting_voltage_v > 0.0) {
        const double per_cell_v = resting_voltage_v / cells_given;
        if (per_cell_v < kRestMinCellV || per_cell_v > kRestMaxCellV) {
            std::string note = "the log's pack rests at " + number_text(resting_voltage_v, "%.2f V") + ", " +
                               number_text(per_cell_v, "%.2f V") + " per cell on the " + std::to_string(cells_given) +
                               " cells given, outside where a lithium cell rests (" + number_text(kRestMinCellV, "%.2f") +
                               "-" + number_text(kRestMaxCellV, "%.2f") + " V)";
            if (const int m = cells_from_resting_voltage(resting_voltage_v))
                note += "; on " + std::to_string(m) + " cells it is " + number_text(resting_voltage_v / m, "%.2f V") +
                        " per cell: check --cells";
            p.notes.push_back(note);
        }
    }
    if (first_positive(info, {"BATT_CAPACITY", "BAT1_CAPACITY", "BAT_CAPACITY"}, &v, &from)) {
        p.capacity_ah = v / 1000.0;
        p.capacity_from = "the log's " + from + " mAh";
    }
    // The values per cell are judged with the count the config will have: the user's, when
    // given, else the log's (they had been judged with the log's and then lost, or scaled
    // by it, under another --cells).
    const int n = cells_given > 0 ? cells_given : p.cells;
    // ArduPilot's low-voltage failsafe is the voltage the pilot flies to: the remaining
    // time's target. (PX4's BAT1_V_EMPTY is a load-compensated empty cell, not a cutoff.)
    if (first_positive(info, {"BATT_LOW_VOLT", "FS_BATT_VOLTAGE", "LOW_VOLT"}, &v, &from)) {
        if (n > 0 && v / n >= kCutoffMinV && v / n <= kCutoffMaxV) {
            p.cutoff_voltage_v = v;
            p.cutoff_from = "the log's " + from + " V (" + number_text(v / n, "%.2f V") + " per cell)";
            // A failsafe that takes no action (ArduCopter 3.x FS_BATT_ENABLE, later BATT_FS_LOW_ACT;
            // 0 = warn only) does not end the flight there; said, since the level sets the remaining time.
            double enabled = NAN;
            std::string switch_name;
            for (const char* name : {"FS_BATT_ENABLE", "BATT_FS_LOW_ACT"}) {
                const double e = log_parameter(info, name);
                if (std::isfinite(e)) {
                    enabled = e;
                    switch_name = name;
                    break;
                }
            }
            if (enabled == 0.0)
                p.cutoff_notes.push_back("the log's battery failsafe takes no action (" + switch_name + " 0): its " + from +
                                  " V only raised a warning, and the pilot may fly below it; it is the cutoff all the "
                                  "same (give --cutoff-v to set another)");
            if (v / n < kLipoCutoffMinV) {
                std::string note = "the log's " + from + " V is " + number_text(v / n, "%.2f V") + " per cell on " +
                                   std::to_string(n) + " cells, below where a LiPo is flown (" +
                                   number_text(kLipoCutoffMinV, "%.1f") + " V per cell or more under load)";
                // The one other count at which it is an ordinary LiPo cutoff, when there is one.
                int fits = 0, fitting = 0;
                for (int m = 1; m <= core::kMaxCells; ++m)
                    if (m != n && v / m >= kLipoCutoffLowV && v / m <= kLipoCutoffHighV) {
                        fits = m;
                        ++fitting;
                    }
                if (fitting == 1)
                    note += "; it is " + number_text(v / fits, "%.2f V") + " per cell on " + std::to_string(fits) +
                            " cells: set for another pack?";
                note += " The remaining time runs to it, which lengthens it; give --cutoff-v (e.g. " +
                        number_text(kMinV * n, "%.2f") + " for " + std::to_string(n) +
                        " cells at 3.325 V) unless this is a Li-ion pack flown that low";
                p.cutoff_notes.push_back(note);
            }
        } else if (n > 0) {
            p.ignored.push_back(from + " V: " + number_text(v / n, "%.2f V") + " per cell (" +
                                std::to_string(n) + " cells) is no cutoff (" + number_text(kCutoffMinV, "%.1f") + "-" +
                                number_text(kCutoffMaxV, "%.1f") + " V); the default 3.325 V per cell is used");
        } else {
            p.ignored.push_back(from + " V: with no cell count it cannot be judged per cell; "
                                "the default 3.325 V per cell is used");
        }
    }
    if (first_positive(info, {"BATT_LOW_TIMER"}, &v, &from) && v <= 600.0) {
        p.cutoff_delay_s = v;  // the failsafe acts once the voltage has stayed low this long
        p.cutoff_delay_from = "the log's " + from + " s";
    }
    if (first_positive(info, {"BAT1_R_INTERNAL", "BAT_R_INTERNAL"}, &v, &from)) {
        if (n > 0) {
            p.resistance_ohm = v * n;  // PX4's is per cell
            p.resistance_from = "the log's " + from + " ohm per cell";
        } else {
            p.ignored.push_back(from + " ohm per cell: with no cell count no pack resistance");
        }
    }
    return p;
}

void FirstRest::add(const core::Sample& s) {
    if (!started_) {
        started_ = true;
        t0_us_ = s.time_us;
    }
    constexpr uint64_t kWindowUs = 10000000;
    if (!std::isnan(voltage_v_) || s.time_us - t0_us_ > kWindowUs) return;
    if (std::isfinite(s.voltage_v) && s.voltage_v > 0.0f && std::fabs(s.current_a) <= max_current_a_)
        voltage_v_ = s.voltage_v;
}

LogPack read_log_pack(const std::string& path, const ReaderOptions& options, int cells_given) {
    std::unique_ptr<SampleReader> reader = open_reader(path, options);
    core::Sample sample;
    FirstRest rest(1.0);
    bool any = false;
    while (reader->next(sample)) {
        rest.add(sample);
        any = true;
    }
    if (!any) throw InputError(path, 0, 0, "the log holds no samples");
    return log_pack(reader->info(), rest.voltage_v(), cells_given);
}

}  // namespace host
}  // namespace battsim
