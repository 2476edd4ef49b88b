// Plots: files appear atomically as PNG/SVG, identical for identical input, and the replay
// plot reads the series CSV that `battsim replay --series` writes.
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "host/plot/plot.h"
#include "host/replay.h"
#include "test_files.h"

using namespace battsim::host;

namespace {
std::string temp(const std::string& name) {
    static const std::string dir = testsupport::scratch_dir("plot");
    return dir + "/" + name;
}
plot::Panel sine_panel() {
    plot::Panel p;
    p.title = "a sine with a gap";
    p.xlabel = "x";
    p.ylabel = "y";
    p.y2label = "y2";
    plot::Series s, t;
    s.title = "sin";
    t.title = "cos on y2";
    t.y2 = true;
    for (int i = 0; i < 500; ++i) {
        s.x.push_back(i * 0.02);
        s.y.push_back(i > 200 && i < 220 ? NAN : std::sin(i * 0.02));
        t.x.push_back(i * 0.02);
        t.y.push_back(std::cos(i * 0.02));
    }
    p.series = {s, t};
    p.vertical_marks.push_back({5.0, "it's a mark"});  // a quote in a label must not break the script
    return p;
}
}  // namespace

TEST_CASE("render writes PNG and SVG, the same bytes for the same input", "[plot]") {
    const std::string png = temp("a.png"), svg = temp("a.svg"), png2 = temp("b.png");
    plot::render({sine_panel(), sine_panel()}, "title with 'quotes'", png);
    plot::render({sine_panel()}, "t", svg);
    plot::render({sine_panel(), sine_panel()}, "title with 'quotes'", png2);
    const std::string a = testsupport::read_file(png), b = testsupport::read_file(png2), c = testsupport::read_file(svg);
    REQUIRE(a.size() > 1000);
    CHECK(a.compare(1, 3, "PNG") == 0);
    CHECK(a == b);
    CHECK(c.find("<svg") != std::string::npos);
    // No temporary left behind.
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(png).parent_path()))
        CHECK(e.path().string().rfind(png + ".tmp", 0) != 0);
    for (const std::string& f : {png, svg, png2}) std::remove(f.c_str());
    CHECK_THROWS_AS(plot::render({sine_panel()}, "t", temp("a.pdf")), std::invalid_argument);
    CHECK_THROWS_AS(plot::render({}, "t", temp("c.png")), std::invalid_argument);
    CHECK_THROWS_AS(plot::render({sine_panel()}, "t", "/nonexistent-dir/x.png"), std::runtime_error);
}

TEST_CASE("render keeps a series without values as a legend entry, even a whole empty panel", "[plot]") {
    plot::Panel empty;
    empty.title = "nothing yet";
    plot::Series none, gaps;
    none.title = "never estimated";
    gaps.title = "only gaps";
    gaps.y2 = true;
    gaps.x = {0.0, 1.0};
    gaps.y = {NAN, NAN};
    empty.series = {none, gaps};
    plot::Panel mixed = sine_panel();
    mixed.series.push_back(none);
    const std::string svg = temp("empty.svg");
    plot::render({empty, mixed}, "t", svg);  // gnuplot stops at an empty series if it is plotted
    const std::string text = testsupport::read_file(svg);
    CHECK(text.find(">never estimated (no values)<") != std::string::npos);
    CHECK(text.find(">only gaps (no values)<") != std::string::npos);
    CHECK(text.find(">sin<") != std::string::npos);
}

TEST_CASE("Envelope thinning keeps the extremes", "[plot]") {
    std::vector<double> x, y, xo, yo;
    for (int i = 0; i < 100000; ++i) {
        x.push_back(i);
        y.push_back(i == 54321 ? 10.0 : (i % 2 ? 1.0 : -1.0));
    }
    plot::thin_envelope(x, y, 1000, xo, yo);
    CHECK(xo.size() <= 1000);
    CHECK(*std::max_element(yo.begin(), yo.end()) == 10.0);
    CHECK(*std::min_element(yo.begin(), yo.end()) == -1.0);
    for (size_t i = 1; i < xo.size(); ++i) CHECK(xo[i] >= xo[i - 1]);
}

TEST_CASE("plot_replay from memory and from the replay's series CSV", "[plot][data]") {
    const std::string log = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/30.csv";
    const std::string series = temp("series.csv"), png1 = temp("r1.png"), png2 = temp("r2.png");
    ReplayOptions ro;
    ro.config = load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json");
    ro.reader.shunt = ro.config.monitor.shunt;
    ro.series_path = series;
    plot::ReplaySeries memory;
    replay_log(log, ro, [&](const battsim::core::Sample& s, const battsim::core::MonitorStatus& st) { memory.add(s, st); });
    const plot::ReplaySeries from_csv = plot::read_replay_series_csv(series);
    CHECK(from_csv.time_s.size() == memory.time_s.size());
    CHECK(from_csv.cell_v.size() == 4);
    CHECK(memory.cell_v.size() == 4);
    CHECK(from_csv.voltage_v[1000] == Approx(memory.voltage_v[1000]).margin(1e-4));
    plot::plot_replay(memory, "flight 30", png1);
    plot::plot_replay(from_csv, "flight 30", png2);
    CHECK(testsupport::read_file(png1).size() > 10000);
    CHECK(testsupport::read_file(png2).size() > 10000);
    for (const std::string& f : {series, png1, png2}) std::remove(f.c_str());
    CHECK_THROWS_AS(plot::read_replay_series_csv(log), InputError);  // a flight log is not a series
}

