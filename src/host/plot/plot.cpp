#include "host/plot/plot.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <gnuplot-iostream.h>
#include <signal.h>
#include <unistd.h>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "host/io/atomic_file.h"
#include "host/io/csv_reader.h"
#include "host/io/json_text.h"
#include "host/io/line_reader.h"

namespace battsim {
namespace host {
namespace plot {

namespace {

// Case aside: "P.PNG" is a PNG too.
bool ends_with(const std::string& s, const char* suffix) {
    const std::string x(suffix);
    if (s.size() < x.size()) return false;
    for (size_t i = 0; i < x.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(s[s.size() - x.size() + i])) != x[i]) return false;
    return true;
}

// gnuplot single-quoted string: a quote is written twice. What is not UTF-8 (a Latin-1 log
// name) is replaced, or the SVG is not well-formed XML.
std::string gnuplot_quoted(const std::string& s) {
    std::string q = "'";
    for (char c : valid_utf8(s)) {
        if (c == '\'') q += "''";
        else if (c == '\n' || c == '\r') q += ' ';
        else q += c;
    }
    return q + "'";
}

void append_number(std::string& out, const char* fmt, double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, fmt, v);
    out += buf;
}

// "set <axis>range [lo:hi]" when both ends are given, else autoscaling for that axis.
std::string range_command(const char* axis, double lo, double hi) {
    if (!(std::isfinite(lo) && std::isfinite(hi) && hi > lo)) return std::string("set autoscale ") + axis + "\n";
    std::string cmd = std::string("set ") + axis + "range [";
    append_number(cmd, "%.9g", lo);
    cmd += ':';
    append_number(cmd, "%.9g", hi);
    return cmd + "]\n";
}

// `s` as one word for /bin/sh ($TMPDIR may hold spaces or quotes).
std::string shell_quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace

bool Series::has_points() const {
    // A line needs two points to be drawn: one alone would be an empty line with a legend.
    const size_t needed = style.compare(0, 5, "lines") == 0 || style == "steps" ? 2 : 1;
    size_t n = 0;
    for (size_t i = 0; i < x.size() && i < y.size() && n < needed; ++i) {
        if (std::isfinite(x[i]) && std::isfinite(y[i])) ++n;
    }
    return n >= needed;
}

bool Panel::y2_used() const {
    for (const Series& s : series) {
        if (s.y2 && s.has_points()) return true;
    }
    return false;
}

bool Panel::has_points() const {
    for (const Series& s : series) {
        if (s.has_points()) return true;
    }
    return false;
}

void check_plot_path(const std::string& path) {
    if (!ends_with(path, ".png") && !ends_with(path, ".svg"))
        throw std::invalid_argument("plot file \"" + path + "\": expected a name ending in .png or .svg");
}

bool gnuplot_on_path() {
    const char* path = std::getenv("PATH");
    if (path == nullptr) return false;
    std::string dirs = path;
    size_t start = 0;
    while (start <= dirs.size()) {
        const size_t end = std::min(dirs.find(':', start), dirs.size());
        std::string dir = dirs.substr(start, end - start);
        if (dir.empty()) dir = ".";  // an empty PATH entry is the working directory
        if (::access((dir + "/gnuplot").c_str(), X_OK) == 0) return true;
        start = end + 1;
    }
    return false;
}

void thin_envelope(const std::vector<double>& x, const std::vector<double>& y, size_t max_points,
                   std::vector<double>& xo, std::vector<double>& yo) {
    xo.clear();
    yo.clear();
    const size_t n = std::min(x.size(), y.size());
    if (n <= max_points || max_points < 4) {
        xo.assign(x.begin(), x.begin() + n);
        yo.assign(y.begin(), y.begin() + n);
        return;
    }
    const size_t buckets = max_points / 2;
    for (size_t b = 0; b < buckets; ++b) {
        const size_t lo = b * n / buckets, hi = (b + 1) * n / buckets;
        size_t imin = hi, imax = hi;
        bool gap = false;
        for (size_t i = lo; i < hi; ++i) {
            if (!std::isfinite(y[i])) {
                gap = true;
                continue;
            }
            if (imin == hi || y[i] < y[imin]) imin = i;
            if (imax == hi || y[i] > y[imax]) imax = i;
        }
        if (imin == hi) {
            xo.push_back(x[lo]);
            yo.push_back(NAN);
            continue;
        }
        const size_t first = std::min(imin, imax), second = std::max(imin, imax);
        xo.push_back(x[first]);
        yo.push_back(y[first]);
        if (second != first) {
            xo.push_back(x[second]);
            yo.push_back(y[second]);
        }
        if (gap) {
            xo.push_back(x[hi - 1]);
            yo.push_back(NAN);
        }
    }
}

void render(const std::vector<Panel>& panels, const std::string& title, const std::string& path, int width_px,
            int panel_height_px) {
    check_plot_path(path);
    if (panels.empty()) throw std::invalid_argument("plot: nothing to draw");
    const bool svg = ends_with(path, ".svg");
    // Created first, so a directory that cannot take the file fails before gnuplot runs;
    // gnuplot writes the temporary by name and it is renamed into place only on success.
    std::unique_ptr<AtomicFile> out;
    try {
        out = std::make_unique<AtomicFile>(path);
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(std::string("plot: ") + e.what());
    }
    const std::string& temp = out->temp_path();
    // gnuplot's messages, removed on Ctrl-C too (the signal handler knows it).
    std::unique_ptr<ScratchFile> err_file;
    try {
        err_file = std::make_unique<ScratchFile>("battsim-gnuplot-");
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(std::string("plot: gnuplot's messages: ") + e.what());
    }
    const std::string& err_path = err_file->path();

    std::string script;
    script.reserve(1 << 20);
    const int height = panel_height_px * static_cast<int>(panels.size()) + 40;
    script += svg ? "set terminal svg size " : "set terminal pngcairo size ";
    script += std::to_string(width_px) + "," + std::to_string(height) + " font 'DejaVu Sans,10' noenhanced\n";
    script += "set encoding utf8\n";  // units such as mΩ in labels
    script += "set output " + gnuplot_quoted(temp) + "\n";
    // Data first, as datablocks; a blank line breaks a line at missing values.
    int block = 0;
    for (const Panel& p : panels) {
        for (const Series& s : p.series) {
            script += "$d" + std::to_string(block++) + " << EOD\n";
            bool broken = true;
            for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
                if (!std::isfinite(s.y[i]) || !std::isfinite(s.x[i])) {
                    if (!broken) script += "\n";
                    broken = true;
                    continue;
                }
                append_number(script, "%.9g", s.x[i]);
                script += ' ';
                append_number(script, "%.7g", s.y[i]);
                script += '\n';
                broken = false;
            }
            script += "EOD\n";
        }
    }
    // Fixed side margins, the same in every panel, so the panels' time axes line up.
    bool any_y2 = false;
    for (const Panel& p : panels) any_y2 = any_y2 || p.y2_used();
    script += "set lmargin 11\nset rmargin " + std::string(any_y2 ? "11" : "3") + "\n";
    script += "set multiplot layout " + std::to_string(panels.size()) + ",1 title " + gnuplot_quoted(title) + "\n";
    block = 0;
    for (const Panel& p : panels) {
        script += "unset arrow\nunset label\nset grid\n";
        if (p.key_above) {
            // A taller top margin: the title on its own row, the legend's row under it.
            script += "set tmargin 4\nset key at graph 1, graph 1 right bottom horizontal\n";
        } else {
            script += "set tmargin -1\nset key top right opaque box\n";
        }
        script += "set title " + gnuplot_quoted(p.title) + "\n";
        script += "set xlabel " + gnuplot_quoted(p.xlabel) + "\nset ylabel " + gnuplot_quoted(p.ylabel) + "\n";
        if (p.y2_used()) {
            script += "set ytics nomirror\nset y2tics\nset y2label " + gnuplot_quoted(p.y2label) + "\n";
        } else {
            script += "set ytics mirror\nunset y2tics\nunset y2label\n";
        }
        double x_min = p.x_min, x_max = p.x_max, y_min = p.y_min, y_max = p.y_max;
        if (!p.has_points()) {  // gnuplot cannot autoscale an axis without data: a unit frame
            if (!(y_max > y_min)) y_min = 0, y_max = 1;
            if (!(x_max > x_min) && !(std::isfinite(x_min) && x_min == x_max)) x_min = 0, x_max = 1;
        }
        if (std::isfinite(x_min) && x_min == x_max) {  // one instant: a second either side
            x_min -= 1.0;
            x_max += 1.0;
        }
        script += range_command("y", y_min, y_max);
        script += range_command("y2", p.y2_min, p.y2_max);
        script += range_command("x", x_min, x_max);
        for (const auto& m : p.vertical_marks) {
            std::string x;
            append_number(x, "%.9g", m.first);
            script += "set arrow from " + x + ", graph 0 to " + x + ", graph 1 nohead dt 2 lw 1.5 lc rgb 'black'\n";
            script += "set label " + gnuplot_quoted(m.second) + " at " + x + ", graph 0.06 rotate by 90 offset -1,0 front\n";
        }
        // A plot of legend entries alone trips an assertion in gnuplot 5.4: an undefined
        // function, drawn as nothing, comes first.
        std::string cmd = p.has_points() ? "plot " : "plot NaN notitle";
        bool first = p.has_points();
        for (const Series& s : p.series) {
            if (!first) cmd += ", ";
            first = false;
            const std::string data = "$d" + std::to_string(block++);
            // gnuplot stops at a series with no valid point; its legend entry still says it is empty.
            cmd += s.has_points() ? data + " using 1:2 with " + s.style : "keyentry with " + s.style;
            if (s.style == "lines" || s.style == "linespoints" || s.style == "steps" || s.style == "impulses") {
                std::string w;
                append_number(w, "%.2g", s.width);
                cmd += " lw " + w;
            }
            if (!s.color.empty()) cmd += " lc rgb " + gnuplot_quoted(s.color);
            if (s.has_points()) cmd += s.y2 ? " axes x1y2" : " axes x1y1";
            cmd += " title " + gnuplot_quoted(s.has_points() || s.title.empty() ? s.title : s.title + " (no values)");
        }
        script += cmd + "\n";
    }
    script += "unset multiplot\nunset output\n";
    // gnuplot stops at the first error, and its exit status does not reach us through the
    // pipe: only a script that ran to its end prints this.
    static const char* const kDone = "battsim-plot-done";
    script += std::string("print '") + kDone + "'\n";

