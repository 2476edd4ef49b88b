#include "host/batch/table.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "host/config_json.h"
#include "host/io/json_text.h"
#include "host/io/sample_reader.h"
#include "host/report/charger_check.h"
#include "host/report/summary.h"
#include "host/stats.h"

namespace battsim {
namespace host {

using nlohmann::json;

namespace {

// Every row carries these keys, in this order in the CSV.
const std::vector<std::string> kRowKeys = {
    "index", "test", "log", "pack", "monitor", "config", "estimator", "status", "error", "flight", "flight_duration_s",
    "capacity_mean_ah", "capacity_first20_ah", "capacity_final_ah", "capacity_final_sigma_ah", "capacity_after_rest_ah", "charger_ratio",
    "charger_fault", "charger_current_gain", "charger_suggested_gain", "error_mean_v", "abs_error_mean_v", "resistance_mean_ohm",
    "resistance_first20_ohm", "resistance_final_ohm", "cell_scores", "remaining_at20_s", "warnings", "samples", "sensor_fault_samples",
    "sensor_fault_cause", "notes", "outlier_cell"};

// The first key of a batch row whose value is not of the type batch writes ("key: expected
// ..."), or an unknown key; empty when the row is well formed.
std::string row_type_problem(const json& r) {
    static const std::vector<std::string> texts = {"test", "log", "config", "estimator", "status"};
    static const std::vector<std::string> texts_or_null = {"pack", "monitor", "error"};
    static const std::vector<std::string> text_lists = {"warnings", "sensor_fault_cause", "notes"};
    const auto in = [](const std::vector<std::string>& keys, const std::string& k) {
        return std::find(keys.begin(), keys.end(), k) != keys.end();
    };
    for (auto it = r.begin(); it != r.end(); ++it) {
        const std::string& k = it.key();
        const json& v = it.value();
        if (!in(kRowKeys, k)) return k + ": not a key batch writes";
        if (k == "index" || k == "flight") continue;  // checked by the caller
        if (in(texts, k)) {
            if (!v.is_string()) return k + ": expected text, found " + json_brief(v);
        } else if (in(texts_or_null, k)) {
            if (!v.is_string() && !v.is_null()) return k + ": expected text or null, found " + json_brief(v);
        } else if (in(text_lists, k)) {
            for (const json& e : v)
                if (!e.is_string()) return k + ": expected a list of text, found " + json_brief(e);
        } else if (k == "cell_scores") {
            for (const json& e : v)
                if (!e.is_number() && !e.is_null()) return k + ": expected a list of numbers, found " + json_brief(e);
        } else if (k == "charger_fault") {
            if (!v.is_boolean() && !v.is_null()) return k + ": expected true, false or null, found " + json_brief(v);
        } else if (!v.is_number() && !v.is_null()) {
            return k + ": expected a number or null, found " + json_brief(v);
        }
    }
    return "";
}

const std::vector<std::string> kPackKeys = {"pack", "flights", "failed", "other_pack_config", "capacity_mean_ah",
                                            "capacity_trend_ah_per_flight", "capacity_final_median_ah",
                                            "capacity_final_trend_ah_per_flight", "capacity_final_spread_ah",
                                            "capacity_final_sigma_median_ah", "capacity_scatter_ratio",
                                            "resistance_mean_ohm", "resistance_trend_ohm_per_flight"};

// A row whose notes say its config is for another pack than the log's (cell count, voltage).
bool read_with_other_pack_config(const json& r) {
    const json notes = r.value("notes", json());
    if (!notes.is_array()) return false;
    for (const json& n : notes)
        if (n.is_string() && is_other_pack_note(n.get<std::string>())) return true;
    return false;
}

const std::vector<std::string> kMonitorKeys = {"monitor", "flights", "failed", "charger_checks", "charger_flagged",
                                               "charger_pooled", "charger_ratio_pooled", "suggested_gain_spread",
                                               "current_gain", "suggested_current_gain", "charger_tolerance",
                                               "charger_fault", "fleet_flights", "fleet_capacity_source", "fleet_capacity_effect",
                                               "fleet_capacity_effect_sigma", "fleet_resistance_effect",
                                               "fleet_resistance_effect_sigma", "fleet_gain_error",
                                               "fleet_gain_error_sigma", "fleet_gain_fault", "fault_flights_reading",
                                               "fault_flights_cells", "fault_flights_current_offset", "fault_flights_sample_gap"};

// Every sensor-fault cause's name (the summary's), which a monitor's flights are counted by.
const json kFaultCauses = sensor_fault_cause_names(0xFF);

json number_or_null(double v) { return std::isfinite(v) ? json(round_sig(v)) : json(nullptr); }

// Fixed decimals for the Markdown table; "–" for no value.
std::string fixed(const json& v, int decimals) { return fixed_text(v, decimals); }

std::string significant(const json& v, int digits) {
    if (!v.is_number()) return "–";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%+#.*g", digits, v.get<double>());  // "#": -0.000100, not -0.0001 (read as rounded to 4 places)
    std::string s = buf;
    if (v.get<double>() == 0.0) s = "0";
    return s;
}

// A Markdown cell: pipes escaped, line breaks flattened.
std::string md_cell(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '|') out += "\\|";
        else if (c == '\n' || c == '\r') out += ' ';
        else out += c;
    }
    return out;
}

std::string text(const json& v) { return v.is_string() ? v.get<std::string>() : std::string(); }

// The last component of `path`: a directory given as "DIR/" (a shell's completion) is named
// "DIR" (its error row's log cell had been empty).
std::string file_name(const std::string& path) {
    const size_t end = path.find_last_not_of('/');
    if (end == std::string::npos) return path;  // "/" or empty
    const size_t slash = path.find_last_of('/', end);
    const size_t from = slash == std::string::npos ? 0 : slash + 1;
    return path.substr(from, end + 1 - from);
}

// A CSV field: numbers in their shortest exact form, arrays joined with `separator`, quoted
// when needed (RFC 4180).
std::string csv_field(const json& v, const char* separator = ";") {
    std::string s;
    if (v.is_null()) return s;
    if (v.is_string()) {
        s = v.get<std::string>();
    } else if (v.is_array()) {
        for (size_t i = 0; i < v.size(); ++i)
            s += (i ? separator : "") + (v[i].is_string() ? v[i].get<std::string>() : json_text(v[i]));
    } else {
        s = json_text(v);
    }
    if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

std::string render_rows_md(const json& table) {
    std::ostringstream o;
    // The appendix's columns, and the capacity at the landing beside its mean: over a flight
    // the mean of a converging estimate can rank packs the wrong way round (the joint
    // estimator's sad pack had the highest mean and the lowest final capacity).
    o << "| test | log | pack | mean capacity Ah | first 20 % capacity Ah | final capacity Ah | error V | abs error V "
         "| R Ω | first 20 % R Ω | cell differences | remaining at 20 % s | warnings | status |\n";
    o << "|---|---|---|--:|--:|--:|--:|--:|--:|--:|---|--:|---|---|\n";
    for (const json& r : table["rows"]) {
        std::string cells;
        // The cells' Piao scores are the reference estimator's; the joint one does not compute them.
        if (r["estimator"] != "joint")
            for (const json& c : r["cell_scores"]) cells += (cells.empty() ? "" : " / ") + fixed(c, 2);
        std::string final_ah = fixed(r["capacity_final_ah"], 3);
        if (r["capacity_final_sigma_ah"].is_number()) final_ah += " ± " + fixed(r["capacity_final_sigma_ah"], 3);
        std::string warnings;
        for (const json& w : r["warnings"]) {
            warnings += (warnings.empty() ? "" : ", ") + text(w);
            // Which cell, and for what: the operator's next step is that cell's lead or the pack.
            if (text(w) == "cell_outlier" && r.value("outlier_cell", json()).is_number())
                warnings += " (cell " + json_text(r["outlier_cell"]) + ")";
            // A fleet's table should tell a dropped log line from a broken sensor at a glance.
            if (text(w) == "sensor_fault" && !r["sensor_fault_cause"].empty()) {
                std::string cause;
                for (const json& c : r["sensor_fault_cause"]) cause += (cause.empty() ? "" : ", ") + text(c);
                warnings += " (" + cause + ")";
            }
        }
        std::string status = text(r["status"]);
        if (status == kRowOk && !r["flight"].get<bool>()) status = "ok (no flight)";
        // A log replayed with a config for another pack reads "ok" with nonsense figures (a 3S
        // log on the built-in 4S config: 160 V of model error); its note sat in the CSV alone.
        if (status.compare(0, 2, kRowOk) == 0 && read_with_other_pack_config(r)) status += " (config for another pack: see notes)";
        if (status == kRowNoValidSamples) status = "no valid samples";
        if (status != "ok" && r["error"].is_string()) status += ": " + r["error"].get<std::string>();
        o << "| " << md_cell(text(r["test"])) << " | " << md_cell(file_name(text(r["log"]))) << " | "
          << md_cell(r["pack"].is_string() ? text(r["pack"]) : "–") << " | " << fixed(r["capacity_mean_ah"], 3) << " | "
          << fixed(r["capacity_first20_ah"], 3) << " | " << final_ah << " | " << fixed(r["error_mean_v"], 3) << " | "
          << fixed(r["abs_error_mean_v"], 3) << " | " << fixed(r["resistance_mean_ohm"], 4) << " | "
          << fixed(r["resistance_first20_ohm"], 4) << " | " << (cells.empty() ? "–" : cells) << " | "
          << fixed(r["remaining_at20_s"], 1) << " | " << (warnings.empty() ? "–" : md_cell(warnings)) << " | "
          << md_cell(status) << " |\n";
    }
    return o.str();
}

std::string render_packs_md(const json& packs) {
    std::ostringstream o;
    // The capacity at the landing, not the flight's mean: the mean of a converging estimate
    // ranked an aged pack above a new one and read a rising trend on a pack wearing out.
    o << "| pack | flights | failed | left out (another pack's config) | final capacity Ah | final capacity trend Ah/flight "
         "| final spread / σ | R Ω | R trend Ω/flight |\n";
    o << "|---|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    for (const json& p : packs) {
        o << "| " << md_cell(text(p["pack"])) << " | " << json_text(p["flights"]) << " | " << json_text(p["failed"]) << " | "
          << json_text(p.value("other_pack_config", json(0))) << " | " << fixed(p["capacity_final_median_ah"], 3) << " | "
          << significant(p.value("capacity_final_trend_ah_per_flight", json()), 3) << " | "
          << fixed(p["capacity_scatter_ratio"], 1) << " | " << fixed(p["resistance_mean_ohm"], 4) << " | "
          << significant(p["resistance_trend_ohm_per_flight"], 3) << " |\n";
    }
    return o.str();
}

std::string render_monitors_md(const json& monitors) {
    std::ostringstream o;
    o << "| monitor | flights | failed | charger checks | flagged | pooled | count / charger | spread of the gains "
         "| gain | suggested gain | fault | gain error against the fleet | fleet fault | sensor faults (flights) |\n";
    o << "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|--:|---|---|\n";
    for (const json& m : monitors) {
        const json& fault = m["charger_fault"];
        auto yes_no = [](const json& b) { return b.is_boolean() ? (b.get<bool>() ? "yes" : "no") : "–"; };
        o << "| " << md_cell(text(m["monitor"])) << " | " << json_text(m["flights"]) << " | " << json_text(m["failed"]) << " | "
          << json_text(m["charger_checks"]) << " | " << json_text(m["charger_flagged"]) << " | " << json_text(m["charger_pooled"])
          << " | " << fixed(m["charger_ratio_pooled"], 4) << " | " << fixed(m["suggested_gain_spread"], 4) << " | "
          << fixed(m["current_gain"], 4) << " | " << fixed(m["suggested_current_gain"], 4) << " | "
          << yes_no(fault) << " | ";
        const json& g = m["fleet_gain_error"];
        const json& gs = m["fleet_gain_error_sigma"];
        if (g.is_number() && gs.is_number()) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%+.1f ± %.1f %%", 100.0 * g.get<double>(), 100.0 * gs.get<double>());
            o << buf;
        } else {
            o << "–";
        }
        // A monitor whose flights keep raising one cause: its balance lead, its current
        // sensor's zero, its bus.
        std::string faults;
        for (const json& c : kFaultCauses) {
            const json n = m.value("fault_flights_" + text(c), json(0));
            if (n.is_number() && n.get<long>() > 0) faults += (faults.empty() ? "" : ", ") + text(c) + " " + json_text(n);
        }
        o << " | " << yes_no(m["fleet_gain_fault"]) << " | " << (faults.empty() ? "–" : faults) << " |\n";
    }
    return o.str();
}

