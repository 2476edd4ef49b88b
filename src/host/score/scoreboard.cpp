#include "host/score/scoreboard.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "host/parallel.h"
#include "host/report/summary.h"
#include "host/io/atomic_file.h"
#include "host/io/sample_reader.h"
#include "host/stats.h"
#include "host/sim/det_math.h"

namespace battsim {
namespace host {
namespace score {

namespace {

using nlohmann::json;

// Cell `cell` (0-based) is one of the flight's outlier cells (by the truth).
bool is_outlier(const std::vector<int>& outlier_cells, int cell) {
    return std::find(outlier_cells.begin(), outlier_cells.end(), cell) != outlier_cells.end();
}

constexpr double kFractions[3] = {0.1, 0.2, 0.5};

bool has_warning(const std::vector<std::string>& list, const char* name) {
    return std::find(list.begin(), list.end(), name) != list.end();
}

// Last index whose time is at or before t; −1 if none.
long index_at(const std::vector<Estimate>& est, double t) {
    long lo = -1, hi = static_cast<long>(est.size());
    while (hi - lo > 1) {
        const long mid = (lo + hi) / 2;
        if (est[static_cast<size_t>(mid)].time_s <= t + 1e-9) lo = mid;
        else hi = mid;
    }
    return lo;
}

ColumnFlight judge(const std::vector<Estimate>& est, const sim::SimulationResult& sim,
                   const std::vector<long>& snap_of_sample) {
    const sim::Truth& t = sim.truth;
    ColumnFlight cf;
    const double total = t.total_flight_time_s;
    sim::Plant plant;
    plant.configure(t.plant, 1.0, sim.scenario.ambient_c);
    const auto true_resistance = [&](long i) -> double {
        const long k = snap_of_sample[static_cast<size_t>(i)];
        if (k < 0) return NAN;
        plant.set_state(sim.snapshots[static_cast<size_t>(k)].state);
        return plant.pack_r0_ohm();
    };
    const auto true_energy = [&](long i) -> double {
        const long k = snap_of_sample[static_cast<size_t>(i)];
        if (k < 0) return NAN;
        return t.energy_to_cutoff_wh - sim.snapshots[static_cast<size_t>(k)].flight_energy_wh;
    };
    for (int p = 0; p < 3; ++p) {
        const double tp = t.takeoff_s + kFractions[p] * total;
        if (tp > t.landing_s) continue;
        const long i = index_at(est, tp);
        if (i < 0 || est[static_cast<size_t>(i)].time_s < t.takeoff_s) continue;
        const Estimate& e = est[static_cast<size_t>(i)];
        if (e.has_remaining_time) {
            cf.has_rt[p] = true;
            cf.rt_err_pct[p] = (e.remaining_time_s - (t.cutoff_s - e.time_s)) / total * 100.0;
        }
        if (p == 1) {
            const double truth_e = true_energy(i);
            if (e.has_remaining_energy && std::isfinite(truth_e) && truth_e > 0.0) {
                cf.has_energy20 = true;
                cf.energy_err20_pct = (e.remaining_energy_wh - truth_e) / truth_e * 100.0;
            }
            if (e.has_capacity) {
                cf.has_cap20 = true;
                cf.cap_err20_pct = (e.capacity_ah - t.pack_capacity_ah) / t.pack_capacity_ah * 100.0;
            }
            const double r = true_resistance(i);
            if (e.has_resistance && std::isfinite(r)) {
                cf.has_res20 = true;
                cf.res_err20_pct = (e.resistance_ohm - r) / r * 100.0;
            }
        }
    }
    if (!est.empty() && est.back().has_rest_capacity) {
        cf.has_cap_rest = true;
        cf.cap_err_rest_pct = (est.back().rest_capacity_ah - t.pack_capacity_ah) / t.pack_capacity_ah * 100.0;
    }
    const long iend = index_at(est, t.landing_s);
    if (iend >= 0 && est[static_cast<size_t>(iend)].time_s >= t.takeoff_s) {
        const Estimate& e = est[static_cast<size_t>(iend)];
        if (e.has_capacity) {
            cf.has_cap_end = true;
            cf.cap_err_end_pct = (e.capacity_ah - t.pack_capacity_ah) / t.pack_capacity_ah * 100.0;
        }
        const double r = true_resistance(iend);
        if (e.has_resistance && std::isfinite(r)) {
            cf.has_res_end = true;
            cf.res_err_end_pct = (e.resistance_ohm - r) / r * 100.0;
        }
    }

    // Warnings over the whole log.
    double correct_cell_s = -1.0;
    bool correct_cell = false;
    for (const Estimate& e : est) {
        for (int w = 0; w < core::kWarnCount; ++w) {
            if ((e.warnings >> w) & 1u) {
                if (cf.first_warning_s[w] < 0.0) {
                    cf.first_warning_s[w] = e.time_s - t.takeoff_s;
                    if (cf.first_warning_s[w] < 0.0) cf.first_warning_s[w] = 0.0;  // raised on the ground
                }
            }
        }
        cf.fault_causes |= e.fault_cause;
        if ((e.warnings >> core::kWarnCellOutlier) & 1u) {
            cf.cell_warning = true;
            cf.named_cell = e.outlier_cell;
            if (!correct_cell && is_outlier(t.outlier_cells, e.outlier_cell)) {
                correct_cell = true;
                correct_cell_s = std::max(0.0, e.time_s - t.takeoff_s);
            }
        }
    }
    cf.sensor_warning = cf.first_warning_s[core::kWarnSensorFault] >= 0.0;
    const double deadline = 0.2 * total;
    if (t.short_flight()) {
        const auto in_time = [&](int w) { return cf.first_warning_s[w] >= 0.0 && cf.first_warning_s[w] <= deadline; };
        if (has_warning(t.justified_warnings, "low_capacity") && in_time(core::kWarnLowCapacity)) cf.warned_in_time = true;
        if (has_warning(t.justified_warnings, "high_resistance") && in_time(core::kWarnHighResistance)) cf.warned_in_time = true;
        if (correct_cell && correct_cell_s <= deadline) cf.warned_in_time = true;
    }
    if (cf.first_warning_s[core::kWarnLowCapacity] >= 0.0 && !has_warning(t.justified_warnings, "low_capacity"))
        cf.false_warnings.push_back("low_capacity");
    if (cf.first_warning_s[core::kWarnHighResistance] >= 0.0 && !has_warning(t.justified_warnings, "high_resistance"))
        cf.false_warnings.push_back("high_resistance");
    if (cf.first_warning_s[core::kWarnShortFlight] >= 0.0 && !t.short_flight()) cf.false_warnings.push_back("short_flight");
    return cf;
}

// Reads a log with the standard readers, exactly as `battsim replay` would.
std::vector<core::Sample> read_samples(const std::string& path, const sim::SimulationResult& sim) {
    ReaderOptions ro;
    ro.format = sim.format == sim::SimLogFormat::Raw         ? LogFormat::RawPbms
                : sim.format == sim::SimLogFormat::DataFlash ? LogFormat::DataflashBinary
                : sim.format == sim::SimLogFormat::ULog      ? LogFormat::Ulog
                                                              : LogFormat::Csv;
    ro.shunt = sim.scenario.config.monitor.shunt;
    std::unique_ptr<SampleReader> reader = open_reader(path, ro);
    std::vector<core::Sample> out;
    core::Sample s;
    while (reader->next(s)) out.push_back(s);
    return out;
}

// --- aggregation -----------------------------------------------------------------------

struct Stat {
    std::vector<double> v;
    void add(bool has, double x) {
        if (has) v.push_back(x);
    }
    double median_abs() const {
        std::vector<double> a;
        for (double x : v) a.push_back(std::fabs(x));
        return host::median(a);
    }
    double median() const { return host::median(v); }
    double max() const {
        double m = NAN;
        for (double x : v) {
            if (std::isnan(m) || x > m) m = x;
        }
        return m;
    }
    double worst() const {
        double w = NAN;
        for (double x : v) {
            if (std::isnan(w) || std::fabs(x) > std::fabs(w)) w = x;
        }
        return w;
    }
};

struct Count {
    int k = 0, n = 0;
};

struct Row {
    std::string key;    // JSON key
    std::string label;  // table text
    enum Kind { Median, Worst, SignedMedian, Max, Counted } kind;
    std::vector<Stat> stats;    // per column (Median/Worst)
    std::vector<Count> counts;  // per column (Counted)
};

std::vector<Row> build_rows(const ScoreResult& r) {
    const size_t nc = r.columns.size();
    std::vector<Row> rows;
    const auto add_pair = [&](const std::string& key, const std::string& label,
                              const std::function<void(const FlightScore&, const ColumnFlight&, Stat&)>& f) {
        Row med{key, label + ", median |err| %", Row::Median, std::vector<Stat>(nc), {}};
        for (const FlightScore& fl : r.flights)
            for (size_t c = 0; c < nc; ++c) f(fl, fl.columns[c], med.stats[c]);
        Row worst{key, std::string(label.size() + 2, ' ') + "worst %", Row::Worst, med.stats, {}};
        rows.push_back(med);
        rows.push_back(worst);
    };
    const char* pct[3] = {"10", "20", "50"};
    for (int p = 0; p < 3; ++p) {
        add_pair(std::string("remaining_time_") + pct[p], std::string("remaining time at ") + pct[p] + " %",
                 [p](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_rt[p], c.rt_err_pct[p]); });
    }
    // Against the floor: per flight, this column's |error| minus the oracle's, in points.
    const auto oracle = std::find(r.columns.begin(), r.columns.end(), "oracle");
    if (oracle != r.columns.end()) {
        const size_t o = static_cast<size_t>(oracle - r.columns.begin());
        Row med{"remaining_time_20_above_oracle", "remaining time at 20 %, |err| minus the oracle's, median points",
                Row::SignedMedian, std::vector<Stat>(nc), {}};
        for (const FlightScore& fl : r.flights) {
            const ColumnFlight& oc = fl.columns[o];
            for (size_t c = 0; c < nc; ++c) {
                const ColumnFlight& cc = fl.columns[c];
                med.stats[c].add(cc.has_rt[1] && oc.has_rt[1], std::fabs(cc.rt_err_pct[1]) - std::fabs(oc.rt_err_pct[1]));
            }
        }
        Row most{"remaining_time_20_above_oracle", std::string(24, ' ') + "largest, points", Row::Max, med.stats, {}};
        rows.push_back(med);
        rows.push_back(most);
    }
    {
        Row med{"remaining_time_20_sensor_faults", "remaining time at 20 %, sensor-fault flights, median |err| %",
                Row::Median, std::vector<Stat>(nc), {}};
        for (const FlightScore& fl : r.flights)
            for (size_t c = 0; c < nc; ++c)
                if (fl.sensor_faulty) med.stats[c].add(fl.columns[c].has_rt[1], fl.columns[c].rt_err_pct[1]);
        rows.push_back(med);
    }
    add_pair("remaining_energy_20", "remaining energy at 20 %",
             [](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_energy20, c.energy_err20_pct); });
    add_pair("capacity_20", "capacity at 20 %",
             [](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_cap20, c.cap_err20_pct); });
    add_pair("capacity_end", "capacity at the end",
             [](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_cap_end, c.cap_err_end_pct); });
    add_pair("capacity_after_rest", "capacity after the landing rest",
             [](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_cap_rest, c.cap_err_rest_pct); });
    add_pair("resistance_20", "resistance at 20 %",
             [](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_res20, c.res_err20_pct); });
    add_pair("resistance_end", "resistance at the end",
             [](const FlightScore&, const ColumnFlight& c, Stat& s) { s.add(c.has_res_end, c.res_err_end_pct); });

    const auto add_count = [&](const std::string& key, const std::string& label,
                               const std::function<void(const FlightScore&, const ColumnFlight&, Count&)>& f) {
        Row row{key, label, Row::Counted, {}, std::vector<Count>(nc)};
        for (const FlightScore& fl : r.flights)
            for (size_t c = 0; c < nc; ++c) f(fl, fl.columns[c], row.counts[c]);
        rows.push_back(row);
    };
    add_count("early_warnings", "early warnings (short flights warned by 20 %, right cause)",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (!f.short_flight) return;
                  ++n.n;
                  if (c.warned_in_time) ++n.k;
              });
    add_count("false_warnings", "false health warnings (flights)", [](const FlightScore&, const ColumnFlight& c, Count& n) {
        ++n.n;
        if (!c.false_warnings.empty()) ++n.k;
    });
    add_count("false_warnings_undegraded", "  of which on undegraded packs",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (f.degraded) return;
                  ++n.n;
                  if (!c.false_warnings.empty()) ++n.k;
              });
    add_count("cell_outlier_true_positives", "cell outlier: weak cell named",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (f.weak_cell < 0) return;
                  ++n.n;
                  if (c.cell_warning && is_outlier(f.outlier_cells, c.named_cell)) ++n.k;
              });
    add_count("cell_outlier_false_positives", "cell outlier: false alarms (flights)",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  ++n.n;
                  if (c.cell_warning && !is_outlier(f.outlier_cells, c.named_cell)) ++n.k;
              });
    add_count("sensor_faults_flagged", "sensor faults flagged as sensor faults",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (!f.sensor_faulty) return;
                  ++n.n;
                  if (c.sensor_warning) ++n.k;
              });
    add_count("sensor_faults_cause_named", "sensor faults named by their cause",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (f.nameable_fault_causes == 0) return;  // a gain error: no flight shows it
                  ++n.n;
                  if (c.sensor_warning && (c.fault_causes & f.nameable_fault_causes) == f.nameable_fault_causes) ++n.k;
              });
    add_count("sensor_faults_blamed_on_cells", "sensor faults blamed on cells",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (!f.sensor_faulty) return;
                  ++n.n;
                  if (c.cell_warning && !is_outlier(f.outlier_cells, c.named_cell)) ++n.k;
              });
    add_count("sensor_false_alarms", "sensor-fault warnings on clean logs",
              [](const FlightScore& f, const ColumnFlight& c, Count& n) {
                  if (f.sensor_faulty) return;
                  ++n.n;
                  if (c.sensor_warning) ++n.k;
              });
    return rows;
}

