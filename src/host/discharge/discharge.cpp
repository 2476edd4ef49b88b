#include "host/discharge/discharge.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/estimate/coulomb_counter.h"
#include "host/input_shape.h"
#include "host/plot/plot.h"
#include "host/report/summary.h"
#include "host/stats.h"

namespace battsim {
namespace host {
namespace discharge {

namespace {

struct Raw {
    double time_s, voltage_v, current_a;
};

// Delivered charge outside this share of the rated capacity is noted.
constexpr double kMinRatedShare = 0.5, kMaxRatedShare = 2.0;
// A constant-current discharge holds its current within kConstantBand of the median nearly
// all the time (a charger's within a percent or two); noted past kMaxOffShare of the time.
constexpr double kConstantBand = 0.2, kMaxOffShare = 0.1;

// Whether the log stops above the minimum voltage: its charge is part of a discharge.
bool done_early(const DischargeOptions& o, double last_voltage_v, bool done) {
    return !done && last_voltage_v > o.min_voltage_v + 0.02 * (o.max_voltage_v - o.min_voltage_v);
}


void locate_zones(DischargeResult& r) {
    Zones& z = r.zones;
    const std::vector<CurvePoint>& c = r.curve;
    const double q_total = r.capacity_mah * 1e-3;
    if (c.size() < 10 || !(q_total > 0)) {
        z.note = "too few points on the curve to locate the zones (need 10 after decimation)";
        return;
    }
    z.full_voltage_v = c.front().voltage_v;
    std::vector<double> mid;
    for (const CurvePoint& p : c) {
        const double q = p.consumed_mah * 1e-3;
        if (q >= 0.3 * q_total && q <= 0.7 * q_total) mid.push_back(p.gradient_v_per_ah);
    }
    if (mid.empty()) {
        z.note = "no points between 30 % and 70 % of the capacity";
        return;
    }
    const double g_nom = host::median(mid);  // negative while discharging
    z.nominal_gradient_v_per_ah = g_nom;
    if (!(g_nom < 0)) {
        z.note = "the voltage does not fall over the middle of the discharge";
        return;
    }
    // The exponential term's slope decays as e^(−B·q); Tremblay puts the zone's end where it
    // is down to e^−3 (5 %), so: the first point after the steepest early slope where the
    // slope in excess of the nominal one is down to 5 % of that maximum.
    size_t i_max = 0;
    double excess_max = 0;
    for (size_t i = 0; i < c.size() && c[i].consumed_mah * 1e-3 <= 0.3 * q_total; ++i) {
        const double excess = g_nom - c[i].gradient_v_per_ah;  // > 0 where steeper than nominal
        if (excess > excess_max) {
            excess_max = excess;
            i_max = i;
        }
    }
    if (!(excess_max > 0)) {
        z.note = "no steeper exponential zone at the start of the curve";
        return;
    }
    size_t i_exp = i_max;
    while (i_exp + 1 < c.size() && g_nom - c[i_exp].gradient_v_per_ah > 0.05 * excess_max) ++i_exp;
    // The nominal zone ends at the knee: past half the capacity, the first point where the
    // curve falls 2.5 times faster than over the middle.
    size_t i_nom = c.size();
    for (size_t i = i_exp; i < c.size(); ++i) {
        if (c[i].consumed_mah * 1e-3 < 0.5 * q_total) continue;
        if (c[i].gradient_v_per_ah < 2.5 * g_nom) {
            i_nom = i;
            break;
        }
    }
    // No knee: the log stops before the cell's end (its last point had stood in for the
    // knee, and the capacity, the zones and the OCV table's empty end were read off a part
    // discharge without a word).
    if (i_nom == c.size()) {
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "no knee at the end of the curve (it never falls 2.5 times faster than over its middle; it "
                      "ends at %.3f V): does the log stop before the end of the discharge?",
                      c.back().voltage_v);
        z.note = buf;
        return;
    }
    if (i_exp == 0 || i_exp >= i_nom) {
        z.note = "the exponential zone runs into the end of the nominal zone";
        return;
    }
    z.exponential_end_ah = c[i_exp].consumed_mah * 1e-3;
    z.exponential_end_v = c[i_exp].voltage_v;
    z.nominal_end_ah = c[i_nom].consumed_mah * 1e-3;
    z.nominal_end_v = c[i_nom].voltage_v;
    z.found = true;
}

}  // namespace

DischargeResult process_discharge(const std::string& path, const DischargeOptions& o) {
    if (!(o.min_voltage_v > 0) || !(o.max_voltage_v > o.min_voltage_v))
        throw std::invalid_argument("need 0 < minimum voltage < maximum voltage");
    // The table has a row every step_v between the two: a typo of 1e5 V had asked for ten
    // million rows and 9 GB.
    if (!(o.max_voltage_v <= kMaxTableVoltage_v))
        throw std::invalid_argument("the maximum voltage must be at most " + std::to_string(static_cast<int>(kMaxTableVoltage_v)) + " V");
    if (o.decimate < 1) throw std::invalid_argument("--decimate must be at least 1");
    if (!(o.alpha >= 0 && o.alpha <= 1)) throw std::invalid_argument("--alpha must be in (0, 1]");
    if (!(o.reaction_s >= 0)) throw std::invalid_argument("--reaction must be a number of seconds >= 0");
    if (!(o.step_v > 0)) throw std::invalid_argument("the table step must be positive");
    DischargeResult r;
    r.path = path;
    std::unique_ptr<SampleReader> reader = open_reader(path, o.reader);
    core::Sample s;
    std::vector<Raw> raw;
    // What replay says of the log's shape (samples 1000 s apart, a clock that jumps) holds for
    // a discharge read the same way.
    ShapePack pack;
    pack.empty_v = o.min_voltage_v;
    pack.full_v = o.max_voltage_v;
    if (o.rated_capacity_ah > 0) pack.capacity_ah = o.rated_capacity_ah;
    InputShape shape(o.reader.columns.current_negative_is_discharge, o.loaded_current_a, pack);
    bool connected = false, done = false;
    // The discharge going on under load below the minimum: cut off there without a word, a
    // Li-ion cell read with a 3.325 V LiPo minimum lost its last sixth.
    double below_s = 0.0, below_low_v = INFINITY, below_last_s = NAN;
    while (reader->next(s)) {
        ++r.samples_read;
        shape.add(s);
        if (done) {  // read to the end so the reader checks the whole file
            const double t_s = s.time_us * 1e-6;
            if (std::isfinite(s.voltage_v) && s.voltage_v <= o.min_voltage_v && s.current_a > 0.1f) {
                if (std::isfinite(below_last_s)) below_s += t_s - below_last_s;
                below_low_v = std::min(below_low_v, static_cast<double>(s.voltage_v));
                below_last_s = t_s;
            } else {
                below_last_s = NAN;
            }
            continue;
        }
        const bool above = std::isfinite(s.voltage_v) && s.voltage_v > o.min_voltage_v;
        if (!connected && !above) continue;
        if (connected && !above) {
            done = true;
            continue;
        }
        connected = true;
        raw.push_back(Raw{s.time_us * 1e-6, s.voltage_v, s.current_a});
    }
    r.info = reader->info();
    if (raw.size() < 2) {
        char buf[240];
        std::snprintf(buf, sizeof buf,
                      "fewer than 2 samples above the minimum voltage of %.3f V: is the battery connected, and is the "
                      "minimum right (--min-voltage, or the config's battery.min_voltage_v: without -c, a 4S pack's)?",
                      o.min_voltage_v);
        throw InputError(path, 0, 0, buf);
    }
    const double duration_s = raw.back().time_s - raw.front().time_s;
    if (below_s > 0.01 * duration_s) {
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "the discharge goes on under load below the minimum voltage of %.3f V for %.0f s, down to %.3f V: "
                      "the capacity, the table and the zones end at the minimum (give --min-voltage to go lower)",
                      o.min_voltage_v, below_s, below_low_v);
        r.info.notes.push_back(buf);
    }
    r.samples_kept = raw.size();
    r.start_time_s = raw.front().time_s;
    r.end_time_s = raw.back().time_s;
    r.duration_s = r.end_time_s - r.start_time_s;
    r.first_voltage_v = raw.front().voltage_v;
    r.last_voltage_v = raw.back().voltage_v;