    {
        // A gnuplot that died (or never started) closes the pipe: the write fails and the
        // checks below say so, instead of SIGPIPE ending the run without a word.
        struct IgnorePipe {
            struct sigaction old_action {};
            IgnorePipe() {
                struct sigaction ignore {};
                ignore.sa_handler = SIG_IGN;
                sigemptyset(&ignore.sa_mask);
                sigaction(SIGPIPE, &ignore, &old_action);
            }
            ~IgnorePipe() { sigaction(SIGPIPE, &old_action, nullptr); }
        } ignore_pipe;
        try {
            Gnuplot gp("gnuplot > " + shell_quoted(err_path) + " 2>&1");
            gp << script;
            gp.flush();
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("plot: cannot run gnuplot: ") + e.what());
        }
    }
    // The Gnuplot object has closed the pipe and waited for gnuplot to exit.
    const std::string messages = read_all(err_path);
    err_file.reset();
    std::ifstream check(temp, std::ios::binary | std::ios::ate);
    // A device written straight (/dev/null) has no size to show for what it took.
    const bool ok = check && (out->direct() || check.tellg() > 0) && messages.find("rror") == std::string::npos &&
                    messages.find(kDone) != std::string::npos;
    check.close();
    if (!ok) throw std::runtime_error("plot: gnuplot failed to write " + path + (messages.empty() ? "" : ": " + messages));
    try {
        out->commit();
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(std::string("plot: ") + e.what());
    }
}

