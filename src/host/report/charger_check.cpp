#include "host/report/charger_check.h"

#include <cstdio>
#include <cmath>
#include <stdexcept>
#include <string>

#include "host/report/summary.h"

namespace battsim {
namespace host {

using nlohmann::json;

json charger_check(const json& summary, const ChargerCheckOptions& o) {
    if (!(o.charged_ah > 0.0) || !std::isfinite(o.charged_ah))
        throw std::invalid_argument("the charged charge must be a positive number of mAh");
    if (!(o.tolerance > 0.0) || !std::isfinite(o.tolerance))
        throw std::invalid_argument("the charger tolerance must be a positive fraction");
    // consumed.ah starts from the charge the monitor read as missing at start (from the
    // resting voltage); the charger's count covers the log alone when the pack began full.
    // A log without a valid sample has neither (null in the summary).
    const json consumed = summary.value("consumed", json());
    if (!consumed.is_object() || !consumed.value("ah", json()).is_number())
        throw std::invalid_argument("the log counts no charge drawn (no valid sample): nothing to compare");
    const double consumed_ah = consumed["ah"].get<double>();
    const json init = summary.value("initial_state", json());
    const json init_mah = init.is_object() ? init.value("consumed_mah", json()) : json();
    const double initial_ah = init_mah.is_number() ? init_mah.get<double>() * 1e-3 : 0.0;
    const double counted_ah = consumed_ah - initial_ah;
    if (!(counted_ah > 0.0)) throw std::invalid_argument("the log counts no charge drawn: nothing to compare");
    const double ratio = counted_ah / o.charged_ah;
    json notes = json::array();
    // Reading a full pack's resting voltage leaves about 1 % of its charge; more means the
    // pack was not full, the charger's count holds that deficit too, and the monitor's
    // estimate of it is too rough to take off (a partly charged pack's deficit read from the
    // model's curve was 198 mAh against a true 468 on the simulated suite): no verdict.
    // A current sensor off by a factor of two is broken, not miscalibrated; a count that far
    // off is a typo (Ah given as mAh) or another flight's charge, and a gain fitted to it
    // had written a config battsim then refused to load. Judged first: against a typo, the
    // other notes (the start's deficit is measured against the count) only mislead.
    const bool plausible = ratio >= 0.5 && ratio <= 2.0;
    if (!plausible) {
        // Rounded to a whole percent while that fits a long (--charged-mah 1e-300 had printed LONG_MIN).
        char pct[32];
        if (ratio * 100.0 < 1e9)
            std::snprintf(pct, sizeof pct, "%ld", static_cast<long>(std::lround(ratio * 100.0)));
        else
            std::snprintf(pct, sizeof pct, "%.3g", ratio * 100.0);
        notes.push_back("the monitor counted " + std::string(pct) +
                        " % of the charger's count: check that count (--charged-mah, or a manifest's charged_mah: in mAh) and that the log is of this charge; "
                        "no gain suggested");
    }
    const bool started_full = initial_ah <= 0.05 * o.charged_ah;
    if (!started_full && plausible) {
        notes.push_back("the monitor read " + std::to_string(static_cast<long>(std::lround(initial_ah * 1e3))) +
                        " mAh missing at the start, over 5 % of the charger's " +
                        std::to_string(static_cast<long>(std::lround(o.charged_ah * 1e3))) +
                        " mAh: the pack was not charged full before the log, and the charger's count includes that "
                        "charge; no verdict");
    }
    // An offset's charge grows with the time flown, a gain's with the charge: one count
    // cannot tell them apart, and a gain fitted to an offset is wrong on the next flight.
    // Gaps between samples before the take-off cost the count next to nothing (the ground's
    // current over them): only gaps in flight, and every other cause, hold the gain back.
    // (log171.bin's one 2.1 s gap on the ground had been reported as "raised in flight".)
    bool sensor_fault = false;
    std::string causes;
    for (const json& w : summary.value("warnings", json::array())) {
        if (!w.is_object() || w.value("name", std::string()) != "sensor_fault") continue;
        const bool in_flight = w.value("flight_time_s", json()).is_number();
        for (const json& c : w.value("cause", json::array())) {
            const std::string cause = c.is_string() ? c.get<std::string>() : std::string("unknown");
            if (cause == "sample_gap" && !in_flight) continue;
            sensor_fault = true;
            if (causes.find(cause) == std::string::npos) causes += (causes.empty() ? "" : ", ") + cause;
        }
        if (w.value("cause", json::array()).empty()) {
            sensor_fault = true;
            if (causes.find("unknown") == std::string::npos) causes += (causes.empty() ? "" : ", ") + std::string("unknown");
        }
    }
    if (sensor_fault) {
        notes.push_back("a sensor fault was raised (" + causes +
                        "; a current offset's charge, or a gap's guessed one in flight, reads as gain here): correct "
                        "it first, no gain suggested");
    }
    json j;
    j["charged_ah"] = round_sig(o.charged_ah);
    j["counted_ah"] = round_sig(counted_ah);
    j["ratio"] = round_sig(ratio);
    j["tolerance"] = o.tolerance;
    j["current_gain"] = round_sig(o.current_gain);
    j["suggested_current_gain"] = started_full && !sensor_fault && plausible ? json(round_sig(o.current_gain / ratio)) : json(nullptr);
    j["fault"] = started_full && plausible ? json(std::fabs(ratio - 1.0) > o.tolerance) : json(nullptr);
    j["notes"] = notes;
    return j;
}

void add_charger_check(json& summary, double charged_mah, double tolerance, const core::MonitorConfig& config) {
    ChargerCheckOptions o;
    o.charged_ah = charged_mah * 1e-3;
    o.tolerance = tolerance;
    o.current_gain = config.extensions.current_sensor.gain;
    summary["charger_check"] = charger_check(summary, o);
}

}  // namespace host
}  // namespace battsim