    // Charge and energy as the firmware counts them (rectangular rule, float, compensated).
    core::CoulombCounter counter;
    counter.reset(0.0f, 0.0f);
    std::vector<double> mah(raw.size()), mwh(raw.size()), smooth(raw.size());
    double v_filtered = raw[0].voltage_v;
    for (size_t i = 0; i < raw.size(); ++i) {
        const double dt = i > 0 ? raw[i].time_s - raw[i - 1].time_s : 0.0;
        if (i > 0) counter.update(static_cast<float>(raw[i].current_a), static_cast<float>(raw[i].voltage_v), static_cast<float>(dt));
        mah[i] = counter.status().consumed_mah;
        mwh[i] = counter.status().consumed_mwh;
        if (i > 0) {
            double a = 1.0;
            if (o.alpha > 0) a = o.alpha;
            else if (o.reaction_s > 0) a = std::min(1.0, dt / o.reaction_s);
            v_filtered += a * (raw[i].voltage_v - v_filtered);
        }
        smooth[i] = v_filtered;
    }
    r.capacity_mah = mah.back();
    r.energy_mwh = mwh.back();
    r.mean_current_a = r.duration_s > 0 ? r.capacity_mah * 3.6 / r.duration_s : 0;
    if (r.mean_current_a < 0)
        throw InputError(path, 0, 0,
                         "the mean current is negative (" + std::to_string(r.mean_current_a) +
                             " A): expected positive = discharge; if the log records discharge as negative, pass --negative-discharge");
    r.rated_capacity_ah = std::max(o.rated_capacity_ah, 0.0);
    // A charge far from the pack's rating: a unit a thousand times off (a current in mA read
    // as A delivered 2956 Ah from a 3 Ah cell), or a config for another pack. A discharge that
    // stopped early, or went on below the minimum, says so itself.
    const bool cut_short = done_early(o, r.last_voltage_v, done) || below_s > 0.01 * duration_s;
    if (r.rated_capacity_ah > 0) {
        const double ratio = r.capacity_mah * 1e-3 / o.rated_capacity_ah;
        if (ratio > kMaxRatedShare || (ratio < kMinRatedShare && !cut_short)) {
            // A hundredfold is no pack's spread: a unit; within it, a pack's (or a config's).
            const bool unit = ratio > 100.0 || ratio < 0.01;
            char buf[400];
            std::snprintf(buf, sizeof buf, "the discharge delivered %.4g mAh, %.3g times the config's rated %.4g Ah: %s",
                          r.capacity_mah, ratio, o.rated_capacity_ah,
                          unit ? "a current or time unit off by a thousand (--current-unit, --time-unit)?"
                          : ratio > 1.0 ? "a config for another pack?"
                                        : "a config for another pack, or a pack worn or not charged full?");
            r.info.notes.push_back(buf);
        }
    }
    // A load that varies (a flight, a pulsed test) is no constant-current discharge: the
    // curve then follows the load's sag more than the cell's charge.
    {
        std::vector<double> currents;
        for (const Raw& x : raw) currents.push_back(x.current_a);
        const double median_a = median(currents);
        double off_s = 0.0, lo_a = INFINITY, hi_a = -INFINITY;
        for (size_t i = 1; i < raw.size(); ++i) {
            if (std::fabs(raw[i].current_a - median_a) > kConstantBand * std::fabs(median_a))
                off_s += raw[i].time_s - raw[i - 1].time_s;
            lo_a = std::min(lo_a, raw[i].current_a);
            hi_a = std::max(hi_a, raw[i].current_a);
        }
        const double off_share = r.duration_s > 0 ? off_s / r.duration_s : 0.0;
        if (off_share > kMaxOffShare) {
            char buf[400];
            std::snprintf(buf, sizeof buf,
                          "the current was not constant: %.0f %% of the time more than %.0f %% off its median of %.4g A "
                          "(from %.4g to %.4g A): a flight or a pulsed test, not a constant-current discharge; its "
                          "capacity, zones and OCV table follow the load's sag more than the cell's charge",
                          100.0 * off_share, 100.0 * kConstantBand, median_a, lo_a, hi_a);
            r.info.notes.push_back(buf);
        }
    }
    const bool merged = r.info.averaged_in > r.info.averaged_out + r.info.averaged_out / 5;  // as replay_log
    for (const std::string& note :
         shape.notes(r.mean_current_a >= o.loaded_current_a && r.duration_s >= InputShape::kShortestFlightS,
                     o.loaded_current_a, InputShape::Lags{},
                     static_cast<double>(o.reader.average_us) * 1e-6, r.info.format == LogFormat::Csv, merged, false,
                     ColumnUnits{r.info.time_scale_to_s, r.info.time_column, r.info.current_scale_to_a}))
        r.info.notes.push_back(note);