std::string fmt_pct(double x) {
    if (std::isnan(x)) return "-";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f", x == 0.0 ? 0.0 : x);
    if (std::string(buf) == "-0.0") return "0.0";
    return buf;
}

json num_or_null(double x) { return std::isnan(x) ? json(nullptr) : json(sim::round_fixed(x, 3)); }

}  // namespace

FlightScore score_flight(const sim::SimulationResult& sim, const std::vector<core::Sample>& samples,
                         const std::vector<EstimatorColumn>& columns) {
    const sim::Truth& t = sim.truth;
    FlightScore f;
    f.name = sim.scenario.name;
    f.kind = sim::to_string(sim.scenario.profile.kind);
    f.cells = sim.scenario.pack.cells;
    f.total_flight_time_s = t.total_flight_time_s;
    f.healthy_total_flight_time_s = t.healthy_total_flight_time_s;
    f.flown_s = t.landing_s - t.takeoff_s;
    f.short_flight = t.short_flight();
    f.degraded = t.degraded;
    f.sensor_faulty = t.sensor_faulty;
    f.nameable_fault_causes = sim::nameable_fault_causes(sim.scenario.sensor.faults);
    f.weak_cell = t.weak_cell;
    f.outlier_cells = t.outlier_cells;
    f.justified = t.justified_warnings;
    // Every point past the landing is left out, not only 50 %'s (a 15 s flight loses all three).
    std::vector<std::string> left_out;
    for (double fraction : kFractions)
        if (f.flown_s < fraction * t.total_flight_time_s) left_out.push_back(std::to_string(std::lround(fraction * 100.0)) + " %");
    if (!left_out.empty()) {
        std::string points = left_out.back();
        if (left_out.size() >= 2) points = left_out[left_out.size() - 2] + " and " + points;
        if (left_out.size() == 3) points = left_out[0] + ", " + points;
        f.notes.push_back("landed before " + left_out.front() + " of the flight: the " + points + " point" +
                          (left_out.size() > 1 ? "s are" : " is") + " left out");
    }

    // Which truth snapshot belongs to each sample (the same row of the log).
    std::vector<long> snap(samples.size(), -1);
    size_t k = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
        const int64_t ms = static_cast<int64_t>(samples[i].time_us / 1000);
        while (k < sim.snapshots.size() && sim.snapshots[k].time_ms < ms) ++k;
        if (k < sim.snapshots.size() && sim.snapshots[k].time_ms == ms) snap[i] = static_cast<long>(k);
    }

    FlightInput in;
    in.name = f.name;
    in.config = &sim.scenario.config;
    in.samples = &samples;
    in.truth = &sim;
    for (const EstimatorColumn& col : columns) {
        const std::vector<Estimate> est = col.run(in);
        if (est.size() != samples.size()) {
            throw std::logic_error("estimator " + col.name + " gave " + std::to_string(est.size()) + " estimates for " +
                                   std::to_string(samples.size()) + " samples");
        }
        f.columns.push_back(judge(est, sim, snap));
    }
    return f;
}

