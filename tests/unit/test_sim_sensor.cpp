// The simulator's sensor layer: the logger's formats and quantisation by hand, the
// reference hardware's timing, and every sensor fault visible in the log.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/sensor.h"
#include "host/config_json.h"
#include "host/io/sample_reader.h"
#include "host/sim/scenario.h"
#include "host/sim/sensor.h"
#include "host/sim/simulate.h"
#include "sim_scenarios.h"
#include "test_files.h"

using namespace battsim::host;
using namespace battsim::host::sim;
using nlohmann::json;

namespace {

Scenario scenario(const std::string& extra_json = "{}") {
    return simtest::code_scenario(R"({
      "schema": "battsim.scenario", "version": 1, "name": "sensor", "seed": 11,
      "monitor_config": "embedded",
      "pack": {"cells": 4, "capacity_ah": 1.55},
      "profile": {"kind": "racing", "idle_before_s": 30, "armed_s": 2, "flight_s": 90, "idle_after_s": 10,
                  "mean_power_w": 360}
    })", extra_json);
}

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> f;
    std::string cur;
    for (char c : line) {
        if (c == ',') {
            f.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    f.push_back(cur);
    return f;
}

std::vector<std::vector<std::string>> rows_of(const std::string& text, bool header) {
    std::vector<std::vector<std::string>> rows;
    std::stringstream in(text);
    std::string line;
    if (header) std::getline(in, line);
    while (std::getline(in, line)) rows.push_back(split(line));
    return rows;
}

// Number of decimals written in a field.
int decimals(const std::string& f) {
    const size_t dot = f.find('.');
    return dot == std::string::npos ? 0 : static_cast<int>(f.size() - dot - 1);
}

struct RawRow {
    double t_ms, bus, cell[4], current_ma, shunt_mv;
};
std::vector<RawRow> parse_raw(const std::string& text) {
    std::vector<RawRow> out;
    for (const auto& f : rows_of(text, false)) {
        RawRow r;
        r.t_ms = std::stod(f[0]);
        r.bus = std::stod(f[1]);
        for (int c = 0; c < 4; ++c) r.cell[c] = std::stod(f[2 + c]);
        r.current_ma = std::stod(f[6]);
        r.shunt_mv = std::stod(f[7]);
        out.push_back(r);
    }
    return out;
}

}  // namespace

TEST_CASE("Log rows by hand: raw and headered formats from ADC counts", "[sim][sensor]") {
    const battsim::core::ShuntCalibration cal;  // the reference hardware's 200 A / 75 mV calibration
    LogRecord r;
    r.time_ms = 12345;
    r.bus_count = 13456;                                     // × 1.25 mV = 16.820 V
    r.tap_count[0] = 525, r.tap_count[1] = 1050, r.tap_count[2] = 1575;  // × 8 mV = 4.2, 8.4, 12.6 V
    r.shunt_count = 1000;                                    // × 2.5 µV = 2.5 mV
    r.temperature_dc = 215;
    // 2.5 mV / 3.7834625 mV per 10 A = 6607.71 mA, minus the 982.82 mA offset.
    std::string raw;
    format_record(SimLogFormat::Raw, 4, cal, r, raw);
    CHECK(raw == "12345,16.82,4.20,4.20,4.20,4.22,5624.89,2.50,\n");
    std::string csv;
    format_record(SimLogFormat::Csv, 4, cal, r, csv);
    CHECK(csv == "12.345,16.82000,5.625,4.20000,4.20000,4.20000,4.22000,21.5\n");
    CHECK(format_header(SimLogFormat::Csv, 3) == "time_s,voltage_v,current_a,cell1_v,cell2_v,cell3_v,temperature_c\n");
    CHECK(format_header(SimLogFormat::Raw, 4).empty());
    // A radio log: 16.820 V and 5.625 A in the battery sensor's 0.1 V and 0.1 A steps.
    std::string radio;
    format_record(SimLogFormat::Radio, 4, cal, r, radio);
    CHECK(radio == "2026-01-01,00:00:12.345,16.8,5.6\n");
    CHECK(format_header(SimLogFormat::Radio, 4) == "Date,Time,RxBt(V),Curr(A)\n");
    LogRecord late = r;
    late.time_ms = 86400000 + 3723004;  // the second day, 01:02:03.004
    radio.clear();
    format_record(SimLogFormat::Radio, 4, cal, late, radio);
    CHECK(radio == "2026-01-02,01:02:03.004,16.8,5.6\n");

    // Half a 0.01 mV step rounds away from zero; the current follows the 2.5 µV count.
    r.shunt_count = -3;  // −7.5 µV
    r.bus_count = 13452; // 16.815 V → 16.82
    raw.clear();
    format_record(SimLogFormat::Raw, 4, cal, r, raw);
    CHECK(raw == "12345,16.82,4.20,4.20,4.20,4.22,-1002.64,-0.01,\n");
    CHECK(firmware_current_ma(0, cal) == Approx(-982.8158579));
}