    // Decimate by averaging blocks of `decimate` samples (the last block may be shorter).
    const size_t x = static_cast<size_t>(o.decimate);
    for (size_t b = 0; b < raw.size(); b += x) {
        const size_t e = std::min(raw.size(), b + x);
        CurvePoint p;
        for (size_t i = b; i < e; ++i) {
            p.time_s += raw[i].time_s - r.start_time_s;
            p.voltage_v += smooth[i];
            p.current_a += raw[i].current_a;
            p.consumed_mah += mah[i];
            p.consumed_mwh += mwh[i];
        }
        const double n = static_cast<double>(e - b);
        p.time_s /= n;
        p.voltage_v /= n;
        p.current_a /= n;
        p.consumed_mah /= n;
        p.consumed_mwh /= n;
        r.curve.push_back(p);
    }
    // One averaged point is no curve: said with its cause, not later as a table's "fewer than 2 points".
    if (r.curve.size() < 2 && raw.size() >= 2)
        throw std::invalid_argument("--decimate " + std::to_string(o.decimate) + " averages the discharge's " +
                                    std::to_string(raw.size()) + " samples into " + std::to_string(r.curve.size()) +
                                    " point; expected at most " + std::to_string(raw.size() / 2) + " to keep a curve");
    const double span_mah = std::max(o.gradient_span * r.capacity_mah, 1e-9);
    for (size_t i = 0; i < r.curve.size(); ++i) {
        size_t lo = i, hi = i;
        while (lo > 0 && r.curve[i].consumed_mah - r.curve[lo].consumed_mah < 0.5 * span_mah) --lo;
        while (hi + 1 < r.curve.size() && r.curve[hi].consumed_mah - r.curve[i].consumed_mah < 0.5 * span_mah) ++hi;
        const double dq_ah = (r.curve[hi].consumed_mah - r.curve[lo].consumed_mah) * 1e-3;
        r.curve[i].gradient_v_per_ah = dq_ah > 0 ? (r.curve[hi].voltage_v - r.curve[lo].voltage_v) / dq_ah : 0.0;
    }

