#include "host/sim/simulate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "host/config_json.h"
#include "host/io/atomic_file.h"
#include "host/sim/autopilot_log.h"
#include "host/sim/det_math.h"

namespace battsim {
namespace host {
namespace sim {

namespace {

using nlohmann::json;

enum class Phase { Idle, Armed, Flight, After };

double filter_alpha(double dt_s, double tau_s) { return tau_s > 0.0 ? 1.0 - det_exp(-dt_s / tau_s) : 1.0; }

uint64_t flight_seed(const Scenario& s) { return Rng::stream(s.seed, 31).next_u64(); }

// Flies `params` through the scenario's ground phases and then on the flight demand until
// cutoff, without sensors or landing: the total flight time of that pack.
double total_flight_time(const Scenario& s, const PlantParams& params) {
    Plant plant;
    plant.configure(params, s.pack.initial_soc, s.initial_temperature_c);
    FlightPower flight(s.profile, flight_seed(s));
    const Timeline tl = make_timeline(s.profile);
    const double dt = s.step_s;
    const double cutoff_v = s.cutoff_v_per_cell * s.pack.cells;
    const double alpha = filter_alpha(dt, s.cutoff_filter_s);
    double vf = 0.0;
    bool vf_init = false;
    for (long n = 0;; ++n) {
        const double t = static_cast<double>(n) * dt;
        const bool flying = t >= tl.takeoff_s;
        if (flying && t - tl.takeoff_s > s.profile.flight_s + s.max_continuation_s) return -1.0;
        const double power = !flying ? (t < s.profile.idle_before_s ? s.profile.idle_power_w : s.profile.armed_power_w)
                                     : flight.next(dt);
        const PlantOutput out = plant.step_power(power, dt, flying);
        if (!flying) continue;
        if (!vf_init) {
            vf = out.voltage_v;
            vf_init = true;
        } else {
            vf += alpha * (out.voltage_v - vf);
        }
        if (vf < cutoff_v || out.brownout) return t + dt - tl.takeoff_s;
    }
}

}  // namespace

double flight_time_to_cutoff(const Scenario& scenario, bool healthy) {
    Scenario s = scenario;
    resolve_defaults(s);
    return total_flight_time(s, make_plant_params(s, healthy));
}

namespace {

json round_series(const std::vector<double>& v, int decimals) {
    json a = json::array();
    for (double x : v) a.push_back(round_fixed(x, decimals));
    return a;
}

}  // namespace

ForwardResult fly_to_cutoff(const PlantParams& params, const PlantState& state, double cutoff_filter_v, double power_w,
                            double cutoff_v, double filter_s, double dt_s, double max_s) {
    ForwardResult r;
    Plant plant;
    plant.configure(params, 1.0, state.temperature_c);
    plant.set_state(state);
    // Far from the cutoff, steps four times longer: at a constant power nothing changes
    // quickly there, and this run is repeated for every sample of the oracle.
    const double coarse_s = 4.0 * dt_s;
    const double alpha_fine = filter_alpha(dt_s, filter_s), alpha_coarse = filter_alpha(coarse_s, filter_s);
    const double e0 = state.energy_wh;
    double vf = cutoff_filter_v;
    if (vf < cutoff_v) {
        r.reached = true;
        return r;
    }
    double t = 0.0;
    while (t < max_s) {
        const bool far = vf > 1.04 * cutoff_v;
        const double dt = far ? coarse_s : dt_s;
        const double e_before = plant.state().energy_wh;
        const PlantOutput out = plant.step_power(power_w, dt, true);
        const double v_prev = vf;
        vf += (far ? alpha_coarse : alpha_fine) * (out.voltage_v - vf);
        if (out.brownout) {
            r.time_s = t;
            r.energy_wh = e_before - e0;
            r.reached = true;
            return r;
        }
        if (vf < cutoff_v) {
            // Linear interpolation of the crossing inside the step.
            const double frac = v_prev > vf ? (v_prev - cutoff_v) / (v_prev - vf) : 1.0;
            r.time_s = t + frac * dt;
            r.energy_wh = (e_before - e0) + frac * (plant.state().energy_wh - e_before);
            r.reached = true;
            return r;
        }
        t += dt;
    }
    r.time_s = max_s;
    r.energy_wh = plant.state().energy_wh - e0;
    return r;
}

SimulationResult simulate(const Scenario& scenario, const SimulateOptions& options) {
    SimulationResult res;
    res.scenario = scenario;
    resolve_defaults(res.scenario);
    const Scenario& s = res.scenario;
    res.format = log_format_of(s);
    Truth& tr = res.truth;
    tr.plant = make_plant_params(s, false);
    tr.sensor_faulty = s.sensor.faults.any();

    Plant plant;
    plant.configure(tr.plant, s.pack.initial_soc, s.initial_temperature_c);
    FlightPower flight(s.profile, flight_seed(s));
    SensorChain sensor;
    sensor.configure(s.sensor, s.pack.cells, s.seed);
    const Timeline tl = make_timeline(s.profile);
    const double dt = s.step_s;
    const double cutoff_v = s.cutoff_v_per_cell * s.pack.cells;
    const double alpha = filter_alpha(dt, s.cutoff_filter_s);
    const long decimation_steps = std::max(1L, static_cast<long>(std::llround(s.decimation_s / dt)));
    tr.takeoff_s = tl.takeoff_s;
    tr.planned_landing_s = tl.planned_landing_s;
    tr.cutoff_voltage_v = cutoff_v;

    std::vector<LogRecord> records;
    double landing = tl.planned_landing_s;
    double log_end = tl.log_end_s;
    bool cut_in_flight = false, taken_off = false, vf_init = false;
    double vf = 0.0, energy_at_takeoff = 0.0, energy_at_cutoff = 0.0;
    // The pack, demand and filter at the planned landing, to fly on from there.
    bool have_cont = false;
    PlantState cont_state;
    FlightPower cont_flight;
    double cont_vf = 0.0;
    long cont_step = 0;
    const auto save_continuation = [&](long n) {
        have_cont = true;
        cont_state = plant.state();
        cont_flight = flight;
        cont_vf = vf;
        cont_step = n;
    };

    long n = 0;
    for (;; ++n) {
        const double t = static_cast<double>(n) * dt;
        if (t >= log_end) break;
        const Phase ph = t < s.profile.idle_before_s ? Phase::Idle
                         : t < tl.takeoff_s          ? Phase::Armed
                         : t < landing && !cut_in_flight ? Phase::Flight
                                                         : Phase::After;
        if (ph == Phase::After && !have_cont && !cut_in_flight) save_continuation(n);
        const bool airborne = ph == Phase::Flight;
        if (airborne && !taken_off) {
            taken_off = true;
            energy_at_takeoff = plant.state().energy_wh;
        }
        TruthPoint point;
        const bool record_point = n % decimation_steps == 0;
        if (record_point) {
            point.time_s = t;
            point.temperature_c = plant.state().temperature_c;
            point.soc = plant.min_soc();
            point.resistance_ohm = plant.pack_r0_ohm();
            point.energy_wh = plant.state().energy_wh;
            point.in_flight = airborne;
        }
        double power = s.profile.idle_power_w;
        if (ph == Phase::Armed) power = s.profile.armed_power_w;
        if (airborne) power = flight.next(dt);
        const PlantOutput out = plant.step_power(power, dt, airborne);
        for (int c = 0; c < s.pack.cells; ++c) {
            const double soc = plant.state().soc[c];
            tr.lowest_cell_soc = std::min(tr.lowest_cell_soc, soc);
            if (soc < 0.0 && tr.empty_cell < 0) {
                tr.empty_cell = c;
                tr.cell_empty_s = t + dt;
            }
        }
        if (out.brownout && !airborne) {
            throw ScenarioError(s.source_path + ": the pack cannot deliver even the ground power (" +
                                std::to_string(power) + " W); check the pack and profile");
        }
        if (airborne) {
            if (!vf_init) {
                vf = out.voltage_v;
                vf_init = true;
            } else {
                vf += alpha * (out.voltage_v - vf);
            }
            if (vf < cutoff_v || out.brownout) {
                cut_in_flight = true;
                tr.cutoff_by_brownout = out.brownout;
                tr.cutoff_s = t + dt;
                landing = t + dt;
                log_end = landing + s.profile.idle_after_s;
                energy_at_cutoff = plant.state().energy_wh;
                tr.lowest_cell_soc_at_cutoff = plant.min_soc();
            }
        }
        TrueValues tv;
        tv.voltage_v = out.voltage_v;
        tv.current_a = out.current_a;
        for (int c = 0; c < s.pack.cells; ++c) tv.cell_v[c] = out.cell_v[c];
        tv.temperature_c = plant.state().temperature_c;
        const size_t before = records.size();
        sensor.feed(t, dt, tv, airborne, records);
        if (options.keep_snapshots) {
            for (size_t i = before; i < records.size(); ++i) {
                RowSnapshot snap;
                snap.time_ms = records[i].time_ms;
                snap.time_s = records[i].read_time_s;
                snap.state = plant.state();
                snap.cutoff_filter_v = vf;
                snap.flight_energy_wh = taken_off ? plant.state().energy_wh - energy_at_takeoff : 0.0;
                snap.in_flight = airborne && !cut_in_flight;
                res.snapshots.push_back(snap);
            }
        }
        if (record_point) {
            point.current_a = out.current_a;
            point.voltage_v = out.voltage_v;
            point.power_w = out.power_w;
            tr.series.push_back(point);
        }
    }
    if (!taken_off) throw ScenarioError(s.source_path + ": the log ends before take-off");
    tr.landing_s = landing;
    tr.log_end_s = log_end;
    tr.landed_by_cutoff = cut_in_flight;
    tr.final_temperature_c = plant.state().temperature_c;
    tr.log_charge_ah = plant.state().charge_ah;

    if (!cut_in_flight) {
        if (!have_cont) save_continuation(n);
        Plant cp;
        cp.configure(tr.plant, 1.0, cont_state.temperature_c);
        cp.set_state(cont_state);
        FlightPower f = cont_flight;
        double v = cont_vf;
        for (long m = cont_step;; ++m) {
            const double t = static_cast<double>(m) * dt;
            if (t - landing > s.max_continuation_s) {
                throw ScenarioError(s.source_path + ": the pack did not reach its cutoff within " +
                                    std::to_string(s.max_continuation_s) +
                                    " s after the planned landing; raise profile.mean_power_w or truth.max_continuation_s");
            }
            const PlantOutput out = cp.step_power(f.next(dt), dt, true);
            v += alpha * (out.voltage_v - v);
            if (v < cutoff_v || out.brownout) {
                tr.cutoff_s = t + dt;
                tr.cutoff_by_brownout = out.brownout;
                energy_at_cutoff = cp.state().energy_wh;
                tr.lowest_cell_soc_at_cutoff = cp.min_soc();
                break;
            }
        }
    }
    tr.total_flight_time_s = tr.cutoff_s - tr.takeoff_s;
    if (tr.total_flight_time_s < 1.0) {
        throw ScenarioError(s.source_path + ": the pack is at its cutoff at take-off (" +
                            std::to_string(s.cutoff_v_per_cell) + " V/cell); raise pack.initial_soc or lower the power");
    }
    tr.energy_to_cutoff_wh = energy_at_cutoff - energy_at_takeoff;
    tr.mean_flight_power_w = tr.energy_to_cutoff_wh * 3600.0 / tr.total_flight_time_s;
    for (TruthPoint& p : tr.series) {
        if (!p.in_flight) continue;
        p.remaining_time_s = tr.cutoff_s - p.time_s;
        p.remaining_energy_wh = energy_at_cutoff - p.energy_wh;
    }
    tr.healthy_total_flight_time_s = total_flight_time(s, make_plant_params(s, true));
    // A healthy twin still flying at the end of the continuation flies longer than any number
    // we have: standing in the degraded pack's own time had made a 3.4 x shorter flight "not short".
    if (tr.healthy_total_flight_time_s < 0.0)
        throw ScenarioError(s.source_path + ": the healthy twin pack did not reach its cutoff within " +
                            std::to_string(s.max_continuation_s) +
                            " s after the planned landing, so the flight's shortfall is not known; raise "
                            "truth.max_continuation_s or profile.mean_power_w");

    // Pack facts and what a good monitor may rightly warn about.
    const PlantParams& pp = tr.plant;
    double min_cap = pp.cell[0].capacity_ah, sum_cap = 0.0;
    for (int c = 0; c < pp.cells; ++c) {
        min_cap = std::min(min_cap, pp.cell[c].capacity_ah);
        sum_cap += pp.cell[c].capacity_ah;
    }
    tr.pack_capacity_ah = min_cap;
    tr.mean_cell_capacity_ah = sum_cap / pp.cells;
    tr.nominal_pack_capacity_ah = s.pack.capacity_ah;
    tr.initial_charge_ah = (1.0 - s.pack.initial_soc) * min_cap;
    Plant ref;
    ref.configure(pp, 1.0, 25.0);
    tr.pack_r0_reference_ohm = ref.pack_r0_reference_ohm();
    PlantParams nominal = pp;
    for (int c = 0; c < nominal.cells; ++c) nominal.cell[c].r0_ohm = s.pack.r0_ohm;
    ref.configure(nominal, 1.0, 25.0);
    tr.nominal_pack_r0_reference_ohm = ref.pack_r0_reference_ohm();
    if (pp.cells >= 2) {  // a single cell has no others to differ from
        double worst = 0.0;
        for (int c = 0; c < pp.cells; ++c) {
            std::vector<double> q, r;
            for (int k = 0; k < pp.cells; ++k) {
                if (k == c) continue;
                q.push_back(pp.cell[k].capacity_ah);
                r.push_back(pp.cell[k].r0_ohm);
            }
            std::sort(q.begin(), q.end());
            std::sort(r.begin(), r.end());
            const size_t m = q.size();
            const double q_med = m % 2 ? q[m / 2] : 0.5 * (q[m / 2 - 1] + q[m / 2]);
            const double r_med = m % 2 ? r[m / 2] : 0.5 * (r[m / 2 - 1] + r[m / 2]);
            const double deficit = 1.0 - pp.cell[c].capacity_ah / q_med;
            const double excess = pp.cell[c].r0_ohm / r_med - 1.0;
            if (deficit > 0.10 || excess > 0.10) {
                tr.outlier_cells.push_back(c);
                if (std::max(deficit, excess) > worst) {
                    worst = std::max(deficit, excess);
                    tr.weak_cell = c;
                }
            }
        }
    }
    const double capacity_ratio = tr.pack_capacity_ah / tr.nominal_pack_capacity_ah;
    const double resistance_ratio = tr.pack_r0_reference_ohm / tr.nominal_pack_r0_reference_ohm;
    if (capacity_ratio <= 0.9) tr.justified_warnings.push_back("low_capacity");
    if (resistance_ratio >= 1.2) tr.justified_warnings.push_back("high_resistance");
    if (tr.weak_cell >= 0) tr.justified_warnings.push_back("cell_outlier");
    tr.degraded = !tr.justified_warnings.empty();
    tr.sensor_unit = sensor.unit();
    tr.sensor_stats = sensor.stats();
    tr.rows = 0;

    // The log text (bytes, for the autopilots' binary logs).
    const bool autopilot = res.format == SimLogFormat::DataFlash || res.format == SimLogFormat::ULog;
    const AutopilotLog autopilot_kind = res.format == SimLogFormat::ULog ? AutopilotLog::ULog : AutopilotLog::DataFlash;
    AutopilotLogWriter autopilot_log(autopilot_kind, s.pack.cells);
    res.log_text = autopilot ? autopilot_log.header() : format_header(res.format, s.pack.cells);
    res.log_text.reserve(records.size() * (res.format == SimLogFormat::Raw ? 48 : 80));
    // A radio or an autopilot logs on its own timer: the first reading at or after each
    // interval's start.
    const bool thinned = autopilot || res.format == SimLogFormat::Radio;
    const double interval_s = autopilot ? autopilot_log_interval_s(autopilot_kind) : s.log_interval_s;
    const int64_t interval_ms = static_cast<int64_t>(std::llround(interval_s * 1000.0));
    int64_t next_ms = 0;
    for (const LogRecord& r : records) {
        if (thinned) {
            if (r.time_ms < next_ms) continue;
            next_ms = (r.time_ms / interval_ms + 1) * interval_ms;
        }
        if (autopilot) {
            const RecordValues v = record_values(s.pack.cells, s.sensor.shunt, r);
            autopilot_log.append(res.log_text, r.time_ms * 1000, v.voltage_v, v.current_a, v.cell_v, v.temperature_c);
        } else {
            format_record(res.format, s.pack.cells, s.sensor.shunt, r, res.log_text);
        }
        ++tr.rows;
    }
    return res;
}

json truth_to_json(const SimulationResult& r) {
    const Truth& t = r.truth;
    const Scenario& s = r.scenario;
    json j;
    j["schema"] = kTruthSchema;
    j["schema_version"] = kTruthVersion;
    j["battsim_version"] = BATTSIM_VERSION;
    j["scenario"] = scenario_to_json(s);
    j["monitor_config"] = config_to_json(s.config);
    j["log"] = {{"format", sim_log_format_name(r.format)},
                {"rows", t.rows}};
    json cells = json::array();
    for (int c = 0; c < t.plant.cells; ++c) {
        const CellParams& p = t.plant.cell[c];
        cells.push_back({{"capacity_ah", round_fixed(p.capacity_ah, 6)},
                         {"r0_ohm_25c", round_fixed(p.r0_ohm, 7)},
                         {"r1_ohm_25c", round_fixed(p.r1_ohm, 7)},
                         {"tau1_s", p.tau1_s},
                         {"r2_ohm_25c", round_fixed(p.r2_ohm, 7)},
                         {"tau2_s", p.tau2_s}});
    }
    j["pack"] = {{"cells", t.plant.cells},
                 {"capacity_ah", round_fixed(t.pack_capacity_ah, 6)},
                 {"capacity_note", "the weakest cell's capacity: what the series string can deliver from full to empty (3.3 V rest)"},
                 {"mean_cell_capacity_ah", round_fixed(t.mean_cell_capacity_ah, 6)},
                 {"nominal_capacity_ah", round_fixed(t.nominal_pack_capacity_ah, 6)},
                 {"initial_soc", s.pack.initial_soc},
                 {"initial_charge_drawn_ah", round_fixed(t.initial_charge_ah, 6)},
                 {"resistance_ohm_25c", round_fixed(t.pack_r0_reference_ohm, 7)},
                 {"nominal_resistance_ohm_25c", round_fixed(t.nominal_pack_r0_reference_ohm, 7)},
                 {"resistance_note", "series ohmic resistance R0 (what an instantaneous current step shows); the RC branches are per cell below"},
                 {"per_cell", cells}};
    j["flight"] = {{"takeoff_s", round_fixed(t.takeoff_s, 3)},
                   {"planned_landing_s", round_fixed(t.planned_landing_s, 3)},
                   {"landing_s", round_fixed(t.landing_s, 3)},
                   {"log_end_s", round_fixed(t.log_end_s, 3)},
                   {"landed_by_cutoff", t.landed_by_cutoff},
                   {"cutoff_s", round_fixed(t.cutoff_s, 3)},
                   {"cutoff_voltage_v", round_fixed(t.cutoff_voltage_v, 4)},
                   {"cutoff_by_brownout", t.cutoff_by_brownout},
                   {"total_flight_time_s", round_fixed(t.total_flight_time_s, 3)},
                   {"healthy_total_flight_time_s", round_fixed(t.healthy_total_flight_time_s, 3)},
                   {"short_flight", t.short_flight()},
                   {"energy_to_cutoff_wh", round_fixed(t.energy_to_cutoff_wh, 4)},
                   {"mean_flight_power_w", round_fixed(t.mean_flight_power_w, 3)},
                   {"final_temperature_c", round_fixed(t.final_temperature_c, 2)},
                   // Below 0 the plant ran past empty on an extrapolated OCV table: a cutoff
                   // under the empty cell's voltage, or a cell too weak for the flight.
                   {"lowest_cell_soc", round_fixed(t.lowest_cell_soc, 5)},
                   {"lowest_cell_soc_at_cutoff", round_fixed(t.lowest_cell_soc_at_cutoff, 5)},
                   {"empty_cell", t.empty_cell >= 0 ? json(t.empty_cell + 1) : json(nullptr)},
                   {"cell_empty_s", t.cell_empty_s >= 0.0 ? json(round_fixed(t.cell_empty_s, 3)) : json(nullptr)},
                   // What a charger puts back after the log (with pack.initial_charge_drawn_ah):
                   // the ruler for a current-sensor check against the charger's count.
                   {"log_charge_ah", round_fixed(t.log_charge_ah, 6)}};
    j["degradation"] = {{"degraded", t.degraded},
                        {"justified_warnings", t.justified_warnings},
                        {"weak_cell", t.weak_cell >= 0 ? json(t.weak_cell + 1) : json(nullptr)},
                        {"outlier_cells", [&] {
                             json a = json::array();
                             for (int c : t.outlier_cells) a.push_back(c + 1);
                             return a;
                         }()},
                        {"outlier_note", "cells with capacity > 10 % below or R0 > 10 % above the median of the other cells (25 °C values in pack.per_cell)"},
                        {"capacity_ratio", round_fixed(t.pack_capacity_ah / t.nominal_pack_capacity_ah, 5)},
                        {"resistance_ratio", round_fixed(t.pack_r0_reference_ohm / t.nominal_pack_r0_reference_ohm, 5)}};
    json gains = json::array(), offsets = json::array();
    for (int k = 0; k + 1 < t.plant.cells; ++k) {
        gains.push_back(round_fixed(t.sensor_unit.tap_gain_error[k], 7));
        offsets.push_back(round_fixed(t.sensor_unit.tap_offset_v[k], 6));
    }
    j["sensor"] = {{"faulty", t.sensor_faulty},
                   {"unit", {{"bus_gain_error", round_fixed(t.sensor_unit.bus_gain_error, 7)},
                             {"tap_gain_error", gains},
                             {"tap_offset_v", offsets}}},
                   {"reads", t.sensor_stats.reads},
                   {"rows_dropped", t.sensor_stats.dropped},
                   {"sd_stalls", t.sensor_stats.stalls},
                   {"late_reads", t.sensor_stats.late_reads},
                   {"loose_lead_episodes", t.sensor_stats.loose_episodes},
                   {"loose_lead_open_s", round_fixed(t.sensor_stats.loose_open_s, 3)},
                   {"current_clipped_reads", t.sensor_stats.current_clipped}};
    std::vector<double> time, current, voltage, power, temp, soc, res, rem_t, rem_e;
    json rem_time = json::array(), rem_energy = json::array();
    for (const TruthPoint& p : t.series) {
        time.push_back(p.time_s);
        current.push_back(p.current_a);
        voltage.push_back(p.voltage_v);
        power.push_back(p.power_w);
        temp.push_back(p.temperature_c);
        soc.push_back(p.soc);
        res.push_back(p.resistance_ohm);
        rem_time.push_back(p.in_flight ? json(round_fixed(p.remaining_time_s, 3)) : json(nullptr));
        rem_energy.push_back(p.in_flight ? json(round_fixed(p.remaining_energy_wh, 4)) : json(nullptr));
    }
    j["series"] = {{"decimation_s", s.decimation_s},
                   {"note", "values at each time; remaining_* are null outside the flight (take-off to landing)"},
                   {"time_s", round_series(time, 3)},
                   {"current_a", round_series(current, 3)},
                   {"voltage_v", round_series(voltage, 4)},
                   {"power_w", round_series(power, 2)},
                   {"temperature_c", round_series(temp, 3)},
                   {"soc_min_cell", round_series(soc, 5)},
                   {"resistance_ohm", round_series(res, 6)},
                   {"remaining_flight_time_s", rem_time},
                   {"remaining_energy_wh", rem_energy}};
    return j;
}

std::string default_truth_path(const std::string& log_path) {
    const size_t slash = log_path.find_last_of('/');
    const size_t dot = log_path.find_last_of('.');
    const bool extension = dot != std::string::npos && (slash == std::string::npos || dot > slash);
    return (extension ? log_path.substr(0, dot) : log_path) + ".truth.json";
}

void write_simulation(const SimulationResult& r, const std::string& log_path, const std::string& truth_path) {
    // Both are committed only when both could be written.
    AtomicFile log(log_path);
    log.write(r.log_text);
    AtomicFile truth(truth_path);
    truth.write(json_text(truth_to_json(r), 2) + "\n");
    log.commit();
    truth.commit();
}

std::string ground_draw_note(const SimulationResult& r) {
    std::vector<double> ground_a;
    for (const TruthPoint& p : r.truth.series)
        if (p.time_s < r.truth.takeoff_s - r.scenario.profile.armed_s) ground_a.push_back(p.current_a);
    if (ground_a.empty()) return "";
    // The median: the idle's own draw, whatever a first point or the arming does.
    std::nth_element(ground_a.begin(), ground_a.begin() + ground_a.size() / 2, ground_a.end());
    const double idle_a = ground_a[ground_a.size() / 2];
    const double bar_a = r.scenario.config.monitor.flying.min_flying_current_a;
    if (!(idle_a >= bar_a)) return "";
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "%s: the ground idle draws %.2f A (profile.idle_power_w %g W), at or above the monitor config's "
                  "take-off current (monitor.min_flying_current_a %.3g A): its replay reads the ground as flight, one "
                  "flight from the log's first sample that never lands. Give the scenario a smaller idle_power_w "
                  "(what the craft draws disarmed), or the config a take-off current above the idle's",
                  r.scenario.name.c_str(), idle_a, r.scenario.profile.idle_power_w, bar_a);
    return buf;
}

std::string flight_draw_note(const SimulationResult& r) {
    std::vector<double> flight_a;
    for (const TruthPoint& p : r.truth.series)
        if (p.in_flight) flight_a.push_back(p.current_a);
    if (flight_a.empty()) return "";
    // The median: the flight's own draw, whatever a take-off boost or a gust does.
    std::nth_element(flight_a.begin(), flight_a.begin() + flight_a.size() / 2, flight_a.end());
    const double flight_median_a = flight_a[flight_a.size() / 2];
    const double bar_a = r.scenario.config.monitor.flying.min_flying_current_a;
    if (!(flight_median_a < bar_a)) return "";
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "the flight draws %.2f A (median; profile.mean_power_w %g W), below the monitor config's "
                  "take-off current (monitor.min_flying_current_a %.3g A): its replay does not see the take-off and "
                  "reads the flight as ground. Give the scenario a larger mean_power_w, or the config a take-off "
                  "current below the flight's",
                  flight_median_a, r.scenario.profile.mean_power_w, bar_a);
    return buf;
}

std::string empty_cell_note(const SimulationResult& r) {
    const Truth& t = r.truth;
    // The log only: a weak cell below 0 % by the time the truth flies on to a pack-voltage
    // cutoff is what a series pack does (the suite's weak cells reach about −5 %).
    if (t.empty_cell < 0) return "";
    char buf[640];
    std::snprintf(buf, sizeof buf,
                  "cell %d passed 0 %% state of charge at %.1f s and reaches %.1f %% in the log (the truth's "
                  "flight.empty_cell, cell_empty_s, lowest_cell_soc): the plant runs on past empty, where its voltages "
                  "are extrapolated. Raise truth.cutoff_v_per_cell (%.2f V), shorten the flight or strengthen the cell",
                  t.empty_cell + 1, t.cell_empty_s, t.lowest_cell_soc * 100.0, r.scenario.cutoff_v_per_cell);
    return buf;
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