ScoreResult score_scenarios(const std::vector<sim::Scenario>& suite, const std::vector<EstimatorColumn>& columns,
                            const ScoreOptions& options) {
    if (options.copies < 1) throw std::invalid_argument("--copies must be at least 1");
    if (options.copies > 1 && !options.logs_dir.empty())
        throw std::invalid_argument("--copies simulates its flights; it cannot read them from a --logs directory");
    std::vector<sim::Scenario> scenarios;
    std::vector<int> copy_of;
    for (int k = 0; k < options.copies; ++k) {
        for (const sim::Scenario& s : suite) {
            scenarios.push_back(sim::reseeded(s, k));
            copy_of.push_back(k);
        }
    }
    ScoreResult result;
    result.copies = options.copies;
    for (const EstimatorColumn& c : columns) {
        result.columns.push_back(c.name);
        result.descriptions.push_back(c.description);
    }
    result.flights.resize(scenarios.size());
    // The first failing scenario, in suite order, is the one reported.
    parallel_for(scenarios.size(), options.jobs, [&](size_t i) {
        sim::SimulateOptions so;
        so.keep_snapshots = true;
        const sim::SimulationResult simr = sim::simulate(scenarios[i], so);
        std::string path;
        // The log goes through a file, as a user's would; a scratch file, so that a
        // signal removes it too.
        std::unique_ptr<ScratchFile> scratch;
        if (options.logs_dir.empty()) {
            scratch = std::make_unique<ScratchFile>("battsim-score-");
            path = scratch->path();
            std::ofstream out(path, std::ios::binary);
            out << simr.log_text;
            if (!out) throw std::runtime_error(path + ": cannot write the temporary log");
        } else {
            path = options.logs_dir + "/" + simr.scenario.name + sim::sim_log_extension(simr.format);
        }
        std::vector<core::Sample> samples;
        try {
            samples = read_samples(path, simr);
        } catch (const InputError& e) {
            // The temporary log is gone by the time this is read: name the scenario.
            // A simulated log is gone by now: its line is all there is to say. A log of
            // --logs is the user's file: its path, line and column.
            if (!options.logs_dir.empty())
                throw InputError(scenarios[i].source_path, 0, 0,
                                 "scenario " + simr.scenario.name + ": its log in --logs cannot be read: " + e.what());
            throw InputError(scenarios[i].source_path, 0, 0,
                             "scenario " + simr.scenario.name + ": its simulated log cannot be read back" +
                                 (e.line() > 0 ? " (line " + std::to_string(e.line()) + ")" : std::string()) +
                                 ": " + e.message());
        }
        scratch.reset();
        if (!options.logs_dir.empty()) {
            // The truth is this scenario's as it is now: a log of another seed or of an
            // edited scenario would be graded against another flight's truth.
            std::ifstream in(path, std::ios::binary);
            std::stringstream buf;
            buf << in.rdbuf();
            if (buf.str() != simr.log_text)
                throw InputError(path, 0, 0,
                                 "not the log scenario " + simr.scenario.name + " (" + scenarios[i].source_path +
                                     ") simulates as it is now (written with another --seed, --format or "
                                     "--cutoff-v-per-cell, or from an edited scenario): its truth would not match the "
                                     "log; re-simulate it with `battsim simulate SCENARIO --out-dir " +
                                     options.logs_dir + "`");
        }
        result.flights[i] = score_flight(simr, samples, columns);
        result.flights[i].copy = copy_of[i];
        // A flight the monitor never sees is scored all the same: said, as simulate says it.
        const std::string unseen = sim::flight_draw_note(simr);
        if (!unseen.empty()) result.flights[i].notes.push_back(unseen);
        if (simr.truth.sensor_stats.current_clipped > 0)
            result.flights[i].notes.push_back("the simulated current sensor clipped " +
                                              std::to_string(simr.truth.sensor_stats.current_clipped) + " of " +
                                              std::to_string(simr.truth.sensor_stats.reads) +
                                              " reads at its shunt range: the log's current is wrong there");
    });
    return result;
}