    // Lookup tables: rows from the maximum down to the minimum voltage every step. Points that
    // round to the same row are averaged; a row no point rounds to takes the next available
    // row below it (the value the discharge reaches next), and rows past the lowest measured
    // one take that one (the nearest edge).
    // Rows at or above the minimum only (a maximum off the step, 4.205 V, had rounded up to a
    // row below it).
    const long rows = static_cast<long>(std::floor((o.max_voltage_v - o.min_voltage_v) / o.step_v + 1e-9)) + 1;
    std::vector<double> sum_mah(rows, 0), sum_mwh(rows, 0);
    std::vector<long> count(rows, 0);
    for (const CurvePoint& p : r.curve) {
        const long j = std::lround((o.max_voltage_v - p.voltage_v) / o.step_v);
        if (j < 0 || j >= rows) continue;
        sum_mah[j] += p.consumed_mah;
        sum_mwh[j] += p.consumed_mwh;
        ++count[j];
    }
    r.table.resize(rows);
    long last = -1;
    for (long j = 0; j < rows; ++j) {
        r.table[j].voltage_v = o.max_voltage_v - j * o.step_v;
        if (count[j] > 0) last = j;
    }
    if (last < 0)
        throw InputError(path, 0, 0, "no point of the curve lies between the table's minimum and maximum voltage");
    for (long j = rows - 1; j >= 0; --j) {
        TableRow& row = r.table[j];
        if (count[j] > 0) {
            row.consumed_mah = sum_mah[j] / count[j];
            row.consumed_mwh = sum_mwh[j] / count[j];
            row.measured = true;
        } else if (j > last) {
            row.consumed_mah = sum_mah[last] / count[last];
            row.consumed_mwh = sum_mwh[last] / count[last];
        } else {
            row.consumed_mah = r.table[j + 1].consumed_mah;
            row.consumed_mwh = r.table[j + 1].consumed_mwh;
        }
    }
    locate_zones(r);
    // A log that stops above the minimum voltage holds part of a discharge: its capacity is
    // what flowed until it stopped, and the zones would be read off the wrong part of the curve
    // (the first 200 rows of a 3 Ah cell's had made a 0.017 Ah config without a word).
    if (done_early(o, r.last_voltage_v, done)) {
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "the log ends at %.3f V, above the minimum voltage of %.3f V: the discharge stopped before its "
                      "end, and %.1f mAh is only what flowed until then (to process the part as it is, give --min-voltage %.2f)",
                      r.last_voltage_v, o.min_voltage_v, r.capacity_mah, std::floor(r.last_voltage_v * 100.0) / 100.0);
        r.ended_early = buf;
        r.zones = Zones{};
        r.zones.note = buf;
    }
    return r;
}