std::string render_csv(const json& rows, const std::vector<std::string>& keys) {
    std::string out;
    for (size_t i = 0; i < keys.size(); ++i) out += (i ? "," : "") + keys[i];
    out += "\n";
    for (const json& r : rows) {
        // Notes are sentences, some with commas and semicolons of their own: "; " reads apart.
        for (size_t i = 0; i < keys.size(); ++i) out += (i ? "," : "") + csv_field(r[keys[i]], keys[i] == "notes" ? "; " : ";");
        out += "\n";
    }
    return out;
}

}  // namespace

TableFormat parse_table_format(const std::string& name) {
    if (name == "md") return TableFormat::Markdown;
    if (name == "csv") return TableFormat::Csv;
    if (name == "json") return TableFormat::Json;
    throw std::invalid_argument("unknown table format \"" + name + "\"; expected md, csv or json");
}

double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y) {
    const size_t n = std::min(x.size(), y.size());
    if (n < 2) return NAN;
    double mx = 0, my = 0;
    for (size_t i = 0; i < n; ++i) {
        mx += x[i];
        my += y[i];
    }
    mx /= n;
    my /= n;
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < n; ++i) {
        sxy += (x[i] - mx) * (y[i] - my);
        sxx += (x[i] - mx) * (x[i] - mx);
    }
    return sxx > 0 ? sxy / sxx : NAN;
}