namespace {

// The flights of one copy of the suite, as a result of their own.
ScoreResult copy_result(const ScoreResult& r, int copy) {
    ScoreResult c;
    c.columns = r.columns;
    c.descriptions = r.descriptions;
    for (const FlightScore& f : r.flights)
        if (f.copy == copy) c.flights.push_back(f);
    return c;
}

std::vector<std::vector<Row>> rows_by_copy(const ScoreResult& r) {
    std::vector<std::vector<Row>> by;
    if (r.copies > 1)
        for (int k = 0; k < r.copies; ++k) by.push_back(build_rows(copy_result(r, k)));
    return by;
}

// A row's figure for column c: NaN when it has none (Counted rows give k).
double row_value(const Row& row, size_t c) {
    switch (row.kind) {
        case Row::Median: return row.stats[c].median_abs();
        case Row::Worst: return row.stats[c].worst();
        case Row::SignedMedian: return row.stats[c].median();
        case Row::Max: return row.stats[c].max();
        default: return row.counts[c].k;
    }
}

std::string cell_text(const Row& row, size_t c) {
    if (row.kind == Row::Counted) return std::to_string(row.counts[c].k) + "/" + std::to_string(row.counts[c].n);
    return fmt_pct(row_value(row, c));
}

// The copies' lowest and highest figure for row i, column c (NaN, NaN when none has one).
// A Worst row's figures are signed; they are ordered by magnitude (the mildest copy's worst,
// then the harshest's).
std::pair<double, double> copy_range(const std::vector<std::vector<Row>>& by, size_t i, size_t c) {
    const bool by_magnitude = !by.empty() && by[0][i].kind == Row::Worst;
    const auto key = [by_magnitude](double x) { return by_magnitude ? std::fabs(x) : x; };
    double lo = NAN, hi = NAN;
    for (const std::vector<Row>& rows : by) {
        const double x = row_value(rows[i], c);
        if (std::isnan(x)) continue;
        if (std::isnan(lo) || key(x) < key(lo)) lo = x;
        if (std::isnan(hi) || key(x) > key(hi)) hi = x;
    }
    return {lo, hi};
}

// " (lowest..highest)" of the copies' figures for row i, column c; counts as k/n, ordered
// by their share (the copies need not have the same n: outlier cells come from the draw).
std::string range_text(const std::vector<std::vector<Row>>& by, size_t i, size_t c) {
    if (by[0][i].kind == Row::Counted) {
        const Count* lo = nullptr;
        const Count* hi = nullptr;
        const auto share = [](const Count* n) { return n->n > 0 ? static_cast<double>(n->k) / n->n : 0.0; };
        for (const std::vector<Row>& rows : by) {
            const Count* n = &rows[i].counts[c];
            if (n->n == 0) continue;
            if (!lo || share(n) < share(lo)) lo = n;
            if (!hi || share(n) > share(hi)) hi = n;
        }
        if (!lo) return " (-)";
        const auto text = [](const Count* n) { return std::to_string(n->k) + "/" + std::to_string(n->n); };
        return " (" + text(lo) + ".." + text(hi) + ")";
    }
    const std::pair<double, double> range = copy_range(by, i, c);
    if (std::isnan(range.first)) return " (-)";
    return " (" + fmt_pct(range.first) + ".." + fmt_pct(range.second) + ")";
}

}  // namespace

