#include "host/score/estimator.h"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "host/score/coulomb_baseline.h"
#include "core/estimate/power_time_solver.h"
#include "core/model/ocv.h"
#include "host/sim/plant.h"

namespace battsim {
namespace host {
namespace score {

namespace {
// The truth's snapshot at this sample's millisecond, if any; k walks forward with the samples.
const sim::RowSnapshot* snapshot_at(const sim::SimulationResult& r, const core::Sample& smp, size_t& k) {
    const int64_t ms = static_cast<int64_t>(smp.time_us / 1000);
    while (k < r.snapshots.size() && r.snapshots[k].time_ms < ms) ++k;
    return k < r.snapshots.size() && r.snapshots[k].time_ms == ms ? &r.snapshots[k] : nullptr;
}

// A forward run every quarter second; between runs the same answer aged by the time passed
// (at a constant demand it falls 1 s per s). Shared by the columns that run to the cutoff.
class AgedForwardRuns {
public:
    // run() -> {time_s, energy_wh}, called only when a new run is due.
    template <class Run>
    void fill(double now_s, double power_w, Run run, Estimate& e) {
        if (!have_ || now_s - run_time_s_ >= 0.25) {
            const std::pair<double, double> r = run();
            have_ = true;
            run_time_s_ = now_s;
            remaining_s_ = r.first;
            energy_wh_ = r.second;
            power_w_ = power_w;
        }
        const double aged_s = now_s - run_time_s_;
        e.has_remaining_time = true;
        e.remaining_time_s = std::max(0.0, remaining_s_ - aged_s);
        e.has_remaining_energy = true;
        e.remaining_energy_wh = std::max(0.0, energy_wh_ - power_w_ * aged_s / 3600.0);
    }

private:
    bool have_ = false;
    double run_time_s_ = 0.0, remaining_s_ = 0.0, energy_wh_ = 0.0, power_w_ = 0.0;
};
}  // namespace

std::vector<EstimatorColumn> standard_columns() {
    return {
        // Forced, not "as configured": a suite of make-config packs (estimator joint) had
        // scored the joint estimator under the reference's name, twice.
        monitor_column("reference", "the core Monitor with the reference estimator (the dissertation's method)",
                       [](core::MonitorConfig& c) { c.estimator = core::EstimatorKind::Reference; }),
        baseline_column(),
        oracle_column(),
        monitor_column("joint", "the core Monitor with the joint state/parameter estimator",
                       [](core::MonitorConfig& c) { c.estimator = core::EstimatorKind::Joint; }),
    };
}

std::vector<EstimatorColumn> diagnostic_columns() { return {solve_truth_column()}; }

std::vector<EstimatorColumn> select_columns(const std::string& names) {
    std::vector<std::string> wanted;
    for (size_t b = 0; b <= names.size() && !names.empty();) {
        const size_t e = std::min(names.find(',', b), names.size());
        if (e > b) wanted.push_back(names.substr(b, e - b));
        b = e + 1;
    }
    std::vector<EstimatorColumn> all = standard_columns();
    if (wanted.empty()) return all;
    for (EstimatorColumn& d : diagnostic_columns()) all.push_back(std::move(d));
    std::vector<EstimatorColumn> columns;
    for (const std::string& name : wanted) {
        const auto it = std::find_if(all.begin(), all.end(), [&](const EstimatorColumn& c) { return c.name == name; });
        if (it == all.end()) {
            std::string known;
            for (const EstimatorColumn& c : all) known += (known.empty() ? "" : ", ") + c.name;
            throw std::invalid_argument("unknown estimator \"" + name + "\"; expected " + known);
        }
        // Twice is one column printed twice, and its flights scored twice.
        if (std::any_of(columns.begin(), columns.end(), [&](const EstimatorColumn& c) { return c.name == name; }))
            throw std::invalid_argument("\"" + name + "\" given twice");
        columns.push_back(*it);
    }
    return columns;
}

EstimatorColumn monitor_column(std::string name, std::string description,
                               std::function<void(core::MonitorConfig&)> tweak) {
    EstimatorColumn col;
    col.name = std::move(name);
    col.description = std::move(description);
    col.run = [tweak](const FlightInput& in) {
        core::MonitorConfig cfg = in.config->monitor;
        if (tweak) tweak(cfg);
        auto monitor = std::make_unique<core::Monitor>();  // large: keep it off the stack
        monitor->configure(cfg);
        const double nominal_v = cfg.flight_time.nominal_voltage_v;
        const bool joint = cfg.estimator == core::EstimatorKind::Joint;
        std::vector<Estimate> out;
        out.reserve(in.samples->size());
        for (const core::Sample& s : *in.samples) {
            const core::MonitorStatus& st = monitor->update(s);
            Estimate e;
            e.time_s = static_cast<double>(s.time_us) * 1e-6;
            if (st.initialised && st.time_valid) {
                e.has_remaining_time = true;
                e.remaining_time_s = st.remaining_time_s;
                // The joint estimator reports its energy to cutoff; the reference's usable
                // energy is usable capacity × nominal voltage.
                e.has_remaining_energy = true;
                e.remaining_energy_wh = joint ? st.remaining_energy_wh
                                              : st.usable_capacity_ah * nominal_v - st.consumed_mwh * 1e-3;
            }
            if (st.initialised) {
                e.has_capacity = true;
                e.capacity_ah = st.capacity_ah;
            }
            if (st.resistance_ohm > 0.0f) {
                e.has_resistance = true;
                e.resistance_ohm = st.resistance_ohm;
            }
            if (st.rest_capacity_ah > 0.0f) {
                e.has_rest_capacity = true;
                e.rest_capacity_ah = st.rest_capacity_ah;
            }
            e.warnings = st.warnings;
            e.fault_cause = st.sensor_fault_cause;
            e.outlier_cell = st.outlier_cell;
            out.push_back(e);
        }
        return out;
    };
    return col;
}

EstimatorColumn baseline_column() {
    EstimatorColumn col;
    col.name = "baseline";
    col.description = "coulomb counting from full, rated capacity, 50 s average current (ArduPilot/PX4 style)";
    col.run = [](const FlightInput& in) {
        CoulombBaseline b;
        CoulombBaseline::Config c;
        c.rated_capacity_ah = in.config->monitor.battery.capacity_ah;
        b.configure(c);
        std::vector<Estimate> out;
        out.reserve(in.samples->size());
        bool have_time = false;
        uint64_t last_us = 0;
        for (const core::Sample& s : *in.samples) {
            const float dt = have_time && s.time_us > last_us ? static_cast<float>(s.time_us - last_us) * 1e-6f : 0.0f;
            have_time = true;
            last_us = s.time_us;
            b.update(s.current_a, dt);
            Estimate e;
            e.time_s = static_cast<double>(s.time_us) * 1e-6;
            e.has_remaining_time = b.status().time_valid;
            e.remaining_time_s = b.status().remaining_time_s;
            e.has_capacity = true;  // it assumes the rated capacity
            e.capacity_ah = c.rated_capacity_ah;
            out.push_back(e);
        }
        return out;
    };
    return col;
}

EstimatorColumn oracle_column() {
    EstimatorColumn col;
    col.name = "oracle";
    col.description = "knows the true pack and state, assumes the flight's average power so far continues";
    col.run = [](const FlightInput& in) {
        const sim::SimulationResult& r = *in.truth;
        const sim::Truth& t = r.truth;
        const sim::Scenario& s = r.scenario;
        std::vector<Estimate> out;
        out.reserve(in.samples->size());
        // It raises exactly the warnings the pack justifies, from take-off.
        uint8_t bits = 0;
        for (const std::string& w : t.justified_warnings) {
            if (w == "low_capacity") bits |= 1u << core::kWarnLowCapacity;
            if (w == "high_resistance") bits |= 1u << core::kWarnHighResistance;
            if (w == "cell_outlier") bits |= 1u << core::kWarnCellOutlier;
        }
        if (t.sensor_faulty) bits |= 1u << core::kWarnSensorFault;
        const uint8_t causes = sim::nameable_fault_causes(s.sensor.faults);
        sim::Plant plant;
        plant.configure(t.plant, 1.0, s.ambient_c);
        AgedForwardRuns runs;
        size_t k = 0;
        for (const core::Sample& smp : *in.samples) {
            Estimate e;
            e.time_s = static_cast<double>(smp.time_us) * 1e-6;
            if (const sim::RowSnapshot* at = snapshot_at(r, smp, k)) {
                const sim::RowSnapshot& snap = *at;
                plant.set_state(snap.state);
                e.has_capacity = true;
                e.capacity_ah = t.pack_capacity_ah;
                e.has_rest_capacity = snap.time_s > t.landing_s;
                e.rest_capacity_ah = t.pack_capacity_ah;
                e.has_resistance = true;
                e.resistance_ohm = plant.pack_r0_ohm();
                const double flown_s = snap.time_s - t.takeoff_s;
                if (snap.in_flight && flown_s >= 1.0) {
                    const double power = snap.flight_energy_wh * 3600.0 / flown_s;
                    runs.fill(snap.time_s, power, [&] {
                        const sim::ForwardResult f =
                            sim::fly_to_cutoff(t.plant, snap.state, snap.cutoff_filter_v, power,
                                               s.cutoff_v_per_cell * s.pack.cells, s.cutoff_filter_s, 0.5,
                                               s.max_continuation_s + s.profile.flight_s);
                        return std::make_pair(f.time_s, f.energy_wh);
                    }, e);
                }
                if (e.time_s >= t.takeoff_s) {
                    e.warnings = bits;
                    e.fault_cause = causes;
                    e.outlier_cell = static_cast<int8_t>(t.weak_cell);
                }
            }
            out.push_back(e);
        }
        return out;
    };
    return col;
}

EstimatorColumn solve_truth_column() {
    EstimatorColumn col;
    col.name = "solve-truth";
    col.description =
        "the joint estimator's flight-time solve fed the true pack: what the model lacks, apart from what the estimates miss";
    col.run = [](const FlightInput& in) {
        const sim::SimulationResult& r = *in.truth;
        const sim::Truth& t = r.truth;
        const sim::PlantParams& pp = t.plant;
        const core::MonitorConfig& mc = in.config->monitor;
        core::OcvCurve ocv;
        ocv.configure(mc.joint.ocv, mc.cells_in_series, mc.battery);
        core::PowerTimeSolver solver;
        solver.set_cutoff_delay_s(mc.joint.cutoff_delay_s);
        sim::Plant plant;
        plant.configure(pp, 1.0, r.scenario.ambient_c);
        std::vector<Estimate> out;
        out.reserve(in.samples->size());
        AgedForwardRuns runs;  // as often as the oracle
        size_t k = 0;
        for (const core::Sample& smp : *in.samples) {
            Estimate e;
            e.time_s = static_cast<double>(smp.time_us) * 1e-6;
            const sim::RowSnapshot* at = snapshot_at(r, smp, k);
            const double flown_s = at ? at->time_s - t.takeoff_s : 0.0;
            if (at && at->in_flight && flown_s >= 1.0) {
                const sim::RowSnapshot& snap = *at;
                const double power_w = snap.flight_energy_wh * 3600.0 / flown_s;
                runs.fill(snap.time_s, power_w, [&] {
                    plant.set_state(snap.state);
                    // The solve's one-cell picture of the pack: the mean cell's charge and
                    // capacity, every resistance the plant has now (R0 and both RC branches
                    // at steady state), and the flight's mean power so far.
                    double soc = 0.0, capacity_ah = 0.0, rc_ohm = 0.0;
                    for (int c = 0; c < pp.cells; ++c) {
                        soc += snap.state.soc[c];
                        capacity_ah += pp.cell[c].capacity_ah;
                        rc_ohm += pp.cell[c].r1_ohm + pp.cell[c].r2_ohm;
                    }
                    const double resistance_ohm = plant.pack_r0_ohm() + rc_ohm * plant.temperature_factor();
                    solver.start(static_cast<float>(soc / pp.cells), static_cast<float>(capacity_ah / pp.cells),
                                 static_cast<float>(resistance_ohm), static_cast<float>(power_w),
                                 mc.flight_time.min_flight_voltage_v, 64);
                    solver.advance(ocv, 64);
                    return std::make_pair(static_cast<double>(solver.result().time_s),
                                          static_cast<double>(solver.result().energy_wh));
                }, e);
            }
            out.push_back(e);
        }
        return out;
    };
    return col;
}

}  // namespace score
}  // namespace host
}  // namespace battsim
