#include "host/report/brief.h"

#include <cstdint>
#include <string>

#include "host/replay.h"
#include "host/report/summary.h"

namespace battsim {
namespace host {

namespace {
std::string fixed(const nlohmann::json& v, int decimals, double scale = 1.0) {
    return fixed_text(v, decimals, "n/a", scale);
}

// When in the flight a time since the take-off falls: in it, or after its landing (a text or
// a warning can come once the drone is down, and "157.7 s into" a 150.2 s flight misleads).
std::string when_in_flight(const nlohmann::json& flight_time_s, const nlohmann::json& duration_s) {
    const double t = flight_time_s.get<double>();
    if (duration_s.is_number() && t > duration_s.get<double>())
        return fixed(t - duration_s.get<double>(), 1) + " s after the landing";
    return fixed(flight_time_s, 1) + " s into the flight";
}

// What a warning's summary entry says beyond its name and time: when in the flight, the
// cause, the cell, what was measured, and whether it still held at the end of the log.
std::string warning_detail(const nlohmann::json& w, const nlohmann::json& duration_s) {
    std::string d;
    const auto add = [&d](const std::string& part) { d += (d.empty() ? "" : "; ") + part; };
    if (w.contains("flight_time_s"))
        add(w["flight_time_s"].is_number() ? when_in_flight(w["flight_time_s"], duration_s) : "before the take-off");
    if (w.contains("cell")) add("cell " + std::to_string(w["cell"].get<int>()));
    if (w.contains("finding")) add(w["finding"].get<std::string>());
    for (const auto& c : w.value("cause", nlohmann::json::array())) {
        const std::string cause = c.get<std::string>();
        if (cause == "sample_gap" && w.contains("sample_gaps")) {
            const auto& g = w["sample_gaps"];
            add(std::to_string(g["count"].get<uint64_t>()) + (g["count"] == 1 ? " gap" : " gaps") +
                " between samples, longest " + fixed(g["longest_s"], 2) + " s");
        } else if (cause == "current_offset" && w.contains("current_offset_a")) {
            add("current sensor offset " + fixed(w["current_offset_a"], 2) + " A");
        } else if (cause == "reading") {
            add("readings outside the sensor limits");
        } else if (cause == "cells") {
            add("cell readings outside the limits");
        } else {
            add(cause);
        }
    }
    if (!w.value("active_at_end", false)) add("cleared before the end");
    return d.empty() ? d : " (" + d + ")";
}
// A warning that went off and on again: each time it was on (a few; the count says the rest).
std::string warning_spells(const nlohmann::json& w) {
    const uint64_t count = w.value("spell_count", uint64_t{0});
    if (count < 2 || !w.contains("spells")) return "";
    constexpr size_t kShown = 4;
    std::string d = "\n      on ";
    size_t shown = 0;
    for (const auto& sp : w["spells"]) {
        if (shown == kShown) break;
        d += (shown++ ? ", " : "") + fixed(sp["from_s"], 1) + "–" +
             (sp["to_s"].is_number() ? fixed(sp["to_s"], 1) + " s" : "the end");
        std::string causes;
        for (const auto& c : sp.value("cause", nlohmann::json::array())) causes += (causes.empty() ? "" : ", ") + c.get<std::string>();
        if (!causes.empty()) d += " (" + causes + ")";
    }
    if (count > shown) d += ", and " + std::to_string(count - shown) + " more";
    return d;
}

// The flight's lines of the brief: its length, capacity, resistance, model error, and the
// remaining time at 20 %.
void print_flight_brief(const nlohmann::json& s, std::ostream& out) {
    const auto& f = s["flight"];
    const auto& cap = f["capacity_ah"];
    out << "  flight " << fixed(f["duration_s"], 1) << " s";
    // Two hops are one window, the ground between them in it; say so rather than read as one flight.
    if (f.value("take_offs", 1) > 1) out << " (" << f["take_offs"] << " take-offs: from the first to the last landing)";
    out << "; capacity ";
    const char* end = f.value("landed", true) ? "at the landing" : "at the end of the log (still flying)";
    // The joint estimator's standard error: a flight that draws little of the pack says little.
    if (cap.contains("final_sigma") && !cap["final_sigma"].is_null()) {
        out << fixed(cap["final"], 3) << " +/- " << fixed(cap["final_sigma"], 3) << " Ah " << end << " (mean "
            << fixed(cap["mean"], 3) << ", first 20 %: " << fixed(cap["first20_mean"], 3) << ")";
    } else {
        out << "mean " << fixed(cap["mean"], 3) << " Ah (first 20 %: " << fixed(cap["first20_mean"], 3) << ", " << end << " "
            << fixed(cap["final"], 3) << ")";
    }
    if (f["resistance_ohm"]["mean"].is_null())
        out << "; resistance not measured";  // the joint estimator kept its configured prior
    else
        out << "; resistance mean " << fixed(f["resistance_ohm"]["mean"], 2, 1000.0) << " mOhm";
    out << "; model MAE " << fixed(f["voltage_error_v"]["model"]["mean_abs"], 3) << " V";
    // The joint estimator's own model (its tracking filter, one step ahead) is what it
    // compares with the measurement; the configured curve's error says how far the config is.
    if (s["estimator"] == "joint") out << " (the estimator's own: " << fixed(f["voltage_error_v"]["adapted"]["mean_abs"], 3) << " V)";
    out << "\n";
    const auto& at20 = f["remaining_time_s"]["at20"];
    out << "  remaining time 20 % into the flight: " << (at20.is_number() ? fixed(at20, 1) + " s" : "not known yet") << "\n";
    // The battery states a ground station shows (not warnings): a remaining time of 0 s beside
    // "warnings: none" had read as a contradiction.
    const auto began = [&](const char* key) -> std::string {
        const auto& t = f["remaining_time_s"].value(key, nlohmann::json());
        if (!t.is_number()) return std::string();
        // On the landing sample itself (flight 29's last solve: 64 s to 57.6 s as it landed),
        // "145.1 s into the flight" of a 145.1 s flight had read as a state flown in.
        if (f["end_s"].is_number() && t.get<double>() >= f["end_s"].get<double>())
            return fixed(t, 1) + " s (at the landing)";
        return fixed(t, 1) + " s (" + fixed(t.get<double>() - f["start_s"].get<double>(), 1) + " s into the flight)";
    };
    const std::string low = began("low_from_s"), critical = began("critical_from_s");
    // A state that went off and came back: how often, and when it last began.
    const auto again = [&](const char* spells, const char* last) -> std::string {
        const auto& n = f["remaining_time_s"].value(spells, nlohmann::json());
        if (!n.is_number_integer() || n.get<long>() < 2) return std::string();
        const auto& t = f["remaining_time_s"].value(last, nlohmann::json());
        return ", " + std::to_string(n.get<long>()) + " spells, the last from " + fixed(t, 1) + " s";
    };
    if (!low.empty()) {
        out << "  battery state (telemetry.low_time_s, critical_time_s): LOW from " << low << again("low_spells", "low_last_from_s");
        if (!critical.empty()) out << "; CRITICAL from " << critical << again("critical_spells", "critical_last_from_s");
        out << "\n";
    }
}
}  // namespace

void print_brief(const nlohmann::json& s, std::ostream& out) {
    out << s["input"]["path"].get<std::string>() << ": " << s["samples"]["total"] << " samples, "
        << fixed(s["duration_s"], 1) << " s\n";
    // Samples the config's sensor limits kept out: a config for another pack (a 3S config on
    // a 4S log) rejects much of a flight, and the figures below would not say so.
    const std::string kept_out = kept_out_text(s);
    if (!kept_out.empty()) out << "  kept out by the config's sensor limits: " << kept_out << "\n";
    const auto& f = s["flight"];
    if (f.is_null() && s["samples"]["valid"] == 0) {
        out << "  no valid sample (every one kept out, above): no flight, no estimate\n";
    } else if (f.is_null()) {
        out << "  no flight (the current never stayed above the flying threshold long enough for a take-off)\n";
    } else {
        print_flight_brief(s, out);
    }
    // Warnings on the ground count too (a sample gap or a current offset on a bench log).
    out << "  warnings:";
    if (s["warnings"].empty()) out << " none";
    const nlohmann::json duration_s = f.is_object() ? f["duration_s"] : nlohmann::json();
    for (const auto& w : s["warnings"]) {
        out << "\n    " << w["name"].get<std::string>() << " at " << fixed(w["first_time_s"], 1) << " s"
            << warning_detail(w, duration_s);
        out << warning_spells(w);
    }
    out << "\n";
}

void print_said(const nlohmann::json& said, const nlohmann::json& flight, std::ostream& out) {
    out << "  said (ground station):" << (said.empty() ? " nothing" : "") << "\n";
    const nlohmann::json duration_s = flight.is_object() ? flight["duration_s"] : nlohmann::json();
    for (const auto& t : said) {
        const std::string when = t["flight_time_s"].is_number() ? when_in_flight(t["flight_time_s"], duration_s)
                                                               : fixed(t["time_s"], 1) + " s, on the ground";
        out << "    " << when << "  " << (t["severity"] == "notice" ? "notice " : "warning") << "  "
            << t["text"].get<std::string>() << "\n";
    }
}

void print_charger_check(const nlohmann::json& c, std::ostream& out) {
    const nlohmann::json& fault = c["fault"];
    out << "  charger check: counted " << fixed(c["counted_ah"], 3) << " Ah against " << fixed(c["charged_ah"], 3)
        << " Ah charged (x" << fixed(c["ratio"], 4) << "): "
        << (fault.is_null() ? "no verdict" : fault.get<bool>() ? "current sensor fault" : "within tolerance");
    if (c["suggested_current_gain"].is_number())
        out << (fault.is_boolean() && !fault.get<bool>() ? "; no change needed (the gain it implies: "
                                                           : "; suggested extensions.current_sensor.gain ")
            << fixed(c["suggested_current_gain"], 4) << (fault.is_boolean() && !fault.get<bool>() ? ")" : "");
    out << "\n";
}


}  // namespace host
}  // namespace battsim