std::string format_table(const ScoreResult& r) {
    int n_short = 0, n_degraded = 0, n_fault = 0;
    for (const FlightScore& f : r.flights) {
        n_short += f.short_flight;
        n_degraded += f.degraded;
        n_fault += f.sensor_faulty;
    }
    std::ostringstream out;
    out << "battsim score: " << r.flights.size() << " flights (" << n_short << " short, " << n_degraded
        << " degraded packs, " << n_fault << " with sensor faults); errors in % (time: of the true total flight time)\n";
    if (r.copies > 1) {
        out << "  " << r.copies << " copies of the suite (copy k: seeds + 7919 k); each figure over all of them, then (the "
            << "copies' lowest..highest)\n";
    }
    const std::vector<Row> rows = build_rows(r);
    const std::vector<std::vector<Row>> by = rows_by_copy(r);
    std::vector<std::vector<std::string>> cells(rows.size(), std::vector<std::string>(r.columns.size()));
    for (size_t i = 0; i < rows.size(); ++i) {
        for (size_t c = 0; c < r.columns.size(); ++c) {
            cells[i][c] = cell_text(rows[i], c);
            if (!by.empty()) cells[i][c] += range_text(by, i, c);
        }
    }
    size_t label_w = 6;
    for (const Row& row : rows) label_w = std::max(label_w, row.label.size());
    size_t col_w = 10;
    for (const std::string& c : r.columns) col_w = std::max(col_w, c.size() + 2);
    for (const auto& line : cells)
        for (const std::string& cell : line) col_w = std::max(col_w, cell.size() + 2);
    const auto pad_right = [](const std::string& s, size_t w) { return s + std::string(w > s.size() ? w - s.size() : 0, ' '); };
    const auto pad_left = [](const std::string& s, size_t w) { return std::string(w > s.size() ? w - s.size() : 0, ' ') + s; };
    out << pad_right("metric", label_w);
    for (const std::string& c : r.columns) out << pad_left(c, col_w);
    out << "\n";
    for (size_t i = 0; i < rows.size(); ++i) {
        out << pad_right(rows[i].label, label_w);
        for (size_t c = 0; c < r.columns.size(); ++c) out << pad_left(cells[i][c], col_w);
        out << "\n";
    }
    return out.str();
}

