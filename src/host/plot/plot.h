// Plots for people, drawn by gnuplot through gnuplot-iostream: stacked panels of lines,
// written atomically to .png (pngcairo) or .svg. Data goes inline (datablocks) with fixed
// number formatting, so the same input gives the same file.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "core/monitor.h"
#include "core/sample.h"
#include "host/fit/ocv_stitch.h"
#include "host/fit/trace.h"

namespace battsim {
namespace host {
namespace plot {

struct Series {
    std::string title;
    std::vector<double> x, y;  // NaN in y breaks the line
    std::string style = "lines";  // gnuplot "with" clause: lines, points, impulses, boxes...
    std::string color;            // gnuplot colour name or #rrggbb; empty = automatic
    double width = 1.0;
    bool y2 = false;              // right-hand axis
    bool has_points() const;      // any finite (x, y): else only its legend entry is drawn
};

struct Panel {
    std::string title, xlabel, ylabel, y2label;
    std::vector<Series> series;
    std::vector<std::pair<double, std::string>> vertical_marks;  // x position, label
    double y_min = NAN, y_max = NAN;  // left axis range; NaN = automatic
    double y2_min = NAN, y2_max = NAN;  // right axis range; NaN = automatic
    double x_min = NAN, x_max = NAN;  // x axis range; NaN = automatic
    bool key_above = false;  // legend in a row above the frame (else boxed, inside top right)
    bool y2_used() const;  // a series on the right axis has points
    bool has_points() const;
};

// Throws std::invalid_argument unless `path` ends in .png or .svg.
void check_plot_path(const std::string& path);
// Whether an executable `gnuplot` is on PATH: checked with the options, before any work (a
// missing one had killed the run by SIGPIPE with exit 141, the outputs after the plot lost).
bool gnuplot_on_path();
// A line of `x`, `y` thinned to about 8000 points for drawing (spikes kept).
Series line_series(const std::string& title, const std::vector<double>& x, const std::vector<double>& y,
                   const std::string& color, bool y2 = false, double width = 1.0);

// Renders the panels one above the other. Throws std::runtime_error if gnuplot is missing
// or fails (with its message); the target is only replaced on success.
void render(const std::vector<Panel>& panels, const std::string& title, const std::string& path,
            int width_px = 1400, int panel_height_px = 360);

// --- replay -------------------------------------------------------------------------------
// What the replay plot shows, sample by sample. Fill it in memory with add() (e.g. from a
// replay observer) or read it back from a series CSV written by `battsim replay --series`.
struct ReplaySeries {
    std::vector<double> time_s, voltage_v, model_v, adapted_v, current_a, filtered_a;
    std::vector<double> capacity_ah, resistance_ohm, remaining_s, total_s;
    std::vector<bool> flying;
    std::vector<std::vector<double>> cell_v;  // [cell][sample]
    void add(const core::Sample& sample, const core::MonitorStatus& status);
};
ReplaySeries read_replay_series_csv(const std::string& path);  // throws InputError
void plot_replay(const ReplaySeries& s, const std::string& title, const std::string& path);

// --- model against measurement --------------------------------------------------------------
struct ModelTraceSeries {
    std::string label, role;
    std::vector<double> time_s, measured_v, model_v;
};
ModelTraceSeries model_series(const fit::Trace& trace, const std::vector<float>& model_v, const std::string& role);
// One panel per log, at most 8 (up to 4 of them test logs): measured and model voltage,
// residual on the right axis. Returns how many logs were left out.
size_t plot_model_fit(const std::vector<ModelTraceSeries>& logs, const std::string& title, const std::string& path);

// --- an OCV table stitched from flights (battsim fit-ocv) --------------------------------------
// One panel against the state of charge: the config's curve, the fitted table, and each
// flight's voltage with the fitted sag added back (fitted flights grey, test flights blue);
// the samples each table point holds on the right axis.
void plot_ocv_stitch(const fit::OcvStitch& s, const std::string& title, const std::string& path);

// Evenly thins (x, y) to about `max_points` keeping each bucket's minimum and maximum, so
// spikes survive the thinning.
void thin_envelope(const std::vector<double>& x, const std::vector<double>& y, size_t max_points,
                   std::vector<double>& xo, std::vector<double>& yo);

}  // namespace plot
}  // namespace host
}  // namespace battsim