// --- replay -------------------------------------------------------------------------------

void ReplaySeries::add(const core::Sample& sample, const core::MonitorStatus& s) {
    if (!s.sample_valid) return;
    const double nan = NAN;
    time_s.push_back(sample.time_us * 1e-6);
    voltage_v.push_back(sample.voltage_v);
    current_a.push_back(sample.current_a);
    filtered_a.push_back(s.filtered_current_a);
    model_v.push_back(s.initialised ? s.model_voltage_v : nan);
    adapted_v.push_back(s.initialised ? s.adapted_model_voltage_v : nan);
    capacity_ah.push_back(s.capacity_ah);
    resistance_ohm.push_back(s.resistance_ohm > 0 ? s.resistance_ohm : nan);
    remaining_s.push_back(s.time_valid ? s.remaining_time_s : nan);
    total_s.push_back(s.time_valid ? s.total_time_s : nan);
    flying.push_back(s.flying);
    if (cell_v.size() < sample.cell_count) cell_v.resize(sample.cell_count, std::vector<double>(time_s.size() - 1, nan));
    for (size_t c = 0; c < cell_v.size(); ++c) cell_v[c].push_back(c < sample.cell_count ? sample.cell_voltage_v[c] : nan);
}

ReplaySeries read_replay_series_csv(const std::string& path) {
    LineReader lines(path);
    std::string_view line;
    if (!lines.next(line)) throw InputError(path, 0, 0, "empty series file: expected the header of `battsim replay --series`");
    std::vector<std::string_view> fields;
    long bad = 0;
    text::split_fields(line, fields, bad);
    std::vector<std::string> names(fields.begin(), fields.end());
    auto col = [&](const char* n) -> long {
        for (size_t i = 0; i < names.size(); ++i) {
            if (names[i] == n) return static_cast<long>(i);
        }
        return -1;
    };
    const long c_time = col("time_s"), c_v = col("voltage_v"), c_model = col("model_voltage_v"),
               c_adapted = col("adapted_model_voltage_v"), c_i = col("current_a"), c_fi = col("filtered_current_a"),
               c_cap = col("capacity_ah"), c_r = col("resistance_ohm"), c_rem = col("remaining_time_s"),
               c_tot = col("total_time_s"), c_valid = col("sample_valid"), c_flying = col("flying");
    for (long c : {c_time, c_v, c_model, c_adapted, c_i, c_fi, c_cap, c_r, c_rem, c_tot, c_valid, c_flying}) {
        if (c < 0)
            throw InputError(path, 1, 0,
                             "not a replay series: expected the columns time_s, voltage_v, current_a, filtered_current_a, "
                             "model_voltage_v, adapted_model_voltage_v, capacity_ah, resistance_ohm, remaining_time_s, "
                             "total_time_s, flying, sample_valid");
    }
    std::vector<long> cells;
    for (int c = 1; c <= core::kMaxCells; ++c) {
        const long k = col(("cell" + std::to_string(c) + "_v").c_str());
        if (k < 0) break;
        cells.push_back(k);
    }
    ReplaySeries s;
    s.cell_v.resize(cells.size());
    while (lines.next(line)) {
        if (line.empty()) continue;
        if (!text::split_fields(line, fields, bad)) throw InputError(path, lines.line_number(), bad, "unterminated quote");
        if (fields.size() != names.size())
            throw InputError(path, lines.line_number(), 0,
                             "expected " + std::to_string(names.size()) + " fields, found " + std::to_string(fields.size()));
        auto get = [&](long c, bool blank_ok) -> double {
            double v = 0;
            const text::NumberStatus st = text::parse_number(fields[c], v);
            if (st == text::NumberStatus::Ok) return v;
            if (st == text::NumberStatus::Empty && blank_ok) return NAN;
            throw InputError(path, lines.line_number(), c + 1, text::number_error_message(st, fields[c]));
        };
        if (get(c_valid, false) == 0) continue;
        s.time_s.push_back(get(c_time, false));
        s.voltage_v.push_back(get(c_v, false));
        s.current_a.push_back(get(c_i, false));
        s.filtered_a.push_back(get(c_fi, false));
        s.model_v.push_back(get(c_model, true));  // empty before the initial state
        s.adapted_v.push_back(get(c_adapted, true));
        s.capacity_ah.push_back(get(c_cap, false));
        const double r = get(c_r, true);  // empty before a resistance is known
        s.resistance_ohm.push_back(r > 0 ? r : NAN);
        s.remaining_s.push_back(get(c_rem, true));
        s.total_s.push_back(get(c_tot, true));
        s.flying.push_back(get(c_flying, false) != 0);
        for (size_t c = 0; c < cells.size(); ++c) s.cell_v[c].push_back(get(cells[c], true));
    }
    if (s.time_s.empty()) throw InputError(path, 0, 0, "the series holds no valid samples");
    return s;
}

