#include "host/fit/shape_calibration.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "host/report/summary.h"

namespace battsim {
namespace host {

namespace {

// The in-flight capacity at the end and the one from the rests, from one replay's summary
// (rest: 0 when the log has no rest after a flight).
void read_capacities(const nlohmann::json& summary, double& final_ah, double& rest_ah) {
    final_ah = rest_ah = 0.0;
    const auto flight = summary.find("flight");
    if (flight == summary.end() || !flight->is_object()) return;
    const auto cap = flight->find("capacity_ah");
    if (cap == flight->end() || !cap->is_object()) return;
    if (cap->contains("final") && (*cap)["final"].is_number()) final_ah = (*cap)["final"].get<double>();
    if (cap->contains("after_rest") && (*cap)["after_rest"].is_number()) rest_ah = (*cap)["after_rest"].get<double>();
}

}  // namespace

size_t choose_candidate(const std::vector<ShapeCandidate>& candidates, double tolerance) {
    // Keep the configured share (the first) within the tolerance; otherwise the best, the
    // nearer to the configured one on a tie (ties happen where a share does not move the end
    // capacity).
    if (candidates.empty() || candidates.front().mean_abs_error <= tolerance) return 0;
    const double configured = candidates.front().slow_share;
    size_t best = 0;
    for (size_t k = 1; k < candidates.size(); ++k) {
        const double d = candidates[k].mean_abs_error - candidates[best].mean_abs_error;
        const bool nearer = std::fabs(candidates[k].slow_share - configured) < std::fabs(candidates[best].slow_share - configured);
        if (d < -1e-12 || (std::fabs(d) <= 1e-12 && nearer)) best = k;
    }
    return best;
}

ShapeCalibration calibrate_slow_share(const std::vector<std::string>& logs, const ReplayOptions& base,
                                      const ShapeCalibrationOptions& options) {
    ShapeCalibration out;
    ReplayOptions opt = base;
    opt.series_path.clear();
    opt.realtime_speed = 0;
    opt.config.monitor.estimator = core::EstimatorKind::Joint;
    out.configured_share = opt.config.monitor.joint.health.polarisation_slow_share;
    std::vector<double> shares{out.configured_share};
    for (double s : options.slow_shares) {
        if (!(s >= 0.0 && s <= 1.0)) throw std::invalid_argument("slow share " + std::to_string(s) + " is outside [0, 1]");
        if (std::fabs(s - out.configured_share) > 1e-6) shares.push_back(s);
    }
    // The configured share first: its replays decide which logs have a rest.
    for (size_t k = 0; k < shares.size(); ++k) {
        ShapeCandidate cand;
        cand.slow_share = shares[k];
        opt.config.monitor.joint.health.polarisation_slow_share = static_cast<float>(shares[k]);
        const std::vector<std::string>& used = k == 0 ? logs : out.logs;
        for (size_t i = 0; i < used.size(); ++i) {
            double final_ah = 0.0, rest_ah = 0.0;
            const nlohmann::json summary = replay_log(used[i], opt);
            read_capacities(summary, final_ah, rest_ah);
            if (k == 0) {
                // The real cause when a log has no rest: a config for another pack keeps its
                // samples out, which "no rest" alone had hidden; and what replay says of the
                // log's shape (a current of the other sign, a clock that jumps).
                for (const std::string& note : log_notes(summary))
                    out.notes.push_back(used[i] + ": " + note);
                if (!(rest_ah > 0.0) || !(final_ah > 0.0)) {
                    out.logs_without_rest.push_back(used[i]);
                    continue;
                }
                out.logs.push_back(used[i]);
                out.rest_ah.push_back(rest_ah);
            }
            const size_t j = cand.final_ah.size();
            cand.final_ah.push_back(final_ah);
            cand.mean_abs_error += std::fabs(final_ah / out.rest_ah[j] - 1.0);
        }
        if (k == 0 && out.logs.empty()) {  // nothing to calibrate on: the configured share stands
            out.chosen_share = out.configured_share;
            return out;
        }
        cand.mean_abs_error /= static_cast<double>(out.logs.size());
        out.candidates.push_back(cand);
    }
    const ShapeCandidate* best = &out.candidates[choose_candidate(out.candidates, options.tolerance)];
    out.chosen_share = best->slow_share;
    out.changed = std::fabs(out.chosen_share - out.configured_share) > 1e-6;
    if (best->mean_abs_error > options.tolerance) {
        double lo = best->slow_share, hi = best->slow_share;
        for (const ShapeCandidate& k : out.candidates) {
            lo = std::min(lo, k.slow_share);
            hi = std::max(hi, k.slow_share);
        }
        const bool edge = best->slow_share == lo || best->slow_share == hi;
        char buf[400];
        std::snprintf(buf, sizeof buf,
                      "the best share, %.3g%s, still misses the rests' capacities by %.1f %% (mean; tolerance %.1f %%): "
                      "the polarisation shape alone does not explain the gap; check the config's OCV table "
                      "(battsim fit-ocv), capacity and current sensor before trusting it",
                      best->slow_share, edge ? " (the edge of the shares tried)" : "", 100.0 * best->mean_abs_error,
                      100.0 * options.tolerance);
        out.notes.push_back(buf);
    }
    return out;
}

nlohmann::json to_json(const ShapeCalibration& c) {
    using nlohmann::json;
    json cands = json::array();
    for (const ShapeCandidate& k : c.candidates) {
        json f = json::array();
        for (double v : k.final_ah) f.push_back(round_sig(v));
        cands.push_back({{"slow_share", round_sig(k.slow_share)},
                         {"final_capacity_ah", f},
                         {"mean_abs_error", round_sig(k.mean_abs_error)}});
    }
    json rest = json::array();
    for (double v : c.rest_ah) rest.push_back(round_sig(v));
    return {{"schema", "battsim.shape_calibration"},
            {"schema_version", 1},
            {"battsim_version", BATTSIM_VERSION},  // as every other report: which release wrote it
            {"configured_slow_share", round_sig(c.configured_share)},
            {"chosen_slow_share", round_sig(c.chosen_share)},
            {"changed", c.changed},
            {"logs", c.logs},
            {"rest_capacity_ah", rest},
            {"logs_without_rest", c.logs_without_rest},
            {"candidates", cands},
            {"notes", c.notes}};
}

}  // namespace host
}  // namespace battsim