TEST_CASE("Raw log: the dissertation logger's layout, resolution and timing", "[sim][sensor]") {
    const SimulationResult r = simulate(scenario());
    REQUIRE(r.format == SimLogFormat::Raw);
    const auto rows = rows_of(r.log_text, false);
    REQUIRE(rows.size() > 1500);
    const battsim::core::ShuntCalibration cal;
    for (const auto& f : rows) {
        REQUIRE(f.size() == 9);  // 8 values and the empty field after the trailing comma
        CHECK(f[8].empty());
        CHECK(decimals(f[0]) == 0);
        for (int k = 1; k < 8; ++k) CHECK(decimals(f[static_cast<size_t>(k)]) == 2);
        // The current is the firmware's float formula applied to a 2.5 µV shunt count
        // that the logged 0.01 mV shunt value is the rounding of.
        const double shunt = std::stod(f[7]);
        bool found = false;
        for (int count = static_cast<int>(std::floor((shunt - 0.005) / 0.0025)) - 1;
             count <= static_cast<int>(std::ceil((shunt + 0.005) / 0.0025)) + 1; ++count) {
            const double ma = firmware_current_ma(count, cal);
            if (std::fabs(ma - std::stod(f[6])) <= 0.005 + 1e-6 && std::fabs(count * 0.0025 - shunt) <= 0.005 + 1e-9)
                found = true;
        }
        CHECK(found);
    }
    const std::vector<RawRow> raw = parse_raw(r.log_text);
    std::vector<double> dt;
    for (size_t i = 1; i < raw.size(); ++i) dt.push_back(raw[i].t_ms - raw[i - 1].t_ms);
    for (const RawRow& x : raw) {
        // The logger's cells are differences of taps and the bus: they sum to the bus.
        const double sum = x.cell[0] + x.cell[1] + x.cell[2] + x.cell[3];
        CHECK(std::fabs(sum - x.bus) <= 0.025);
    }
    std::vector<double> sorted = dt;
    std::sort(sorted.begin(), sorted.end());
    CHECK(sorted[sorted.size() / 2] >= 66.0);
    CHECK(sorted[sorted.size() / 2] <= 68.0);
    CHECK(sorted.front() > 0.0);  // time never stands still or runs back
    CHECK(sorted.back() <= 360.0);
    const long gaps = std::count_if(dt.begin(), dt.end(), [](double d) { return d >= 100.0; });
    CHECK(gaps >= 1);                        // SD-card stalls happen
    CHECK(gaps < static_cast<long>(dt.size() / 50));  // but rarely
    CHECK(raw.front().t_ms >= 600.0);        // the ESP boots before the first row
    CHECK(raw.front().t_ms < 700.0);
}

TEST_CASE("Headered log for other cell counts reads back through the standard reader", "[sim][sensor]") {
    const SimulationResult r = simulate(scenario(R"({"pack": {"cells": 6}, "profile": {"mean_power_w": 540}})"));
    REQUIRE(r.format == SimLogFormat::Csv);
    const auto rows = rows_of(r.log_text, true);
    REQUIRE(rows.size() > 1500);
    for (const auto& f : rows) {
        REQUIRE(f.size() == 10);
        // 1.25 mV bus steps and 8 mV tap steps, written exactly.
        const long bus_10uv = std::lround(std::stod(f[1]) * 1e5);
        CHECK(bus_10uv % 125 == 0);
        for (int c = 3; c < 8; ++c) CHECK(std::lround(std::stod(f[static_cast<size_t>(c)]) * 1e5) % 800 == 0);
        CHECK(decimals(f[9]) == 1);
    }
    const testsupport::TempDir dir("sensor");
    const std::string path = dir.write("six.csv", r.log_text);
    ReaderOptions ro;
    std::unique_ptr<SampleReader> reader = open_reader(path, ro);
    battsim::core::Sample s;
    size_t n = 0;
    while (reader->next(s)) {
        REQUIRE(s.cell_count == 6);
        REQUIRE(s.has_temperature);
        float sum = 0;
        for (int c = 0; c < 6; ++c) sum += s.cell_voltage_v[c];
        CHECK(std::fabs(sum - s.voltage_v) < 1e-3f);
        ++n;
    }
    CHECK(n == rows.size());
    CHECK(reader->info().format == LogFormat::Csv);
}