Series line_series(const std::string& title, const std::vector<double>& x, const std::vector<double>& y,
                   const std::string& color, bool y2, double width) {
    Series s;
    s.title = title;
    thin_envelope(x, y, 8000, s.x, s.y);
    s.color = color;
    s.y2 = y2;
    s.width = width;
    return s;
}

namespace {
// The range of a panel axis's data with a margin, so no line runs along the frame.
// `trim` > 0 leaves that share of the values out at each end, so that a few spikes do
// not squash what is typical.
std::pair<double, double> padded_range(std::vector<double> values, double trim = 0.0) {
    values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
    if (values.empty()) return {NAN, NAN};
    std::sort(values.begin(), values.end());
    const size_t cut = static_cast<size_t>(trim * static_cast<double>(values.size() - 1));
    const double lo = values[cut], hi = values[values.size() - 1 - cut];
    const double pad = hi > lo ? 0.06 * (hi - lo) : std::max(0.05 * std::fabs(hi), 0.01);
    return {lo - pad, hi + pad};
}
std::pair<double, double> padded_range(const Panel& p, bool y2, double trim = 0.0) {
    std::vector<double> values;
    for (const Series& s : p.series) {
        if (s.y2 == y2) values.insert(values.end(), s.y.begin(), s.y.end());
    }
    return padded_range(std::move(values), trim);
}
}  // namespace