double mean_c_rate(const DischargeResult& r) {
    const double capacity_ah = r.rated_capacity_ah > 0 ? r.rated_capacity_ah : r.capacity_mah * 1e-3;
    return capacity_ah > 0 ? r.mean_current_a / capacity_ah : 0.0;
}

std::string c_rate_text(const DischargeResult& r) {
    const double rate = mean_c_rate(r);
    // Two figures below 10C (0.1C, 2.5C), whole ones above (14C, not 1.4e+01C).
    char figure[32];
    std::snprintf(figure, sizeof figure, rate >= 10.0 ? "%.0fC" : "%.2gC", rate);
    char buf[160];
    if (r.rated_capacity_ah > 0)
        std::snprintf(buf, sizeof buf, "%s of the config's rated %.3g Ah", figure, r.rated_capacity_ah);
    else
        std::snprintf(buf, sizeof buf, "%s of the charge it delivered, no -c config to rate it by", figure);
    return buf;
}

nlohmann::json discharge_to_json(const DischargeResult& r, bool with_table) {
    nlohmann::json j;
    j["schema"] = "battsim.discharge";
    j["schema_version"] = 1;
    j["battsim_version"] = BATTSIM_VERSION;  // as every other report: which release wrote it
    // A discharge that stopped above the minimum voltage is said where a program looks: its
    // capacity_mah is only what flowed until then (it had been said on standard error alone).
    nlohmann::json notes = r.info.notes;
    if (!r.ended_early.empty()) notes.push_back(r.ended_early);
    j["input"] = {{"path", r.path}, {"format", to_string(r.info.format)}, {"notes", notes}};
    j["complete"] = r.ended_early.empty();
    j["samples"] = {{"read", r.samples_read}, {"kept", r.samples_kept}, {"curve_points", r.curve.size()}};
    j["kept_from_s"] = round_time_s(r.start_time_s);
    j["kept_to_s"] = round_time_s(r.end_time_s);
    j["duration_s"] = round_sig(r.duration_s, 7);
    j["mean_current_a"] = round_sig(r.mean_current_a, 6);
    j["mean_c_rate_per_h"] = round_sig(mean_c_rate(r), 4);
    j["c_rate_of"] = r.rated_capacity_ah > 0 ? "rated capacity" : "delivered charge";
    j["capacity_mah"] = round_sig(r.capacity_mah, 6);
    j["energy_mwh"] = round_sig(r.energy_mwh, 6);
    j["first_voltage_v"] = round_sig(r.first_voltage_v, 6);
    j["last_voltage_v"] = round_sig(r.last_voltage_v, 6);
    const Zones& z = r.zones;
    if (z.found) {
        j["zones"] = {{"found", true},
                      {"full_voltage_v", round_sig(z.full_voltage_v, 6)},
                      {"exponential_end", {{"capacity_ah", round_sig(z.exponential_end_ah, 5)}, {"voltage_v", round_sig(z.exponential_end_v, 5)}}},
                      {"nominal_end", {{"capacity_ah", round_sig(z.nominal_end_ah, 5)}, {"voltage_v", round_sig(z.nominal_end_v, 5)}}},
                      {"nominal_gradient_v_per_ah", round_sig(z.nominal_gradient_v_per_ah, 5)}};
    } else {
        j["zones"] = {{"found", false}, {"note", z.note}};
    }
    if (with_table) {
        nlohmann::json t = nlohmann::json::array();
        for (const TableRow& row : r.table)
            t.push_back({{"voltage_v", round_sig(row.voltage_v, 6)}, {"consumed_mah", round_sig(row.consumed_mah, 6)},
                         {"consumed_mwh", round_sig(row.consumed_mwh, 6)}, {"measured", row.measured}});
        j["table"] = t;
    }
    return j;
}

std::string table_csv(const DischargeResult& r) {
    std::string s = "voltage_v,consumed_mah,consumed_mwh,measured\n";
    char buf[96];
    for (const TableRow& row : r.table) {
        std::snprintf(buf, sizeof buf, "%.3f,%.2f,%.2f,%d\n", row.voltage_v, row.consumed_mah, row.consumed_mwh, row.measured ? 1 : 0);
        s += buf;
    }
    return s;
}

