// Calibrates a monitor's lead cells from flights of healthy packs. On the reference logger the
// last cell is read as pack − last balance tap, across the main lead and the two converters,
// and cell 1 against a ground that may carry part of the main current's return: their
// short-lag resistance reads more than the cell's own (the last cell 2.1–2.3 × the others on
// the dissertation's new and aged packs alike, where the charger measured it as the others).
// That share belongs to the monitor's wiring, not to the pack, so it is measured once: replay
// each flight with the joint estimator and take each lead cell's resistance over the others'
// median, less one. The median over the flights is the share the cell check then takes off
// (`joint.last_cell_lead_excess`, `first_cell_lead_excess`), their spread its allowance
// (`joint.cell_lead_excess_sigma`). It assumes the packs' lead cells are as healthy as the
// others; several packs' flights keep one that is not from setting the value.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/replay.h"

namespace battsim {
namespace host {

struct LeadCalibrationFlight {
    std::string log;
    std::string source;                     // "differences" or "steps" (the summary's cell_resistance_source)
    std::vector<double> cell_resistance_ohm;
    double first_excess = 0.0;              // cell 1 over the median of the cells between the leads, − 1
    double last_excess = 0.0;               // the last cell over the median of all the others, − 1
    bool has_first = false;                 // cell 1 is a lead cell and has two cells to compare with
    bool used = false;                      // pooled: read by the short-lag fit
};

struct LeadCalibration {
    bool first_lead = false;  // the config's first_cell_includes_lead / last_cell_includes_lead
    bool last_lead = false;
    std::vector<LeadCalibrationFlight> flights;
    std::vector<std::string> logs_without_cells;  // no per-cell resistance (no cells, or no flight)
    // Medians over the flights read by the short-lag fit, and their spreads (sample standard
    // deviation; with fewer than three flights at least 0.1). −1: not measured.
    double first_excess = -1.0, first_spread = 0.0;
    double last_excess = -1.0, last_spread = 0.0;
    double sigma = 0.0;  // what the config gets: the larger spread, at least kMinSigma
    size_t flights_used = 0;
    bool steps_only = false;  // every flight read by the steps alone: nothing to calibrate from
    std::vector<std::string> notes;
    // The core's default allowance: a spread measured on a few flights of like packs had been
    // 0.05 on new packs alone, and cell 1 of an aged pack then read 0.13–0.23 over them.
    static constexpr double kMinSigma = 0.1;
};

// Replays each log with the joint estimator, whatever `base.config` selects. Throws InputError
// for a bad log.
LeadCalibration calibrate_cell_leads(const std::vector<std::string>& logs, const ReplayOptions& base);

// Writes the calibration's keys into a config (the lead cells measured; σ as calibrated).
void apply_lead_calibration(const LeadCalibration& c, LoadedConfig& config);

nlohmann::json to_json(const LeadCalibration& c);

}  // namespace host
}  // namespace battsim