void plot_replay(const ReplaySeries& s, const std::string& title, const std::string& path) {
    check_plot_path(path);
    if (s.time_s.empty()) throw std::invalid_argument("plot: the replay has no valid samples");
    std::vector<double> resistance_mohm(s.resistance_ohm);
    for (double& r : resistance_mohm) r *= 1000.0;  // milliohms read better than 0.0xx ohm
    std::vector<Panel> panels;
    Panel v;
    v.title = "Pack voltage: measured and model";
    v.ylabel = "voltage (V)";
    v.y2label = "current (A)";
    v.series.push_back(line_series("current (right axis)", s.time_s, s.current_a, "#b0b0b0", true));
    v.series.push_back(line_series("fixed model", s.time_s, s.model_v, "#d62728", false, 1.5));
    v.series.push_back(line_series("adapted model", s.time_s, s.adapted_v, "#1f77b4", false, 1.5));
    v.series.push_back(line_series("measured", s.time_s, s.voltage_v, "black", false, 0.8));  // on top
    panels.push_back(v);
    Panel e;
    e.title = "Capacity and resistance estimates";
    e.ylabel = "capacity (Ah)";
    e.y2label = "resistance (mΩ)";
    e.series.push_back(line_series("capacity", s.time_s, s.capacity_ah, "#2ca02c", false, 1.5));
    e.series.push_back(line_series("resistance (right axis)", s.time_s, resistance_mohm, "#9467bd", true, 1.5));
    panels.push_back(e);
    Panel t;
    t.title = "Flight time estimates (to the minimum voltage at the average power)";
    t.ylabel = "flight time (s)";
    t.series.push_back(line_series("remaining", s.time_s, s.remaining_s, "#ff7f0e", false, 1.5));
    // With the joint estimator the total is the verdict's own solve from take-off, not flown +
    // remaining (which follows the tracking filter): the two need not agree.
    // Labelled for both estimators: the reference's is flown + remaining, on the ground too.
    t.series.push_back(line_series("total flight time", s.time_s, s.total_s, "#8c564b", false, 1.5));
    panels.push_back(t);
    size_t deviations = SIZE_MAX;  // index of the cell-difference panel, if any
    if (!s.cell_v.empty()) {
        static const char* colors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                       "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#637939"};
        Panel c;
        c.title = "Cell voltages";
        c.ylabel = "voltage (V)";
        // Each cell against the mean of the cells: the pack's sag cancels, so a weak or
        // drifting cell shows, which it does not among noisy absolute voltages.
        Panel d;
        d.title = "Cell voltage minus the mean of the cells";
        d.ylabel = "difference (mV)";
        std::vector<double> mean(s.time_s.size(), 0.0);
        for (size_t i = 0; i < mean.size(); ++i) {
            for (const auto& cell : s.cell_v) mean[i] += cell[i];
            mean[i] /= static_cast<double>(s.cell_v.size());  // NaN if a cell is missing: a gap
        }
        for (size_t k = 0; k < s.cell_v.size(); ++k) {
            const std::string name = "cell " + std::to_string(k + 1);
            std::vector<double> diff_mv(mean.size());
            for (size_t i = 0; i < mean.size(); ++i) diff_mv[i] = (s.cell_v[k][i] - mean[i]) * 1000.0;
            c.series.push_back(line_series(name, s.time_s, s.cell_v[k], colors[k % 12]));
            d.series.push_back(line_series(name, s.time_s, diff_mv, colors[k % 12]));
        }
        panels.push_back(c);
        deviations = panels.size();
        panels.push_back(d);
    }
    // The flight window as the summary defines it: first to last flying sample (no landing
    // mark when the log ends in flight).
    std::vector<std::pair<double, std::string>> marks;
    const size_t n = std::min(s.flying.size(), s.time_s.size());
    size_t first = n, last = n;
    for (size_t k = 0; k < n; ++k) {
        if (!s.flying[k]) continue;
        if (first == n) first = k;
        last = k;
    }
    if (first < n) marks.push_back({s.time_s[first], "take-off"});
    if (last + 1 < n) marks.push_back({s.time_s[last], "landing"});
    for (size_t k = 0; k < panels.size(); ++k) {
        Panel& p = panels[k];
        p.xlabel = k + 1 == panels.size() ? "log time (s)" : "";  // one time axis label, at the bottom
        p.key_above = true;  // never over the data
        p.x_min = s.time_s.front();
        p.x_max = s.time_s.back();
        // The voltage axis follows the measurement: a model run into its pole (−230 V) would
        // flatten the pack's trace into a line.
        std::tie(p.y_min, p.y_max) =
            k == 0 ? padded_range(s.voltage_v) : padded_range(p, false, k == deviations ? 0.002 : 0.0);
        std::tie(p.y2_min, p.y2_max) = padded_range(p, true);
        p.vertical_marks = marks;
        if (k > 0) {
            for (auto& m : p.vertical_marks) m.second.clear();  // named once, in the top panel
        }
    }
    render(panels, title, path, 1400, 320);
}