TEST_CASE("Radio log: one row per log interval, 0.1 V and 0.1 A steps, read back as a radio log", "[sim][sensor]") {
    const SimulationResult full = simulate(scenario(R"({"log": {"format": "csv"}})"));
    const SimulationResult r = simulate(scenario(R"({"log": {"format": "edgetx", "interval_s": 0.5}})"));
    REQUIRE(r.format == SimLogFormat::Radio);
    CHECK(truth_to_json(r)["scenario"]["log"] == json({{"format", "edgetx"}, {"interval_s", 0.5}}));
    const auto rows = rows_of(r.log_text, true);
    const auto full_rows = rows_of(full.log_text, true);
    // The first reading at or after each 0.5 s mark of the logger's span.
    const double span_s = std::stod(full_rows.back()[0]) - std::stod(full_rows.front()[0]);
    CHECK(static_cast<double>(rows.size()) == Approx(span_s / 0.5).margin(1.5));
    CHECK(truth_to_json(r)["log"]["rows"] == rows.size());
    for (const auto& f : rows) {
        REQUIRE(f.size() == 4);
        CHECK(decimals(f[2]) == 1);
        CHECK(decimals(f[3]) == 1);
    }
    const testsupport::TempDir dir("sensor");
    const std::string path = dir.write("radio.csv", r.log_text);
    std::unique_ptr<SampleReader> reader = open_reader(path, ReaderOptions());
    battsim::core::Sample s;
    std::vector<uint64_t> times;
    while (reader->next(s)) {
        CHECK(s.cell_count == 0);
        times.push_back(s.time_us);
    }
    REQUIRE(times.size() == rows.size());
    for (size_t i = 1; i < times.size(); ++i) {
        // Each row falls in the next half second: at most one reading interval late.
        CHECK(times[i] / 500000 == times[i - 1] / 500000 + 1);
    }
    CHECK(reader->info().notes.size() == 1);  // the "columns read as" note, nothing skipped
    // The truth is the same flight whatever the log's format.
    CHECK(r.truth.total_flight_time_s == full.truth.total_flight_time_s);
}

TEST_CASE("Autopilot logs: ArduPilot DataFlash and PX4 ULog read back as the CSV log's rows", "[sim][sensor]") {
    // Each binary log holds the CSV log's readings, thinned to the autopilot's logging
    // interval: every sample read back must be a CSV row at the same time with the same
    // values (the cells in whole mV in DataFlash's BCL). In DataFlash each BAT row's cells
    // come in the BCL row written after it, as ArduPilot writes them: read with the
    // previous update's cells, the cells would miss the pack voltage by up to a current step.
    const SimulationResult full = simulate(scenario(R"({"log": {"format": "csv"}})"));
    const testsupport::TempDir dir("autopilot");
    std::unique_ptr<SampleReader> csv = open_reader(dir.write("full.csv", full.log_text), ReaderOptions());
    std::vector<battsim::core::Sample> rows;
    battsim::core::Sample s;
    while (csv->next(s)) rows.push_back(s);
    for (const auto& [format, kind, extension, interval_us, cell_tolerance_v] :
         {std::make_tuple("dataflash", SimLogFormat::DataFlash, ".bin", 100000, 0.0005),
          std::make_tuple("ulog", SimLogFormat::ULog, ".ulg", 200000, 0.0)}) {
        INFO(format);
        const SimulationResult r = simulate(scenario(std::string(R"({"log": {"format": ")") + format + "\"}}"));
        REQUIRE(r.format == kind);
        CHECK(truth_to_json(r)["log"]["format"] == format);
        CHECK(std::string(sim_log_extension(kind)) == extension);
        std::unique_ptr<SampleReader> reader = open_reader(dir.write(std::string("log") + extension, r.log_text), ReaderOptions());
        CHECK(reader->info().format == (kind == SimLogFormat::DataFlash ? LogFormat::DataflashBinary : LogFormat::Ulog));
        size_t k = 0, n = 0;
        uint64_t last_us = 0;
        while (reader->next(s)) {
            while (k < rows.size() && rows[k].time_us < s.time_us) ++k;
            REQUIRE(k < rows.size());
            REQUIRE(rows[k].time_us == s.time_us);
            CHECK(s.voltage_v == rows[k].voltage_v);
            CHECK(s.current_a == rows[k].current_a);
            // DataFlash's centi-degrees are truncated, as ArduPilot's cast does: 19.9 reads 19.89.
            CHECK(s.temperature_c == Approx(rows[k].temperature_c).margin(kind == SimLogFormat::DataFlash ? 0.0101 : 0.0));
            REQUIRE(s.cell_count == 4);
            for (int c = 0; c < 4; ++c) CHECK(s.cell_voltage_v[c] == Approx(rows[k].cell_voltage_v[c]).margin(cell_tolerance_v + 1e-6));
            // The first reading at or after each interval's mark: one an interval, none
            // where the logger stalled (up to 0.35 s).
            if (n > 0) {
                CHECK(s.time_us / interval_us > last_us / interval_us);
                CHECK(s.time_us - last_us <= 450000u);
            }
            last_us = s.time_us;
            ++n;
        }
        CHECK(static_cast<long>(n) == r.truth.rows);
        CHECK(reader->info().notes.empty());
        CHECK(r.truth.total_flight_time_s == full.truth.total_flight_time_s);
    }
}