namespace {

// Rows grouped by the text under `key` (rows without one left out), each group's rows in input
// order and the groups in order of their first row.
std::vector<std::pair<std::string, std::vector<const json*>>> group_rows(const std::vector<json>& rows, const char* key) {
    std::vector<std::pair<std::string, std::vector<const json*>>> groups;
    std::map<std::string, size_t> index;
    for (const json& r : rows) {
        const json id = r.value(key, json());
        if (!id.is_string()) continue;
        auto it = index.emplace(id.get<std::string>(), groups.size()).first;
        if (it->second == groups.size()) groups.emplace_back(it->first, std::vector<const json*>());
        groups[it->second].second.push_back(&r);
    }
    return groups;
}

double mean_of(const std::vector<double>& v) {
    if (v.empty()) return NAN;
    double s = 0;
    for (double d : v) s += d;
    return s / v.size();
}

// How each monitor reads the packs it shares with other monitors: ln(value) = pack + monitor
// + noise, fitted by least squares (alternating means until they settle), the monitors'
// terms centred on their median within each group of monitors linked by shared packs (most
// monitors of a fleet are taken to be right). A pack's own capacity and resistance go into
// its term, so what a monitor's term holds is its current sensor, or the conditions its drone
// flies in. Its standard error: the fit's residual σ × √(1/n + 1/m), n its rows and m the
// other monitors' rows on the same packs. None in a group of fewer than three monitors: with
// two, which one is off cannot be told.
struct FleetEffect {
    size_t n = 0;
    double effect = NAN, sigma = NAN;
};
std::map<std::string, FleetEffect> fleet_effects(const std::vector<json>& rows, const char* key) {
    std::map<std::string, size_t> pack_ix, monitor_ix;
    std::vector<std::string> monitor_names;
    struct Obs {
        size_t pack, monitor;
        double y;
    };
    std::vector<Obs> obs;
    for (const json& r : rows) {
        const json pack = r.value("pack", json()), monitor = r.value("monitor", json()), v = r.value(key, json());
        if (!pack.is_string() || !monitor.is_string() || !v.is_number() || !(v.get<double>() > 0.0) || r.value("status", json()) != "ok") continue;
        const size_t p = pack_ix.emplace(pack.get<std::string>(), pack_ix.size()).first->second;
        auto mi = monitor_ix.emplace(monitor.get<std::string>(), monitor_ix.size());
        if (mi.second) monitor_names.push_back(monitor.get<std::string>());
        obs.push_back({p, mi.first->second, std::log(v.get<double>())});
    }
    const size_t np = pack_ix.size(), nm = monitor_ix.size();
    // Groups linked by shared packs (union-find over packs 0..np−1 and monitors np..).
    std::vector<size_t> parent(np + nm);
    for (size_t k = 0; k < parent.size(); ++k) parent[k] = k;
    auto root = [&parent](size_t k) {
        while (parent[k] != k) k = parent[k] = parent[parent[k]];
        return k;
    };
    for (const Obs& o : obs) parent[root(o.pack)] = root(np + o.monitor);
    // The least-squares fit, solved exactly: the packs' terms eliminated, the monitors' satisfy
    // A·mon = b (one free shift per group, fixed at its first monitor; the centring below
    // sets it). Alternating between packs and monitors had stopped after 1000 rounds far from
    // the fit on a long chain of monitors (80: off by 6 points at its end).
    std::vector<std::vector<size_t>> in_pack(np);
    for (size_t i = 0; i < obs.size(); ++i) in_pack[obs[i].pack].push_back(i);
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nm), static_cast<Eigen::Index>(nm));
    Eigen::VectorXd b = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nm));
    for (size_t p = 0; p < np; ++p) {
        const double n = static_cast<double>(in_pack[p].size());
        double sum = 0.0;
        for (size_t i : in_pack[p]) sum += obs[i].y;
        for (size_t i : in_pack[p]) {
            const auto mi = static_cast<Eigen::Index>(obs[i].monitor);
            a(mi, mi) += 1.0;
            b(mi) += obs[i].y - sum / n;
            for (size_t j : in_pack[p]) a(mi, static_cast<Eigen::Index>(obs[j].monitor)) -= 1.0 / n;
        }
    }
    std::vector<bool> anchored(np + nm, false);
    for (size_t m = 0; m < nm; ++m) {
        if (anchored[root(np + m)]) continue;
        anchored[root(np + m)] = true;
        const auto mi = static_cast<Eigen::Index>(m);
        a.row(mi).setZero();
        a(mi, mi) = 1.0;
        b(mi) = 0.0;
    }
    const Eigen::VectorXd solved = nm > 0 ? Eigen::VectorXd(a.colPivHouseholderQr().solve(b)) : Eigen::VectorXd();
    std::vector<double> pack(np, 0.0), mon(nm, 0.0);
    for (size_t m = 0; m < nm; ++m) mon[m] = solved(static_cast<Eigen::Index>(m));
    for (size_t p = 0; p < np; ++p) {
        double sum = 0.0;
        for (size_t i : in_pack[p]) sum += obs[i].y - mon[obs[i].monitor];
        pack[p] = sum / static_cast<double>(in_pack[p].size());
    }
    // Centre each group's monitors on their median (its packs take the shift: the fit stays).
    std::map<size_t, std::vector<size_t>> groups;
    for (size_t m = 0; m < nm; ++m) groups[root(np + m)].push_back(m);
    std::map<size_t, double> centres;
    std::vector<bool> judged(nm, false);
    for (const auto& g : groups) {
        std::vector<double> terms;
        for (size_t m : g.second) terms.push_back(mon[m]);
        const double centre = centres[g.first] = median(terms);
        for (size_t m : g.second) {
            mon[m] -= centre;
            judged[m] = g.second.size() >= 3;
        }
    }
    for (size_t p = 0; p < np; ++p) pack[p] += centres[root(p)];
    double rss = 0.0;
    for (const Obs& o : obs) rss += (o.y - pack[o.pack] - mon[o.monitor]) * (o.y - pack[o.pack] - mon[o.monitor]);
    const double dof = static_cast<double>(obs.size()) - static_cast<double>(np + nm) + static_cast<double>(groups.size());
    const double s = dof >= 1.0 ? std::sqrt(rss / dof) : NAN;
    std::vector<double> own(nm, 0.0), others(nm, 0.0);
    std::vector<std::vector<double>> per_pack(np, std::vector<double>(nm, 0.0));
    for (const Obs& o : obs) per_pack[o.pack][o.monitor] += 1.0;
    for (size_t p = 0; p < np; ++p) {
        double total = 0.0;
        for (size_t m = 0; m < nm; ++m) total += per_pack[p][m];
        for (size_t m = 0; m < nm; ++m) {
            if (per_pack[p][m] == 0.0) continue;
            own[m] += per_pack[p][m];
            others[m] += total - per_pack[p][m];
        }
    }
    std::map<std::string, FleetEffect> out;
    for (size_t m = 0; m < nm; ++m) {
        FleetEffect& e = out[monitor_names[m]];
        e.n = static_cast<size_t>(others[m] > 0.0 ? own[m] : 0.0);
        if (!judged[m] || !(others[m] > 0.0)) continue;
        e.effect = mon[m];
        e.sigma = s * std::sqrt(1.0 / own[m] + 1.0 / others[m]);
    }
    return out;
}

}  // namespace