// --- model against measurement --------------------------------------------------------------

ModelTraceSeries model_series(const fit::Trace& trace, const std::vector<float>& model_v, const std::string& role) {
    ModelTraceSeries s;
    s.label = trace.label;
    s.role = role;
    for (size_t k = 0; k < trace.points.size(); ++k) {
        const fit::TracePoint& p = trace.points[k];
        if (!p.valid) continue;
        s.time_s.push_back(p.time_s);
        s.measured_v.push_back(p.voltage_v);
        s.model_v.push_back(k < model_v.size() && std::isfinite(model_v[k]) ? model_v[k] : NAN);
    }
    return s;
}

size_t plot_model_fit(const std::vector<ModelTraceSeries>& logs, const std::string& title, const std::string& path) {
    check_plot_path(path);
    // At most 8 panels; up to half of them for test logs, which come after the fitted ones and
    // would otherwise never be shown.
    constexpr size_t kMaxPanels = 8;
    size_t tests = 0;
    for (const ModelTraceSeries& l : logs) tests += l.role == "test";
    const size_t fitted = logs.size() - tests;
    const size_t fitted_shown = std::min(fitted, kMaxPanels - std::min(tests, kMaxPanels / 2));
    const size_t tests_shown = std::min(tests, kMaxPanels - fitted_shown);
    std::vector<const ModelTraceSeries*> shown;
    size_t f = 0, t = 0;
    for (const ModelTraceSeries& l : logs) {
        if (l.role == "test" ? t++ < tests_shown : f++ < fitted_shown) shown.push_back(&l);
    }
    std::vector<Panel> panels;
    for (const ModelTraceSeries* shown_log : shown) {
        const ModelTraceSeries& l = *shown_log;
        std::vector<double> residual(l.time_s.size());
        double sum_abs = 0;
        size_t n = 0;
        for (size_t k = 0; k < residual.size(); ++k) {
            residual[k] = l.measured_v[k] - l.model_v[k];
            if (std::isfinite(residual[k])) {
                sum_abs += std::fabs(residual[k]);
                ++n;
            }
        }
        Panel p;
        char mae[64];
        std::snprintf(mae, sizeof mae, "MAE %.4f V", n ? sum_abs / n : 0.0);
        p.title = l.label + " (" + l.role + "): " + mae;
        p.xlabel = "time (s)";
        p.ylabel = "voltage (V)";
        p.y2label = "measured - model (V)";
        // The left axis follows the measurement, so a runaway model cannot squash it.
        double lo = INFINITY, hi = -INFINITY;
        for (double v : l.measured_v) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
        if (hi >= lo) {
            const double pad = 0.1 * std::max(hi - lo, 0.01);
            p.y_min = lo - pad;
            p.y_max = hi + pad;
        }
        p.series.push_back(line_series("model", l.time_s, l.model_v, "#d62728", false, 1.2));
        p.series.push_back(line_series("measured", l.time_s, l.measured_v, "black", false, 0.8));
        p.series.push_back(line_series("residual", l.time_s, residual, "#1f77b4", true));
        panels.push_back(p);
    }
    render(panels, title, path);
    return logs.size() - shown.size();
}