std::string curve_csv(const DischargeResult& r) {
    std::string s = "time_s,voltage_v,current_a,consumed_mah,consumed_mwh,gradient_v_per_ah\n";
    char buf[160];
    for (const CurvePoint& p : r.curve) {
        std::snprintf(buf, sizeof buf, "%.3f,%.5f,%.5f,%.3f,%.3f,%.6f\n", p.time_s, p.voltage_v, p.current_a, p.consumed_mah,
                      p.consumed_mwh, p.gradient_v_per_ah);
        s += buf;
    }
    return s;
}

void plot_discharge(const DischargeResult& r, const std::string& path) {
    plot::Panel p;
    char title[200];
    std::snprintf(title, sizeof title, "%.0f mAh at %.3f A mean, %.0f mWh", r.capacity_mah, r.mean_current_a, r.energy_mwh);
    p.title = title;
    p.xlabel = "consumed (mAh)";
    p.ylabel = "voltage (V)";
    p.y2label = "gradient dV/dQ (V/Ah)";
    plot::Series v, g;
    v.title = "voltage (smoothed)";
    v.color = "#d62728";
    v.width = 1.5;
    g.title = "gradient";
    g.color = "#1f77b4";
    g.y2 = true;
    for (const CurvePoint& c : r.curve) {
        v.x.push_back(c.consumed_mah);
        v.y.push_back(c.voltage_v);
        g.x.push_back(c.consumed_mah);
        g.y.push_back(c.gradient_v_per_ah);
    }
    p.series = {v, g};
    if (r.zones.found) {
        char label[96];
        std::snprintf(label, sizeof label, "exponential zone end %.0f mAh, %.3f V", r.zones.exponential_end_ah * 1e3, r.zones.exponential_end_v);
        p.vertical_marks.push_back({r.zones.exponential_end_ah * 1e3, label});
        std::snprintf(label, sizeof label, "nominal zone end %.0f mAh, %.3f V", r.zones.nominal_end_ah * 1e3, r.zones.nominal_end_v);
        p.vertical_marks.push_back({r.zones.nominal_end_ah * 1e3, label});
        plot::Series nominal;
        nominal.title = "nominal gradient";
        nominal.color = "#7f7f7f";
        nominal.y2 = true;
        nominal.x = {0.0, r.capacity_mah};
        nominal.y = {r.zones.nominal_gradient_v_per_ah, r.zones.nominal_gradient_v_per_ah};
        p.series.push_back(nominal);
    }
    plot::render({p}, "battsim discharge: " + r.path, path, 1400, 700);
}

core::TremblayParams params_from_discharge(const DischargeResult& r, const core::TremblayParams& keep) {
    if (!r.zones.found) throw std::invalid_argument("the zones were not found (" + r.zones.note + ")");
    core::TremblayParams p = keep;
    p.full_voltage_v = static_cast<float>(r.zones.full_voltage_v);
    p.exponential_voltage_v = static_cast<float>(r.zones.exponential_end_v);
    p.exponential_capacity_ah = static_cast<float>(r.zones.exponential_end_ah);
    p.nominal_zone_voltage_v = static_cast<float>(r.zones.nominal_end_v);
    p.nominal_zone_capacity_ah = static_cast<float>(r.zones.nominal_end_ah);
    p.capacity_ah = static_cast<float>(r.capacity_mah * 1e-3);
    p.curve_current_a = static_cast<float>(r.mean_current_a);
    return p;
}