// Rows made by hand (or by an older battsim) may lack keys: the tables read them with
// value(), never by indexing (const operator[] on a missing key is undefined).
std::vector<json> pack_rows(const std::vector<json>& rows) {
    std::vector<json> out;
    for (const auto& group : group_rows(rows, "pack")) {
        size_t failed = 0, other_pack = 0;
        std::vector<double> cap_x, cap_y, res_x, res_y, final_x, final_ah, final_sigma_ah;
        for (size_t k = 0; k < group.second.size(); ++k) {
            const json& r = *group.second[k];
            const double x = static_cast<double>(k + 1);  // flight number within the pack
            if (r.value("status", json()) != "ok") ++failed;
            // Another pack's figures would enter this pack's: a 3S config on a 4S flight read
            // 3.9 Ah for a 1.6 Ah pack. Counted, kept out, the flight keeping its number.
            if (read_with_other_pack_config(r)) {
                ++other_pack;
                continue;
            }
            const json cap = r.value("capacity_mean_ah", json()), res = r.value("resistance_mean_ohm", json());
            if (cap.is_number()) {
                cap_x.push_back(x);
                cap_y.push_back(cap.get<double>());
            }
            const json f_ah = r.value("capacity_final_ah", json());
            const json f_sigma_ah = r.value("capacity_final_sigma_ah", json());
            if (f_ah.is_number()) {
                final_x.push_back(x);
                final_ah.push_back(f_ah.get<double>());
            }
            if (f_sigma_ah.is_number()) final_sigma_ah.push_back(f_sigma_ah.get<double>());
            if (res.is_number()) {
                res_x.push_back(x);
                res_y.push_back(res.get<double>());
            }
        }
        json p;
        p["pack"] = group.first;
        p["flights"] = group.second.size();
        p["failed"] = failed;
        p["other_pack_config"] = other_pack;
        p["capacity_mean_ah"] = number_or_null(mean_of(cap_y));
        p["capacity_trend_ah_per_flight"] = number_or_null(least_squares_slope(cap_x, cap_y));
        p["capacity_final_trend_ah_per_flight"] = number_or_null(least_squares_slope(final_x, final_ah));
        // Do the flights agree within their own standard errors? The spread of the final
        // capacities against the median σ a flight reports: about 1 when they do; far above,
        // and the config's curve does not fit the pack (or the flights draw too little of it).
        const double spread = robust_spread(final_ah);
        const double sigma = median(final_sigma_ah);
        p["capacity_final_median_ah"] = number_or_null(median(final_ah));
        p["capacity_final_spread_ah"] = number_or_null(spread);
        p["capacity_final_sigma_median_ah"] = number_or_null(sigma);
        p["capacity_scatter_ratio"] = number_or_null(sigma > 0.0 ? spread / sigma : NAN);
        p["resistance_mean_ohm"] = number_or_null(mean_of(res_y));
        p["resistance_trend_ohm_per_flight"] = number_or_null(least_squares_slope(res_x, res_y));
        out.push_back(p);
    }
    return out;
}