void plot_ocv_stitch(const fit::OcvStitch& s, const std::string& title, const std::string& path) {
    check_plot_path(path);
    Panel p;
    p.xlabel = "state of charge (of the config's capacity)";
    p.ylabel = "voltage per cell (V)";
    p.y2label = "samples per table point";
    p.key_above = true;
    bool fitted_titled = false, test_titled = false;
    for (const fit::OcvStitchFlight& f : s.flights) {
        std::string name;
        if (f.test && !test_titled) name = "test flights, sag added back";
        if (!f.test && !fitted_titled) name = "fitted flights, sag added back";
        (f.test ? test_titled : fitted_titled) = true;
        p.series.push_back(line_series(name, f.soc, f.ocv_v, f.test ? "#6baed6" : "#969696", false, 1.0));
    }
    std::vector<double> x;
    for (size_t j = 0; j < s.table_v.size(); ++j) x.push_back(static_cast<double>(j) / static_cast<double>(s.table_v.size() - 1));
    Series prior = line_series("config's curve", x, s.prior_v, "#d62728", false, 1.2);
    prior.style = "lines dashtype 2";
    p.series.push_back(prior);
    Series table = line_series("fitted table", x, s.table_v, "black", false, 1.6);
    table.style = "linespoints pointtype 7 pointsize 0.6";
    p.series.push_back(table);
    Series support = line_series("samples per point", x, s.support, "#2ca02c", true, 4.0);
    support.style = "impulses";
    p.series.push_back(support);
    // The left axis follows the table and the flights, not the config's curve's pole.
    double lo = INFINITY, hi = -INFINITY;
    for (double v : s.table_v) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    p.y_min = lo - 0.05;
    p.y_max = hi + 0.05;
    p.x_min = std::min(0.0, s.soc_min);
    p.x_max = std::max(1.0, s.soc_max);
    render({p}, title + ": OCV per cell against the state of charge, " + std::to_string(s.flights.size()) + " flights", path);
}

}  // namespace plot
}  // namespace host
}  // namespace battsim