OcvTableRead ocv_table_from_discharge(const DischargeResult& r, int cells, double resistance_ohm, int points) {
    if (points < 2 || points > core::kOcvTableMaxPoints)
        throw std::invalid_argument("OCV table points must be 2.." + std::to_string(core::kOcvTableMaxPoints) + ", got " +
                                    std::to_string(points));
    if (cells < 1) throw std::invalid_argument("OCV table: cells in series must be at least 1");
    if (!(resistance_ohm >= 0)) throw std::invalid_argument("OCV table: the resistance must be 0 or more");
    if (!r.ended_early.empty()) throw std::invalid_argument("OCV table: " + r.ended_early);
    const std::vector<CurvePoint>& c = r.curve;
    const double q_total_ah = r.capacity_mah * 1e-3;
    if (c.size() < 2 || !(q_total_ah > 0))
        throw std::invalid_argument("OCV table: the discharge curve has fewer than 2 points or no charge");
    OcvTableRead t;
    t.cells = cells;
    t.capacity_ah = q_total_ah;
    t.sag_resistance_ohm = resistance_ohm;
    t.mean_c_rate = mean_c_rate(r);
    // The curve is in order of charge drawn; interpolate voltage and current at each
    // table point's charge (clamped to the curve's ends).
    size_t i = c.size() - 1;  // the segment (c[i − 1], c[i]] holding the charge; moves down
    for (int k = 0; k < points; ++k) {
        const double soc = static_cast<double>(k) / (points - 1);
        const double q_mah = (1.0 - soc) * r.capacity_mah;
        double v = 0, a = 0;
        if (q_mah <= c.front().consumed_mah) {
            v = c.front().voltage_v;
            a = c.front().current_a;
        } else if (q_mah >= c.back().consumed_mah) {
            v = c.back().voltage_v;
            a = c.back().current_a;
        } else {
            // Points go from SOC 0 (the end of the curve) upwards, so the charge only falls;
            // c.front() is below it, so this stops at i ≥ 1.
            while (i > 1 && c[i - 1].consumed_mah >= q_mah) --i;
            const CurvePoint& lo = c[i - 1];
            const CurvePoint& hi = c[i];
            const double span = hi.consumed_mah - lo.consumed_mah;
            const double f = span > 0 ? (q_mah - lo.consumed_mah) / span : 0.0;
            v = lo.voltage_v + f * (hi.voltage_v - lo.voltage_v);
            a = lo.current_a + f * (hi.current_a - lo.current_a);
        }
        t.cell_voltage_v.push_back((v + a * resistance_ohm) / cells);
    }
    // The estimator inverts the table: keep it rising (a flat stretch read with noise can dip
    // by a fraction of a millivolt).
    int lifted = 0;
    for (size_t k = 1; k < t.cell_voltage_v.size(); ++k) {
        if (t.cell_voltage_v[k] <= t.cell_voltage_v[k - 1]) {
            t.cell_voltage_v[k] = t.cell_voltage_v[k - 1] + 1e-4;
            ++lifted;
        }
    }
    if (lifted > 0)
        t.notes.push_back(std::to_string(lifted) + " OCV table point(s) lifted to keep the table rising (noise on a flat stretch)");
    if (t.mean_c_rate > 0.25) {
        t.notes.push_back("the discharge ran at a mean " + c_rate_text(r) +
                          ": faster than C/4 its polarisation sags the table below the rest voltage by more than the I·R "
                          "correction takes back; read the table off a C/10 to C/5 discharge");
    }
    return t;
}

nlohmann::json ocv_table_to_json(const OcvTableRead& t) {
    nlohmann::json v = nlohmann::json::array();
    for (double x : t.cell_voltage_v) v.push_back(round_sig(x, 5));
    return {{"cells_in_series", t.cells},
            {"capacity_ah", round_sig(t.capacity_ah, 5)},
            {"sag_resistance_ohm", round_sig(t.sag_resistance_ohm, 5)},
            {"mean_c_rate_per_h", round_sig(t.mean_c_rate, 4)},
            {"cell_voltage_v", v},
            {"notes", t.notes}};
}

LoadedConfig start_config_from_discharge(const DischargeResult& r, const LoadedConfig& base, const OcvTableRead* ocv) {
    LoadedConfig out = base;
    out.monitor.battery = params_from_discharge(r, base.monitor.battery);
    if (ocv) {
        core::OcvTable& table = out.monitor.joint.ocv;
        table = core::OcvTable{};
        table.points = static_cast<int>(ocv->cell_voltage_v.size());
        for (int k = 0; k < table.points; ++k) table.cell_voltage_v[k] = static_cast<float>(ocv->cell_voltage_v[k]);
    }
    const size_t slash = r.path.find_last_of('/');
    out.name = "discharge-" + (slash == std::string::npos ? r.path : r.path.substr(slash + 1));
    out.description = "Tremblay points read off the discharge " + r.path + " by battsim discharge " BATTSIM_VERSION
                             " (start values for battsim fit; the resistance is the base config's)";
    if (ocv) out.description += "; the joint estimator's OCV table read off the same discharge, I*R added back";
    return out;
}

}  // namespace discharge
}  // namespace host
}  // namespace battsim