TEST_CASE("Sensor faults are visible in the log and leave the truth alone", "[sim][sensor]") {
    const SimulationResult clean = simulate(scenario());
    const std::vector<RawRow> base = parse_raw(clean.log_text);
    const auto mean_current = [](const std::vector<RawRow>& rows, double from_ms, double to_ms) {
        double s = 0;
        int n = 0;
        for (const RawRow& r : rows) {
            if (r.t_ms >= from_ms && r.t_ms < to_ms) {
                s += r.current_ma / 1000.0;
                ++n;
            }
        }
        return s / n;
    };

    SECTION("current offset: the ground idle reads 1.5 A more") {
        const SimulationResult f = simulate(scenario(R"({"sensor": {"faults": {"current_offset_a": 1.5}}})"));
        const std::vector<RawRow> rows = parse_raw(f.log_text);
        CHECK(mean_current(rows, 1000, 29000) - mean_current(base, 1000, 29000) == Approx(1.5).margin(0.02));
        CHECK(f.truth.sensor_faulty);
        CHECK(f.truth.total_flight_time_s == clean.truth.total_flight_time_s);
    }
    SECTION("current gain error: the flight reads 8 % more") {
        const SimulationResult f = simulate(scenario(R"({"sensor": {"faults": {"current_gain_error": 0.08}}})"));
        const std::vector<RawRow> rows = parse_raw(f.log_text);
        // Both logs include the shunt calibration's offset, which the gain error leaves alone.
        CHECK(mean_current(rows, 33000, 120000) / mean_current(base, 33000, 120000) == Approx(1.08).margin(0.005));
    }
    SECTION("loose balance lead: tap 2 drops to about 0 V now and then") {
        const SimulationResult f = simulate(scenario(R"({"sensor": {"faults": {"loose_tap": 2}}})"));
        const std::vector<RawRow> rows = parse_raw(f.log_text);
        long open = 0;
        for (const RawRow& r : rows) {
            // tap 2 ≈ 0: cell2 = 0 − tap1 < 0 and cell3 = tap3 − 0 ≈ three cells.
            if (r.cell[1] < -2.0 && r.cell[2] > 9.0) ++open;
        }
        long base_open = 0;
        for (const RawRow& r : base) base_open += r.cell[1] < 2.0 || r.cell[2] > 5.0;
        CHECK(open > 3);
        CHECK(base_open == 0);
        CHECK(f.truth.sensor_stats.loose_episodes > 0);
        CHECK(f.truth.sensor_stats.loose_open_s > 0.2);
        CHECK(truth_to_json(f)["series"] == truth_to_json(clean)["series"]);
    }
    SECTION("missed samples: rows lost singly and in dropouts") {
        const SimulationResult f = simulate(
            scenario(R"({"sensor": {"faults": {"missed_probability": 0.05, "missed_burst_rate_per_min": 3,
                                                "missed_burst_min_s": 1, "missed_burst_max_s": 2}}})"));
        const std::vector<RawRow> rows = parse_raw(f.log_text);
        CHECK(rows.size() < base.size() * 0.97);
        CHECK(f.truth.sensor_stats.dropped > 0);
        CHECK(static_cast<long>(rows.size()) == f.truth.rows);
        double max_gap = 0;
        for (size_t i = 1; i < rows.size(); ++i) max_gap = std::max(max_gap, rows[i].t_ms - rows[i - 1].t_ms);
        CHECK(max_gap > 900.0);
    }
}