namespace {
// A replay series of n samples at 0.1 s: 16 V measured, the fixed model running off to
// -230 V (a model past its pole), 1.5 Ah, 20 mΩ.
plot::ReplaySeries runaway_series(size_t n) {
    plot::ReplaySeries s;
    for (size_t k = 0; k < n; ++k) {
        s.time_s.push_back(0.1 * k);
        s.voltage_v.push_back(16.0 - 0.001 * k);
        s.current_a.push_back(20.0);
        s.filtered_a.push_back(20.0);
        s.model_v.push_back(16.0 - 0.25 * k);
        s.adapted_v.push_back(16.0);
        s.capacity_ah.push_back(1.5);
        s.resistance_ohm.push_back(0.02);
        s.remaining_s.push_back(100.0);
        s.total_s.push_back(200.0);
        s.flying.push_back(true);
    }
    return s;
}
}  // namespace

TEST_CASE("plot_replay: the voltage axis follows the measurement, one sample is drawn as missing", "[plot]") {
    const std::string svg = temp("runaway.svg");
    // A model run into its pole had set the voltage axis to -240..+20 V, the pack a flat line.
    plot::plot_replay(runaway_series(1000), "runaway", svg);
    const std::string text = testsupport::read_file(svg);
    // gnuplot writes tick labels as "> 15.8<". No negative tick anywhere (this series has
    // nothing below 0 but the runaway model), and ticks in the pack's own 15-16 V.
    CHECK_FALSE(std::regex_search(text, std::regex(">\\s*-[0-9]")));
    CHECK(std::regex_search(text, std::regex(">\\s*15\\.[0-9]+<")));
    // One sample draws no line: its legend says so, and every panel has a time axis around it.
    plot::plot_replay(runaway_series(1), "one", svg);
    const std::string one = testsupport::read_file(svg);
    CHECK(one.find(">measured (no values)<") != std::string::npos);
    CHECK(one.find(">capacity (no values)<") != std::string::npos);
    std::remove(svg.c_str());
}

TEST_CASE("render: a title that is not UTF-8 still makes valid SVG; a device takes the plot", "[plot]") {
    const std::string svg = temp("latin1.svg");
    plot::render({sine_panel()}, "flight \xe9t\xe9.csv", svg);  // a Latin-1 log name
    const std::string text = testsupport::read_file(svg);
    CHECK(text.find("flight \xef\xbf\xbdt\xef\xbf\xbd.csv") != std::string::npos);
    CHECK(text.find("\xe9t") == std::string::npos);
    std::remove(svg.c_str());
    // A link to /dev/null is written straight; it has no size to check ("gnuplot failed").
    const std::string link = temp("null.png");
    std::remove(link.c_str());
    std::filesystem::create_symlink("/dev/null", link);
    CHECK_NOTHROW(plot::render({sine_panel()}, "t", link));
    CHECK(std::filesystem::is_symlink(link));  // not renamed over by a regular file
    CHECK(std::filesystem::read_symlink(link) == "/dev/null");
    std::remove(link.c_str());
}

TEST_CASE("plot_model_fit: 8 panels at most, the test logs among them, the rest counted", "[plot]") {
    std::vector<plot::ModelTraceSeries> logs;
    for (int k = 0; k < 13; ++k) {
        plot::ModelTraceSeries l;
        l.label = (k < 10 ? "fitted" : "held") + std::to_string(k);
        l.role = k < 10 ? "fit" : "test";
        for (int i = 0; i < 50; ++i) {
            l.time_s.push_back(i);
            l.measured_v.push_back(16.0 - 0.01 * i);
            l.model_v.push_back(16.0 - 0.011 * i);
        }
        logs.push_back(l);
    }
    const std::string svg = temp("fit13.svg");
    // Before, the first 8 fitted logs filled the plot and the test logs, added last, never showed.
    CHECK(plot::plot_model_fit(logs, "t", svg) == 5);
    const std::string text = testsupport::read_file(svg);
    for (const char* shown : {"fitted0 (fit)", "fitted4 (fit)", "held10 (test)", "held12 (test)"})
        CHECK(text.find(shown) != std::string::npos);
    CHECK(text.find("fitted5 (fit)") == std::string::npos);
    logs.resize(3);
    CHECK(plot::plot_model_fit(logs, "t", svg) == 0);
    std::remove(svg.c_str());
}