std::vector<json> monitor_rows(const std::vector<json>& rows, double tolerance) {
    // The capacity read off the rests before and after a flight scales with the sensor's gain
    // exactly (the charge it counts over the fall in state of charge the OCV curve reads, no
    // prior pulling it back); the in-flight estimate stands in for monitors whose flights
    // have no rest after landing.
    const std::map<std::string, FleetEffect> rest_capacity = fleet_effects(rows, "capacity_after_rest_ah");
    const std::map<std::string, FleetEffect> final_capacity = fleet_effects(rows, "capacity_final_ah");
    // The resistance at the end of the flight: measured throughout, where the flight's mean
    // still holds the configured value of its first seconds.
    const std::map<std::string, FleetEffect> resistance = fleet_effects(rows, "resistance_final_ohm");
    std::vector<json> out;
    for (const auto& group : group_rows(rows, "monitor")) {
        size_t failed = 0, checks = 0, flagged = 0;
        std::map<std::string, size_t> fault_flights;
        std::vector<double> suggestions;
        double current_gain = NAN;  // of the latest flight that suggests one
        for (const json* row : group.second) {
            const json& r = *row;
            if (r.value("status", json()) != "ok") ++failed;
            if (r.value("charger_ratio", json()).is_number()) ++checks;
            if (r.value("charger_fault", json()) == true) ++flagged;
            for (const json& c : r.value("sensor_fault_cause", json::array()))
                if (c.is_string()) ++fault_flights[c.get<std::string>()];
            // Only flights that suggest a gain are pooled: a pack full at the start and no
            // in-flight sensor fault (an offset's charge is not a gain).
            const json suggested = r.value("charger_suggested_gain", json());
            const json gain = r.value("charger_current_gain", json());
            if (suggested.is_number() && gain.is_number()) {
                suggestions.push_back(suggested.get<double>());
                current_gain = gain.get<double>();
            }
        }
        json m;
        m["monitor"] = group.first;
        m["flights"] = group.second.size();
        m["failed"] = failed;
        m["charger_checks"] = checks;
        m["charger_flagged"] = flagged;
        m["charger_pooled"] = suggestions.size();
        for (const json& c : kFaultCauses) m["fault_flights_" + text(c)] = fault_flights[text(c)];
        // The gain every pooled flight asks for, as one median: a charger's own count is good
        // to a percent or two per charge, and one bad entry (a pack not quite full) is outvoted.
        // The ratio is what the sensor counts with the gain in use against the charger.
        const double suggested = median(suggestions);
        const double ratio = suggested > 0.0 ? current_gain / suggested : NAN;
        m["charger_ratio_pooled"] = number_or_null(ratio);
        m["suggested_gain_spread"] = number_or_null(robust_spread(suggestions));
        m["current_gain"] = number_or_null(current_gain);
        m["suggested_current_gain"] = number_or_null(suggested);
        m["charger_tolerance"] = number_or_null(tolerance);
        m["charger_fault"] = std::isfinite(ratio) ? json(std::fabs(ratio - 1.0) > tolerance) : json(nullptr);
        // Without a charger: the same packs flown on other monitors. A current-sensor gain g
        // reads every capacity (1 + g) times and every resistance (ΔV/ΔI) 1 / (1 + g) times,
        // so the capacity's term and minus the resistance's each read ln(1 + g): weighted by
        // their inverse variances (the resistance scatters with each flight's temperature), and
        // they must agree within 3 σ of their difference (a drone flown in the cold reads more
        // resistance too, but barely less capacity). A fault is beyond the tolerance and 3 σ.
        auto effect_of = [&group](const std::map<std::string, FleetEffect>& effects) {
            const auto it = effects.find(group.first);
            return it != effects.end() ? it->second : FleetEffect();
        };
        const FleetEffect rest = effect_of(rest_capacity);
        const FleetEffect ce = std::isfinite(rest.sigma) ? rest : effect_of(final_capacity), re = effect_of(resistance);
        m["fleet_flights"] = std::min(ce.n, re.n);
        m["fleet_capacity_source"] = std::isfinite(rest.sigma) ? json("after_rest") : std::isfinite(ce.sigma) ? json("final") : json(nullptr);
        m["fleet_capacity_effect"] = number_or_null(std::expm1(ce.effect));
        m["fleet_capacity_effect_sigma"] = number_or_null(ce.sigma);
        m["fleet_resistance_effect"] = number_or_null(std::expm1(re.effect));
        m["fleet_resistance_effect_sigma"] = number_or_null(re.sigma);
        double ln_gain = 0.5 * (ce.effect - re.effect), ln_sigma = 0.5 * std::hypot(ce.sigma, re.sigma);
        if (ce.sigma > 0.0 && re.sigma > 0.0) {  // else a fit without scatter: the plain mean
            const double wc = 1.0 / (ce.sigma * ce.sigma), wr = 1.0 / (re.sigma * re.sigma);
            ln_gain = (wc * ce.effect - wr * re.effect) / (wc + wr);
            ln_sigma = 1.0 / std::sqrt(wc + wr);
        }
        m["fleet_gain_error"] = number_or_null(std::expm1(ln_gain));
        m["fleet_gain_error_sigma"] = number_or_null(ln_sigma);
        const bool agree = std::fabs(ce.effect + re.effect) <= 3.0 * std::hypot(ce.sigma, re.sigma);
        m["fleet_gain_fault"] = std::isfinite(ln_gain) && std::isfinite(ln_sigma)
                                    ? json(std::fabs(std::expm1(ln_gain)) > tolerance && std::fabs(ln_gain) > 3.0 * ln_sigma && agree)
                                    : json(nullptr);
        out.push_back(m);
    }
    return out;
}

