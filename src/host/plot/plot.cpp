#include "host/plot/plot.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <gnuplot-iostream.h>
#include <sstream>
#include <stdexcept>

#include "host/io/csv_reader.h"
#include "host/io/line_reader.h"

namespace battsim {
namespace host {
namespace plot {

namespace {

bool ends_with(const std::string& s, const char* suffix) {
    const std::string x(suffix);
    return s.size() >= x.size() && s.compare(s.size() - x.size(), x.size(), x) == 0;
}

// gnuplot single-quoted string: a quote is written twice.
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) {
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

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace

bool Panel::y2_used() const {
    for (const Series& s : series) {
        if (s.y2) return true;
    }
    return false;
}

void check_plot_path(const std::string& path) {
    if (!ends_with(path, ".png") && !ends_with(path, ".svg"))
        throw std::invalid_argument("plot file \"" + path + "\": expected a name ending in .png or .svg");
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
    const std::string temp = path + ".tmp-" + std::to_string(::getpid());
    // Fail early, with a clear message, if the directory cannot take the file.
    if (std::FILE* probe = std::fopen(temp.c_str(), "wb")) {
        std::fclose(probe);
    } else {
        throw std::runtime_error("plot: cannot write " + path + " (cannot create " + temp + ")");
    }
    char err_template[] = "/tmp/battsim-gnuplot-XXXXXX";
    const int fd = ::mkstemp(err_template);
    if (fd < 0) throw std::runtime_error("plot: cannot create a temporary file for gnuplot's messages");
    ::close(fd);
    const std::string err_path = err_template;

    std::string script;
    script.reserve(1 << 20);
    const int height = panel_height_px * static_cast<int>(panels.size()) + 40;
    script += svg ? "set terminal svg size " : "set terminal pngcairo size ";
    script += std::to_string(width_px) + "," + std::to_string(height) + " font 'DejaVu Sans,10' noenhanced\n";
    script += "set output " + quoted(temp) + "\n";
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
    script += "set multiplot layout " + std::to_string(panels.size()) + ",1 title " + quoted(title) + "\n";
    block = 0;
    for (const Panel& p : panels) {
        script += "unset arrow\nunset label\nset grid\nset key top right opaque box\n";
        script += "set title " + quoted(p.title) + "\n";
        script += "set xlabel " + quoted(p.xlabel) + "\nset ylabel " + quoted(p.ylabel) + "\n";
        if (p.y2_used()) {
            script += "set ytics nomirror\nset y2tics\nset y2label " + quoted(p.y2label) + "\n";
        } else {
            script += "set ytics mirror\nunset y2tics\nunset y2label\n";
        }
        if (std::isfinite(p.y_min) && std::isfinite(p.y_max) && p.y_max > p.y_min) {
            std::string lo, hi;
            append_number(lo, "%.7g", p.y_min);
            append_number(hi, "%.7g", p.y_max);
            script += "set yrange [" + lo + ":" + hi + "]\n";
        } else {
            script += "set autoscale y\n";
        }
        if (std::isfinite(p.x_min) && std::isfinite(p.x_max) && p.x_max > p.x_min) {
            std::string lo, hi;
            append_number(lo, "%.9g", p.x_min);
            append_number(hi, "%.9g", p.x_max);
            script += "set xrange [" + lo + ":" + hi + "]\n";
        } else {
            script += "set autoscale x\n";
        }
        for (const auto& m : p.vertical_marks) {
            std::string x;
            append_number(x, "%.9g", m.first);
            script += "set arrow from " + x + ", graph 0 to " + x + ", graph 1 nohead dt 2 lw 1.5 lc rgb 'black'\n";
            script += "set label " + quoted(m.second) + " at " + x + ", graph 0.06 rotate by 90 offset -1,0 front\n";
        }
        std::string cmd = "plot ";
        bool first = true;
        for (const Series& s : p.series) {
            if (!first) cmd += ", ";
            first = false;
            cmd += "$d" + std::to_string(block++) + " using 1:2 with " + s.style;
            if (s.style == "lines" || s.style == "linespoints" || s.style == "steps" || s.style == "impulses") {
                std::string w;
                append_number(w, "%.2g", s.width);
                cmd += " lw " + w;
            }
            if (!s.color.empty()) cmd += " lc rgb " + quoted(s.color);
            cmd += s.y2 ? " axes x1y2" : " axes x1y1";
            cmd += " title " + quoted(s.title);
        }
        script += cmd + "\n";
    }
    script += "unset multiplot\nunset output\n";

    try {
        Gnuplot gp("gnuplot > " + err_path + " 2>&1");
        gp << script;
        gp.flush();
    } catch (const std::exception& e) {
        std::remove(err_path.c_str());
        std::remove(temp.c_str());
        throw std::runtime_error(std::string("plot: cannot run gnuplot: ") + e.what());
    }
    // The Gnuplot object has closed the pipe and waited for gnuplot to exit.
    const std::string messages = read_all(err_path);
    std::remove(err_path.c_str());
    std::ifstream check(temp, std::ios::binary | std::ios::ate);
    const bool ok = check && check.tellg() > 0 && messages.find("rror") == std::string::npos;
    check.close();
    if (!ok) {
        std::remove(temp.c_str());
        throw std::runtime_error("plot: gnuplot failed to write " + path + (messages.empty() ? "" : ": " + messages));
    }
    if (std::rename(temp.c_str(), path.c_str()) != 0) {
        std::remove(temp.c_str());
        throw std::runtime_error("plot: cannot move the plot into place at " + path);
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
               c_tot = col("total_time_s"), c_valid = col("sample_valid");
    for (long c : {c_time, c_v, c_model, c_adapted, c_i, c_fi, c_cap, c_r, c_rem, c_tot, c_valid}) {
        if (c < 0)
            throw InputError(path, 1, 0,
                             "not a replay series: expected the columns time_s, voltage_v, current_a, filtered_current_a, "
                             "model_voltage_v, adapted_model_voltage_v, capacity_ah, resistance_ohm, remaining_time_s, "
                             "total_time_s, sample_valid");
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
        s.model_v.push_back(get(c_model, false));
        s.adapted_v.push_back(get(c_adapted, false));
        s.capacity_ah.push_back(get(c_cap, false));
        const double r = get(c_r, false);
        s.resistance_ohm.push_back(r > 0 ? r : NAN);
        s.remaining_s.push_back(get(c_rem, true));
        s.total_s.push_back(get(c_tot, true));
        for (size_t c = 0; c < cells.size(); ++c) s.cell_v[c].push_back(get(cells[c], true));
    }
    if (s.time_s.empty()) throw InputError(path, 0, 0, "the series holds no valid samples");
    return s;
}

namespace {
Series line_series(const std::string& title, const std::vector<double>& x, const std::vector<double>& y,
                   const std::string& color, bool y2 = false, double width = 1.0) {
    Series s;
    s.title = title;
    thin_envelope(x, y, 8000, s.x, s.y);
    s.color = color;
    s.y2 = y2;
    s.width = width;
    return s;
}
}  // namespace

void plot_replay(const ReplaySeries& s, const std::string& title, const std::string& path) {
    check_plot_path(path);
    if (s.time_s.empty()) throw std::invalid_argument("plot: the replay has no valid samples");
    std::vector<Panel> panels;
    Panel v;
    v.title = "Pack voltage: measured and model";
    v.xlabel = "time (s)";
    v.ylabel = "voltage (V)";
    v.y2label = "current (A)";
    v.series.push_back(line_series("current", s.time_s, s.current_a, "#c8c8c8", true));
    v.series.push_back(line_series("fixed model", s.time_s, s.model_v, "#d62728", false, 1.5));
    v.series.push_back(line_series("adapted model", s.time_s, s.adapted_v, "#1f77b4", false, 1.5));
    v.series.push_back(line_series("measured", s.time_s, s.voltage_v, "black", false, 0.8));  // on top
    panels.push_back(v);
    Panel e;
    e.title = "Capacity and resistance estimates";
    e.xlabel = "time (s)";
    e.ylabel = "capacity (Ah)";
    e.y2label = "resistance (ohm)";
    e.series.push_back(line_series("capacity estimate", s.time_s, s.capacity_ah, "#2ca02c", false, 1.5));
    e.series.push_back(line_series("resistance estimate", s.time_s, s.resistance_ohm, "#9467bd", true, 1.5));
    panels.push_back(e);
    Panel t;
    t.title = "Flight time";
    t.xlabel = "time (s)";
    t.ylabel = "time (s)";
    t.series.push_back(line_series("remaining", s.time_s, s.remaining_s, "#ff7f0e", false, 1.5));
    t.series.push_back(line_series("total", s.time_s, s.total_s, "#8c564b", false, 1.5));
    panels.push_back(t);
    if (!s.cell_v.empty()) {
        static const char* colors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                       "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#637939"};
        Panel c;
        c.title = "Cell voltages";
        c.xlabel = "time (s)";
        c.ylabel = "voltage (V)";
        for (size_t k = 0; k < s.cell_v.size(); ++k)
            c.series.push_back(line_series("cell " + std::to_string(k + 1), s.time_s, s.cell_v[k], colors[k % 12]));
        panels.push_back(c);
    }
    render(panels, title, path);
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

void plot_model_fit(const std::vector<ModelTraceSeries>& logs, const std::string& title, const std::string& path) {
    check_plot_path(path);
    std::vector<Panel> panels;
    for (size_t i = 0; i < logs.size() && i < 8; ++i) {
        const ModelTraceSeries& l = logs[i];
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
}

}  // namespace plot
}  // namespace host
}  // namespace battsim
