// Calibrates a pack's polarisation shape from its own flights. Within a flight a larger slow
// polarisation cannot be told from a lost capacity (both make the pack sag faster), so the
// joint estimator's in-flight capacity rests on the health filter's polarisation shape being
// the pack's (docs/estimator.md, twenty-third session). The capacity read off the rests
// before and after a flight does not depend on that shape. So: replay the pack's logs with
// each candidate slow share of the health filter, and keep the one whose in-flight capacity
// at the end agrees best with the rests' — the config's own share unless it is off by more
// than a tolerance. The result is a config for the pack's next flights.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/replay.h"

namespace battsim {
namespace host {

struct ShapeCalibrationOptions {
    std::vector<double> slow_shares = {0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6};
    // The config's own share is kept while its mean |final / rest − 1| is within this: the
    // rest's capacity is itself good to a few per cent (1.5–1.7 % median on the suites).
    double tolerance = 0.05;
};

struct ShapeCandidate {
    double slow_share = 0.0;
    std::vector<double> final_ah;  // per log with a rest (the in-flight capacity at the end)
    double mean_abs_error = 0.0;   // mean |final / rest − 1| over those logs
};

struct ShapeCalibration {
    double configured_share = 0.0;
    double chosen_share = 0.0;
    bool changed = false;
    std::vector<std::string> logs;          // the logs with a rest after a flight, in order
    std::vector<double> rest_ah;            // their capacity from the rests (shape-independent)
    std::vector<std::string> logs_without_rest;
    std::vector<ShapeCandidate> candidates; // the configured share first
    // When even the chosen share misses the rests by more than the tolerance: the shape is
    // not what keeps the in-flight capacity from the rests', and that is said.
    std::vector<std::string> notes;
};

// Replays each log with the joint estimator, whatever `base.config` selects. Throws
// InputError for a bad log, std::invalid_argument for a share outside [0, 1]. With no log
// that has a rest after a flight, `logs` and `candidates` come back empty and the configured
// share stands.
ShapeCalibration calibrate_slow_share(const std::vector<std::string>& logs, const ReplayOptions& base,
                                      const ShapeCalibrationOptions& options);

// The rule: the first candidate (the configured share) while its error is within
// `tolerance`, else the smallest error, the share nearer the configured one on a tie.
size_t choose_candidate(const std::vector<ShapeCandidate>& candidates, double tolerance);

nlohmann::json to_json(const ShapeCalibration& c);

}  // namespace host
}  // namespace battsim