json make_table(std::vector<json> rows, size_t inputs, const std::string& digest, const ShardSpec& shard) {
    json t;
    t["schema"] = kBatchSchema;
    // "schema_version" as in every other report; "version" kept for the readers of version 2.
    t["schema_version"] = kBatchVersion;
    t["version"] = kBatchVersion;
    t["battsim_version"] = BATTSIM_VERSION;
    t["inputs"] = {{"count", inputs}, {"digest", digest}};
    t["shard"] = shard.active() ? json{{"index", shard.index}, {"count", shard.count}} : json(nullptr);
    // A shard's pack table would cover part of each pack's flights: left to merge.
    t["packs"] = shard.active() ? json(nullptr) : json(pack_rows(rows));
    t["monitors"] = shard.active() ? json(nullptr) : json(monitor_rows(rows, ChargerCheckOptions().tolerance));
    t["rows"] = std::move(rows);
    return t;
}

std::string failed_row_text(const json& row) {
    const std::string log = row.value("log", std::string());
    std::string error = row.value("error", std::string());
    // An error says itself what went wrong; a log replayed without a valid sample is said as such.
    if (row.value("status", std::string()) == kRowNoValidSamples) error = "no valid samples: " + error;
    return error.rfind(log, 0) == 0 ? error : log + ": " + error;
}