namespace {
// Flies the test scenario with and without one wiring key (a lead resistance, ohm) and checks
// that the bus and the one cell that carries the lead read the flight's mean I·R low, the
// other cells not; wiring, not a fault: the truth is the same, and the key round-trips
// (absent at 0).
void check_lead(const char* key, double ohm, int carrying_cell) {
    const SimulationResult clean = simulate(scenario());
    const SimulationResult wired =
        simulate(scenario(nlohmann::json{{"sensor", {{key, ohm}}}}.dump()));
    const std::vector<RawRow> a = parse_raw(clean.log_text);
    const std::vector<RawRow> b = parse_raw(wired.log_text);
    REQUIRE(a.size() == b.size());
    double current = 0, bus = 0, cell[4] = {};
    int n = 0;
    for (size_t k = 0; k < a.size(); ++k) {
        if (a[k].t_ms < 35000 || a[k].t_ms > 120000) continue;  // in flight
        current += a[k].current_ma / 1000.0;
        bus += a[k].bus - b[k].bus;
        for (int c = 0; c < 4; ++c) cell[c] += a[k].cell[c] - b[k].cell[c];
        ++n;
    }
    REQUIRE(n > 1000);
    const double drop_v = ohm * current / n;  // the flight's mean I·R (the shunt's offset is a few mA)
    CHECK(drop_v > 15.0 * ohm);
    CHECK(bus / n == Approx(drop_v).epsilon(0.03));
    for (int c = 0; c < 4; ++c) {
        if (c == carrying_cell) CHECK(cell[c] / n == Approx(drop_v).epsilon(0.05));
        else CHECK(std::fabs(cell[c] / n) < 0.1 * drop_v);
    }
    CHECK_FALSE(wired.truth.sensor_faulty);
    CHECK(wired.truth.total_flight_time_s == clean.truth.total_flight_time_s);
    CHECK(truth_to_json(wired)["scenario"]["sensor"][key] == ohm);
    CHECK_FALSE(truth_to_json(clean)["scenario"]["sensor"].contains(key));
}
}  // namespace

TEST_CASE("A positive lead before the bus input: the bus and the last cell read I·R low, the taps not",
          "[sim][sensor]") {
    // The bus voltage is taken past the positive main lead; the taps are not. Cell 4 is
    // bus − tap 3, so it alone of the cells carries the lead, as on the reference logger.
    check_lead("bus_lead_ohm", 0.004, 3);
}

TEST_CASE("A ground path carrying the main current: the bus and cell 1 read I·R low, the other cells not",
          "[sim][sensor]") {
    // The monitor's ground reaches the pack's negative also through the main lead: every
    // reading against it (bus, tap 1 and up) is low by I·R. Cell 1 is tap 1 alone, cells 2–3
    // are tap differences, cell 4 is bus − tap 3, so only the bus and cell 1 move.
    check_lead("ground_lead_ohm", 0.002, 0);
}

TEST_CASE("Simulated log formats: one table names them, for scenarios, both commands and their messages", "[sim][sensor]") {
    REQUIRE(sim_log_formats().size() == 5);
    std::vector<std::string> names = sim_log_format_names();
    REQUIRE(names == std::vector<std::string>{"raw", "csv", "edgetx", "dataflash", "ulog"});
    for (const SimLogFormatEntry& e : sim_log_formats()) {
        INFO(e.name);
        SimLogFormat parsed = SimLogFormat::Csv;
        CHECK(parse_sim_log_format(e.name, parsed));
        CHECK(parsed == e.format);
        CHECK(std::string(sim_log_format_name(e.format)) == e.name);
        CHECK(std::string(sim_log_extension(e.format)) == e.extension);
    }
    SimLogFormat untouched = SimLogFormat::Radio;
    CHECK_FALSE(parse_sim_log_format("auto", untouched));  // a scenario's default, not a format
    CHECK_FALSE(parse_sim_log_format("ULOG", untouched));
    CHECK(untouched == SimLogFormat::Radio);
    CHECK(sim_log_format_help() ==
          "raw (4 cells only), csv, edgetx (a radio's telemetry log: pack voltage and current in 0.1 V and 0.1 A "
          "steps every log.interval_s, no cells), dataflash (an ArduPilot .bin log: BAT and BCL at 10 Hz) or ulog "
          "(a PX4 .ulg log: battery_status at 5 Hz)");
    CHECK(log_format_problem("xml", 4) ==
          "expected \"auto\", \"raw\", \"csv\", \"edgetx\", \"dataflash\" or \"ulog\", found \"xml\"");
    CHECK(log_format_problem("auto", 6).empty());
    CHECK(log_format_problem("raw", 6) == "the raw logger format has exactly 4 cells; use \"csv\" for 6 cells");
}
