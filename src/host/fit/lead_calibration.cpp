#include "host/fit/lead_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "host/report/summary.h"

namespace battsim {
namespace host {

namespace {

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Median and sample standard deviation; with fewer than three values the spread cannot be
// told, and at least 0.1 (the core's default allowance) stands in for it.
void pool(const std::vector<double>& v, double& centre, double& spread) {
    centre = median_of(v);
    double mean = 0.0;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    double ss = 0.0;
    for (double x : v) ss += (x - mean) * (x - mean);
    spread = v.size() >= 3 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : std::max(0.1, std::sqrt(ss));
}

}  // namespace

LeadCalibration calibrate_cell_leads(const std::vector<std::string>& logs, const ReplayOptions& base) {
    LeadCalibration out;
    ReplayOptions opt = base;
    opt.series_path.clear();
    opt.realtime_speed = 0;
    opt.config.monitor.estimator = core::EstimatorKind::Joint;
    const core::CellAnalyzer::Config& ca = opt.config.monitor.cell_analysis;
    out.first_lead = ca.first_cell_includes_lead;
    out.last_lead = ca.last_cell_includes_lead;
    std::vector<double> first, last;  // the flights pooled: read by the short-lag fit
    bool three_cell_said = false;
    for (const std::string& log : logs) {
        const nlohmann::json summary = replay_log(log, opt);
        for (const std::string& note : log_notes(summary)) out.notes.push_back(log + ": " + note);
        const auto flight = summary.find("flight");
        const nlohmann::json* r = nullptr;
        if (flight != summary.end() && flight->is_object()) {
            const auto it = flight->find("cell_resistance_ohm");
            if (it != flight->end() && it->is_array()) r = &*it;
        }
        // A lead cell needs two others to be compared with.
        if (!r || r->size() < 3) {
            out.logs_without_cells.push_back(log);
            continue;
        }
        LeadCalibrationFlight f;
        f.log = log;
        f.source = flight->value("cell_resistance_source", "");
        bool measured = true;
        for (const nlohmann::json& v : *r) {
            const double ohm = v.is_number() ? v.get<double>() : 0.0;
            measured = measured && ohm > 0.0;
            f.cell_resistance_ohm.push_back(ohm);
        }
        if (!measured) {
            out.logs_without_cells.push_back(log);
            continue;
        }
        // A log for another cell count than the config's was read against the wrong pack.
        if (static_cast<int>(f.cell_resistance_ohm.size()) != opt.config.monitor.cells_in_series) {
            out.notes.push_back(log + ": " + std::to_string(f.cell_resistance_ohm.size()) + " cells, the config's " +
                                std::to_string(opt.config.monitor.cells_in_series) + ": left out");
            continue;
        }
        // A flight given twice (a byte copy under another name) would halve the spread.
        bool twice = false;
        for (const LeadCalibrationFlight& g : out.flights) twice = twice || g.cell_resistance_ohm == f.cell_resistance_ohm;
        if (twice) {
            out.notes.push_back(log + ": the same per-cell resistances as a flight before it (a copy?): left out");
            continue;
        }
        const std::vector<double>& cr = f.cell_resistance_ohm;
        const size_t n = cr.size();
        // As the cell check compares: the last cell with every other cell, cell 1 with the
        // cells between the leads (the last cell's reading is not the cell's).
        f.last_excess = cr[n - 1] / median_of(std::vector<double>(cr.begin(), cr.end() - 1)) - 1.0;
        const size_t inner_end = out.last_lead ? n - 1 : n;
        f.has_first = out.first_lead && inner_end >= 3;
        if (f.has_first) f.first_excess = cr[0] / median_of(std::vector<double>(cr.begin() + 1, cr.begin() + inner_end)) - 1.0;
        if (out.first_lead && !f.has_first && !three_cell_said) {
            out.notes.push_back("cell 1 has a single cell between the leads to be compared with: its share is not "
                                "calibrated, and it is not judged for resistance");
            three_cell_said = true;
        }
        out.flights.push_back(f);
    }
    // The short-lag fit's values and the big steps' differ where the taps convert slower than
    // the bus: the steps, between steady windows, see settled voltages, the short-lag pairs the
    // taps' lag (the lead-cell suite's healthy last cell: +0.1…+0.4 by a hover's steps, +1.3…+1.6
    // by racing differences). A share read off the steps would be taken off the short-lag
    // values too, and would blame healthy last cells on racing flights. So only the short-lag
    // fit's flights are pooled, and with none the calibration fails (`steps_only`).
    size_t left_out = 0;
    for (LeadCalibrationFlight& f : out.flights) {
        f.used = f.source == "differences";
        left_out += f.used ? 0 : 1;
        if (!f.used) continue;
        if (out.last_lead) last.push_back(f.last_excess);
        if (f.has_first) first.push_back(f.first_excess);
    }
    out.steps_only = !out.flights.empty() && left_out == out.flights.size();
    if (left_out > 0 && !out.steps_only)
        out.notes.push_back(std::to_string(left_out) + " flight(s) read by the big steps alone (too little excitation for "
                            "the short-lag fit, as in a hover) left out: the cell check judges by the short-lag fit");
    if (!last.empty()) pool(last, out.last_excess, out.last_spread);
    if (!first.empty()) pool(first, out.first_excess, out.first_spread);
    // A share cannot be negative (wiring adds resistance); a median below zero is the cells'
    // own spread, and zero is what is taken off.
    out.last_excess = out.last_lead && !last.empty() ? std::max(0.0, out.last_excess) : -1.0;
    out.first_excess = out.first_lead && !first.empty() ? std::max(0.0, out.first_excess) : -1.0;
    out.sigma = std::max({LeadCalibration::kMinSigma, out.last_spread, out.first_spread});
    out.flights_used = std::max(last.size(), first.size());
    if (out.flights_used > 0 && out.flights_used < 3)
        out.notes.push_back("fewer than three flights: their spread is no measure, and at least 0.1 of the others' "
                            "median stands in for it; more flights, of several packs, give a tighter bar");
    return out;
}

void apply_lead_calibration(const LeadCalibration& c, LoadedConfig& config) {
    core::CellAnalyzer::Config& ca = config.monitor.cell_analysis;
    if (c.last_excess >= 0.0) ca.last_lead_excess = static_cast<float>(c.last_excess);
    if (c.first_excess >= 0.0) ca.first_lead_excess = static_cast<float>(c.first_excess);
    if (c.last_excess >= 0.0 || c.first_excess >= 0.0) ca.lead_excess_sigma = static_cast<float>(c.sigma);
}

nlohmann::json to_json(const LeadCalibration& c) {
    using nlohmann::json;
    json flights = json::array();
    for (const LeadCalibrationFlight& f : c.flights) {
        json r = json::array();
        for (double v : f.cell_resistance_ohm) r.push_back(round_sig(v, 4));
        flights.push_back({{"log", f.log},
                           {"cell_resistance_source", f.source},
                           {"used", f.used},
                           {"cell_resistance_ohm", r},
                           {"first_cell_excess", f.has_first ? json(round_sig(f.first_excess, 4)) : json(nullptr)},
                           {"last_cell_excess", c.last_lead ? json(round_sig(f.last_excess, 4)) : json(nullptr)}});
    }
    const auto value = [](double v) { return v >= 0.0 ? json(round_sig(v, 4)) : json(nullptr); };
    return {{"schema", "battsim.lead_calibration"},
            {"schema_version", 1},
            {"battsim_version", BATTSIM_VERSION},
            {"first_cell_includes_lead", c.first_lead},
            {"last_cell_includes_lead", c.last_lead},
            {"flights", flights},
            {"flights_used", c.flights_used},
            {"logs_without_cells", c.logs_without_cells},
            {"first_cell_lead_excess", value(c.first_excess)},
            {"first_cell_spread", c.first_excess >= 0.0 ? json(round_sig(c.first_spread, 4)) : json(nullptr)},
            {"last_cell_lead_excess", value(c.last_excess)},
            {"last_cell_spread", c.last_excess >= 0.0 ? json(round_sig(c.last_spread, 4)) : json(nullptr)},
            {"cell_lead_excess_sigma", round_sig(c.sigma, 4)},
            {"notes", c.notes}};
}

}  // namespace host
}  // namespace battsim