size_t failed_rows(const json& table) {
    size_t n = 0;
    for (const json& r : table["rows"]) n += r["status"] != "ok";
    return n;
}

std::string render_table(const json& table, TableFormat format) {
    switch (format) {
        case TableFormat::Json: return json_text(table, 2) + "\n";
        case TableFormat::Csv: return render_csv(table["rows"], kRowKeys);
        case TableFormat::Markdown: break;
    }
    std::string out = render_rows_md(table);
    if (table["shard"].is_object()) {
        out += "\nShard " + json_text(table["shard"]["index"]) + "/" + json_text(table["shard"]["count"]) +
               " of the inputs; `battsim merge` the shards' JSON tables for the whole table and the per-pack table.\n";
    } else if (table["packs"].is_array() && !table["packs"].empty()) {
        out += "\nPer pack (trend: least-squares slope over the pack's flights in input order):\n\n";
        out += render_packs_md(table["packs"]);
    }
    const json monitors = table.value("monitors", json());
    if (monitors.is_array() && !monitors.empty()) {
        out += "\nPer monitor (its current sensor against the charger: the gain its flights' checks suggest, pooled as their "
               "median):\n\n";
        out += render_monitors_md(monitors);
    }
    return out;
}

std::string render_packs(const json& table, TableFormat format) {
    const json packs = table["packs"].is_array() ? table["packs"] : json::array();
    switch (format) {
        case TableFormat::Json: return json_text(packs, 2) + "\n";
        case TableFormat::Csv: return render_csv(packs, kPackKeys);
        case TableFormat::Markdown: break;
    }
    return render_packs_md(packs);
}

std::string render_monitors(const json& table, TableFormat format) {
    const json monitors = table.value("monitors", json());
    const json list = monitors.is_array() ? monitors : json::array();
    switch (format) {
        case TableFormat::Json: return json_text(list, 2) + "\n";
        case TableFormat::Csv: return render_csv(list, kMonitorKeys);
        case TableFormat::Markdown: break;
    }
    return render_monitors_md(list);
}

json read_table_file(const std::string& path) {
    std::string text;
    const TextRead r = read_text_file(path, text);
    if (r != TextRead::Ok) throw InputError(path, 0, 0, text_read_message(r, "batch table"));
    if (text.empty()) throw InputError(path, 0, 0, "file is empty; expected a table written by `battsim batch --format json`");
    json t;
    JsonSyntaxError se;
    if (!parse_json_text(text, t, se)) {
        throw InputError(path, se.line, se.column,
                         "not valid JSON (" + se.what + "); expected a table written by `battsim batch --format json`");
    }
    auto fail = [&path](const std::string& what) { throw InputError(path, 0, 0, what); };
    try {
        if (!t.is_object() || t.value("schema", std::string()) != kBatchSchema)
            fail(std::string("expected a JSON table with \"schema\": \"") + kBatchSchema + "\" (from `battsim batch --format json`)");
        // Either key will do (a table made by hand may carry one); both must agree.
        const json version = t.contains("schema_version") ? t["schema_version"] : t.value("version", json());
        if (t.contains("schema_version") && t.contains("version") && t["version"] != version)
            fail("\"schema_version\" " + json_brief(version) + " and \"version\" " + json_brief(t["version"]) + " disagree");
        if (version != kBatchVersion)
            fail("unsupported table version " + json_brief(version) + "; expected " + std::to_string(kBatchVersion) +
                 " (rerun the shards with this battsim)");
        if (!t.contains("inputs") || !t["inputs"].is_object() || !t["inputs"].value("count", json()).is_number_unsigned() ||
            !t["inputs"].value("digest", json()).is_string())
            fail("expected \"inputs\": {\"count\": N, \"digest\": \"…\"}");
        if (!t.contains("rows") || !t["rows"].is_array()) fail("expected a \"rows\" array");
        if (!t.contains("shard") || !(t["shard"].is_null() || t["shard"].is_object())) fail("expected \"shard\": null or {\"index\", \"count\"}");
        const size_t count = t["inputs"]["count"].get<size_t>();
        // merge allocates a slot per input: a corrupt count of 2^64 − 1 had ended in an
        // allocation error naming no file.
        constexpr size_t kMaxInputs = 100000000;
        if (count > kMaxInputs)
            fail("\"inputs\".\"count\" " + std::to_string(count) + " is more logs than a batch table holds (at most " +
                 std::to_string(kMaxInputs) + ")");
        for (size_t i = 0; i < t["rows"].size(); ++i) {
            const json& r = t["rows"][i];
            const std::string where = "rows[" + std::to_string(i) + "]";
            if (!r.is_object()) fail(where + ": expected an object");
            for (const std::string& k : kRowKeys)
                if (!r.contains(k)) fail(where + ": expected the key \"" + k + "\"");
            if (!r["index"].is_number_unsigned() || r["index"].get<size_t>() >= count)
                fail(where + ".index: expected a whole number below the input count " + std::to_string(count));
            if (!r["status"].is_string() || !r["flight"].is_boolean())
                fail(where + ": expected \"status\" text and \"flight\" true/false");
            if (r["status"] != kRowOk && r["status"] != kRowError && r["status"] != kRowNoValidSamples)
                fail(where + ".status: expected \"ok\", \"error\" or \"no_valid_samples\", found " + json_brief(r["status"]));
            if (!r["cell_scores"].is_array() || !r["warnings"].is_array() || !r["sensor_fault_cause"].is_array() ||
                !r["notes"].is_array())
                fail(where + ": expected \"cell_scores\", \"warnings\", \"sensor_fault_cause\" and \"notes\" arrays");
            // Every value of the type batch writes: an edited or corrupted shard must not pass its
            // values into the merged table and the per-pack trends unseen.
            const std::string problem = row_type_problem(r);
            if (!problem.empty()) fail(where + "." + problem);
        }
    } catch (const nlohmann::json::exception& e) {
        // A value of the wrong type somewhere the checks above did not look.
        fail(std::string("not a batch table: ") + e.what());
    }
    return t;
}