namespace {

json summary_json(const std::vector<Row>& rows, const std::vector<std::string>& columns) {
    json summary = json::object();
    for (const Row& row : rows) {
        json& m = summary[row.key];
        for (size_t c = 0; c < columns.size(); ++c) {
            const std::string& col = columns[c];
            if (row.kind == Row::Median) {
                m[col]["median_abs"] = num_or_null(row.stats[c].median_abs());
                m[col]["n"] = row.stats[c].v.size();
            } else if (row.kind == Row::Worst) {
                m[col]["worst"] = num_or_null(row.stats[c].worst());
            } else if (row.kind == Row::SignedMedian) {
                m[col]["median"] = num_or_null(row.stats[c].median());
                m[col]["n"] = row.stats[c].v.size();
            } else if (row.kind == Row::Max) {
                m[col]["max"] = num_or_null(row.stats[c].max());
            } else {
                m[col] = {{"count", row.counts[c].k}, {"of", row.counts[c].n}};
            }
        }
    }
    return summary;
}

}  // namespace

json to_json(const ScoreResult& r) {
    json j;
    j["schema"] = kScoreSchema;
    j["schema_version"] = kScoreVersion;
    j["battsim_version"] = BATTSIM_VERSION;
    json cols = json::array();
    for (size_t c = 0; c < r.columns.size(); ++c) cols.push_back({{"name", r.columns[c]}, {"description", r.descriptions[c]}});
    j["columns"] = cols;
    j["definitions"] = {
        {"flight_fraction", "of the true total flight time T (take-off to the pack's cutoff flying on at the same demand)"},
        {"remaining_time_error", "(estimate - truth) / T, in % of T, at the last sample at or before the fraction"},
        {"remaining_time_20_above_oracle", "per flight |error| minus the oracle's |error| at 20 %, in points of T"},
        {"remaining_energy_error", "(estimate - truth) / truth, in %, energy to the cutoff"},
        {"capacity_error", "(estimate - weakest cell capacity) / weakest cell capacity, in %"},
        {"resistance_error", "(estimate - pack series ohmic resistance at that instant) / truth, in %"},
        {"capacity_after_rest", "capacity read from the rests before and after the flight, at the end of the log, against the weakest cell's"},
        {"short_flight", "T < 0.8 x the healthy twin's T"},
        {"false_warning", "low capacity or high resistance warning the pack does not justify, or short flight on a flight that is not short"},
        {"sensor_fault_blamed_on_cell", "on a sensor-fault flight, a named cell that is not one of the pack's outlier cells"},
        {"sensor_fault_cause_named", "on a flight with an offset, a loose balance tap or dropouts of a second or more, the sensor-fault warning names each (current_offset, cells, sample_gap); a gain error shows in no flight and is left out"},
        {"copies", "copy k > 0 of the suite adds 7919 k to every scenario's seed and names its flights NAME@k; summary pools every copy, summary_by_copy has each"}};
    j["copies"] = r.copies;
    j["summary"] = summary_json(build_rows(r), r.columns);
    if (r.copies > 1) {
        json by = json::array();
        for (const std::vector<Row>& rows : rows_by_copy(r)) by.push_back(summary_json(rows, r.columns));
        j["summary_by_copy"] = by;
    }
    json flights = json::array();
    for (const FlightScore& f : r.flights) {
        json fj = {{"name", f.name},
                   {"copy", f.copy},
                   {"kind", f.kind},
                   {"cells", f.cells},
                   {"total_flight_time_s", sim::round_fixed(f.total_flight_time_s, 3)},
                   {"healthy_total_flight_time_s", sim::round_fixed(f.healthy_total_flight_time_s, 3)},
                   {"flown_s", sim::round_fixed(f.flown_s, 3)},
                   {"short_flight", f.short_flight},
                   {"degraded", f.degraded},
                   {"justified_warnings", f.justified},
                   {"weak_cell", f.weak_cell >= 0 ? json(f.weak_cell + 1) : json(nullptr)},
                   {"outlier_cells", [&] {
                        json a = json::array();
                        for (int c : f.outlier_cells) a.push_back(c + 1);
                        return a;
                    }()},
                   {"sensor_faulty", f.sensor_faulty},
                   {"nameable_sensor_fault_causes", sensor_fault_cause_names(f.nameable_fault_causes)},
                   {"notes", f.notes}};
        json per = json::object();
        for (size_t c = 0; c < r.columns.size(); ++c) {
            const ColumnFlight& cf = f.columns[c];
            const auto opt = [](bool has, double x) { return has ? json(sim::round_fixed(x, 3)) : json(nullptr); };
            json warn = json::object();
            for (int w = 0; w < core::kWarnCount; ++w) {
                warn[warning_name(static_cast<core::Warning>(w))] =
                    cf.first_warning_s[w] >= 0.0 ? json(sim::round_fixed(cf.first_warning_s[w], 3)) : json(nullptr);
            }
            per[r.columns[c]] = {{"remaining_time_error_pct", {opt(cf.has_rt[0], cf.rt_err_pct[0]), opt(cf.has_rt[1], cf.rt_err_pct[1]), opt(cf.has_rt[2], cf.rt_err_pct[2])}},
                                 {"remaining_energy_error_20_pct", opt(cf.has_energy20, cf.energy_err20_pct)},
                                 {"capacity_error_20_pct", opt(cf.has_cap20, cf.cap_err20_pct)},
                                 {"capacity_error_end_pct", opt(cf.has_cap_end, cf.cap_err_end_pct)},
                                 {"capacity_error_after_rest_pct", opt(cf.has_cap_rest, cf.cap_err_rest_pct)},
                                 {"resistance_error_20_pct", opt(cf.has_res20, cf.res_err20_pct)},
                                 {"resistance_error_end_pct", opt(cf.has_res_end, cf.res_err_end_pct)},
                                 {"first_warning_after_takeoff_s", warn},
                                 {"warned_in_time", cf.warned_in_time},
                                 {"false_warnings", cf.false_warnings},
                                 {"sensor_fault_causes", sensor_fault_cause_names(cf.fault_causes)},
                                 {"named_cell", cf.cell_warning && cf.named_cell >= 0 ? json(cf.named_cell + 1) : json(nullptr)}};
        }
        fj["estimators"] = per;
        flights.push_back(fj);
    }
    j["flights"] = flights;
    return j;
}

}  // namespace score
}  // namespace host
}  // namespace battsim