json merge_tables(const std::vector<json>& tables, const std::vector<std::string>& origins) {
    if (tables.empty()) throw InputError("merge", 0, 0, "expected at least one table");
    const json& first = tables[0];
    const size_t count = first["inputs"]["count"].get<size_t>();
    const std::string digest = first["inputs"]["digest"].get<std::string>();
    std::vector<const json*> by_index(count, nullptr);
    std::vector<size_t> from(count, 0);
    for (size_t t = 0; t < tables.size(); ++t) {
        const json& tab = tables[t];
        const std::string& origin = t < origins.size() ? origins[t] : std::string("table");
        if (tab["inputs"]["count"].get<size_t>() != count || tab["inputs"]["digest"] != digest) {
            throw InputError(origin, 0, 0,
                             "comes from a different input list than " + origins[0] + " (inputs " +
                                 json_text(tab["inputs"]["count"]) + " / digest " + json_text(tab["inputs"]["digest"]) +
                                 " vs " + std::to_string(count) + " / \"" + digest +
                                 "\"); run every shard with the same paths, manifest and options");
        }
        // Shards of one run split it the same way: a 1/1 table beside a 2/2 one is two runs.
        const json& shard = tab["shard"], &first_shard = first["shard"];
        const json shard_count = shard.is_object() ? shard.value("count", json()) : json(1);
        const json first_count = first_shard.is_object() ? first_shard.value("count", json()) : json(1);
        if (shard_count != first_count)
            throw InputError(origin, 0, 0,
                             "is split into " + json_text(shard_count) + " shard(s), " + origins[0] + " into " +
                                 json_text(first_count) + "; give the shards of one run");
        if (tab.value("battsim_version", std::string()) != first.value("battsim_version", std::string()))
            throw InputError(origin, 0, 0, "was written by battsim " + tab.value("battsim_version", std::string("?")) +
                                               ", " + origins[0] + " by " + first.value("battsim_version", std::string("?")));
        for (const json& r : tab["rows"]) {
            const size_t i = r["index"].get<size_t>();
            if (by_index[i]) {
                throw InputError(origin, 0, 0,
                                 "holds input " + std::to_string(i) + " (" + text(r["log"]) + ") that " + origins[from[i]] +
                                     " holds too; give each shard once");
            }
            by_index[i] = &r;
            from[i] = t;
        }
    }
    std::string missing;
    size_t n_missing = 0;
    for (size_t i = 0; i < count; ++i) {
        if (by_index[i]) continue;
        if (n_missing++ < 10) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
    }
    if (n_missing) {
        if (n_missing > 10) missing += ", …";
        throw InputError(origins[0], 0, 0,
                         std::to_string(n_missing) + " of " + std::to_string(count) + " inputs are in none of the given tables (index " +
                             missing + "); expected every shard's table");
    }
    std::vector<json> rows;
    rows.reserve(count);
    for (const json* r : by_index) rows.push_back(*r);
    json merged = make_table(std::move(rows), count, digest, ShardSpec());
    merged["battsim_version"] = first["battsim_version"];
    return merged;
}

}  // namespace host
}  // namespace battsim
