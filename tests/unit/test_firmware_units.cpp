// The firmware application's building blocks: sensor units, time stamps, the line
// protocol (against the host's decoder), the averages file, and the series formatter
// against the host's SeriesWriter.
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

#include "app/averages_file.h"
#include "app/display_pages.h"
#include "app/line_link.h"
#include "app/readings.h"
#include "app/series_line.h"
#include "telemetry/text_buffer.h"
#include "host/report/series_writer.h"
#include "host/serial/line_protocol.h"
#include "mock_hardware.h"
#include "test_firmware_support.h"

using namespace battsim;

TEST_CASE("sensor readings become the floats nearest their decimal values", "[firmware]") {
    fw::PackReading p;
    p.bus_10uv = 1666000;  // 16.66 V
    p.shunt_100nv = 6700;  // 0.67 mV
    CHECK(fwtest::same_bits(fw::bus_voltage_v(p), std::strtof("16.66", nullptr)));
    CHECK(fwtest::same_bits(fw::shunt_voltage_mv(p), std::strtof("0.67", nullptr)));
    core::ShuntCalibration cal;
    CHECK(fwtest::same_bits(fw::pack_current_a(p, cal),
                            core::current_ma_from_shunt_mv(std::strtof("0.67", nullptr), cal) / 1000.0f));

    // Every INA226 bus step up to 36 V and every shunt step over ±81.92 mV, against strtof
    // of the exact decimal the logger writes.
    for (int32_t raw = 0; raw <= 28800; raw += 7) {
        fw::PackReading r;
        r.bus_10uv = raw * 125;
        telemetry::FixedText<32> t;
        t.append_fixed(r.bus_10uv, fw::kBusDecimals);
        INFO(t.c_str());
        REQUIRE(fwtest::same_bits(fw::bus_voltage_v(r), std::strtof(t.c_str(), nullptr)));
    }
    for (int32_t raw = -32768; raw <= 32767; raw += 5) {
        fw::PackReading r;
        r.shunt_100nv = raw * 25;
        telemetry::FixedText<32> t;
        t.append_fixed(r.shunt_100nv, fw::kShuntDecimals);
        INFO(t.c_str());
        REQUIRE(fwtest::same_bits(fw::shunt_voltage_mv(r), std::strtof(t.c_str(), nullptr)));
    }
}

TEST_CASE("cumulative taps give the cell voltages; the top cell is bus minus the last tap", "[firmware]") {
    fw::PackReading p;
    p.bus_10uv = 1666000;
    fw::TapReading t;
    t.tap_mv[0] = 4144;
    t.tap_mv[1] = 8304;
    t.tap_mv[2] = 12472;
    int32_t cells[fw::kTapChannels + 1] = {};
    REQUIRE(fw::cell_voltages_10uv(p, t, 4, cells) == 4);
    CHECK(cells[0] == 414400);
    CHECK(cells[1] == 416000);
    CHECK(cells[2] == 416800);
    CHECK(cells[3] == 1666000 - 1247200);
    REQUIRE(fw::cell_voltages_10uv(p, t, 3, cells) == 3);  // 3S: two taps, top = bus − tap 2
    CHECK(cells[2] == 1666000 - 830400);
    CHECK(fw::cell_voltages_10uv(p, t, 5, cells) == 0);  // more cells than taps: no cell data
    CHECK(fw::cell_voltages_10uv(p, t, 1, cells) == 0);

    core::Sample s;
    fw::make_sample(123, p, &t, 4, core::ShuntCalibration{}, s);
    CHECK(s.time_us == 123u);
    CHECK(s.cell_count == 4);
    CHECK(fwtest::same_bits(s.cell_voltage_v[0], std::strtof("4.144", nullptr)));
    fw::make_sample(123, p, nullptr, 4, core::ShuntCalibration{}, s);
    CHECK(s.cell_count == 0);
}

TEST_CASE("reading timer extends the 32-bit clock and counts skipped conversions", "[firmware]") {
    fw::ReadingTimer t(67712);
    const uint32_t start = 0xFFFFFFFFu - 100000u;  // wraps after two readings
    CHECK(t.stamp(start) == start);
    CHECK(t.stamp(start + 67712u) == uint64_t{start} + 67712u);
    const uint32_t wrapped = start + 2u * 67712u;  // past 2^32
    CHECK(wrapped < start);
    CHECK(t.stamp(wrapped) == uint64_t{start} + 2u * 67712u);
    CHECK(t.missed() == 0);
    t.stamp(wrapped + 67712u + 33000u);  // 1.49 periods: late, nothing skipped
    CHECK(t.missed() == 0);
    t.stamp(wrapped + 67712u + 33000u + 350000u);  // 350 ms: ~5.2 periods, 4 skipped
    CHECK(t.missed() == 4);
    CHECK(t.readings() == 5);
}

TEST_CASE("text buffer writes fixed-point numbers exactly and refuses to overflow", "[firmware]") {
    telemetry::FixedText<16> t;
    t.append_fixed(-5, 5);
    CHECK(std::string(t.c_str()) == "-0.00005");
    t.clear();
    t.append_fixed(1666000, 5);
    CHECK(std::string(t.c_str()) == "16.66000");
    telemetry::FixedText<32> wide;
    wide.append_fixed(std::numeric_limits<int64_t>::min(), 0);
    CHECK(std::string(wide.c_str()) == "-9223372036854775808");
    CHECK_FALSE(wide.overflow());
    t.clear();
    t.append("0123456789abcdefXYZ");
    CHECK(t.overflow());
    CHECK(t.size() == 15);
}

TEST_CASE("device line framing decodes on the host; damaged and joined lines do not", "[firmware][serial]") {
    fw::host::ScriptedSerial port;
    fw::LineLink link(port);
    link.prompt_if_due(0);
    link.prompt_if_due(500);  // not yet due
    link.prompt_if_due(1000);
    CHECK(port.take_output() == "BMS\nBMS\n");
    port.feed("hel");
    CHECK(link.poll() == fw::LineLink::Event::None);
    port.feed("lo\r\nout sd off\n");
    CHECK(link.poll() == fw::LineLink::Event::Hello);
    CHECK(link.connected());
    CHECK(link.poll() == fw::LineLink::Event::Command);
    CHECK(std::string(link.command()) == "out sd off");
    link.prompt_if_due(5000);  // connected: no more prompts
    const std::string csv = "629000,16.66000,0.788048863,0.6700";
    link.send_data((csv + "\n").c_str(), csv.size() + 1);
    link.send_note("hi");
    const std::string out = port.take_output();
    CHECK(out.rfind("hello\n$" + csv + "*", 0) == 0);
    CHECK(out.substr(out.size() - 5) == "# hi\n");
    CHECK(out.find("$" + csv + "*") != std::string::npos);

    // The host accepts exactly what the device framed.
    const host::serial::DecodedStream d = host::serial::decode_device_stream(out);
    REQUIRE(d.csv_lines.size() == 1);
    CHECK(d.csv_lines[0] == csv);
    CHECK(host::serial::with_checksum(csv) + "\n" == out.substr(6, out.size() - 6 - 5));
    CHECK(fw::line_checksum(csv.data(), csv.size()) == host::serial::line_checksum(csv));

    // A flipped character, a line joined half-way (no '$'), a lower-case sum: all rejected.
    std::string bad = host::serial::with_checksum(csv);
    bad[5] = '1';
    CHECK(host::serial::classify_line(bad).kind == host::serial::LineKind::Corrupt);
    CHECK(host::serial::classify_line(host::serial::with_checksum(csv).substr(3)).kind ==
          host::serial::LineKind::Corrupt);
    std::string lower = host::serial::with_checksum("a,b");
    for (char& c : lower) c = static_cast<char>(std::tolower(c));
    if (lower != host::serial::with_checksum("a,b")) {
        CHECK(host::serial::classify_line(lower).kind == host::serial::LineKind::Corrupt);
    }
    // Overlong input from a wrong baud rate is dropped whole, then lines work again.
    port.feed(std::string(100, 'x') + "\nstatus\n");
    CHECK(link.poll() == fw::LineLink::Event::Command);
    CHECK(std::string(link.command()) == "status");
}

TEST_CASE("averages file round-trips floats exactly and rejects anything damaged", "[firmware]") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> dist(0.0f, 2000.0f);
    for (int i = 0; i < 2000; ++i) {
        fw::StoredAverages a;
        a.current_a = dist(rng);
        a.power_w = dist(rng);
        a.flights = static_cast<uint32_t>(i * 37);
        telemetry::FixedText<160> t;
        fw::format_averages(a, t);
        REQUIRE_FALSE(t.overflow());
        fw::StoredAverages b;
        REQUIRE(fw::parse_averages(t.c_str(), t.size(), b));
        REQUIRE(fwtest::same_bits(a.current_a, b.current_a));
        REQUIRE(fwtest::same_bits(a.power_w, b.power_w));
        REQUIRE(a.flights == b.flights);
    }
    const std::string good = "battsim-averages 1\ncurrent_a=12.5\npower_w=300\nflights=3\n";
    fw::StoredAverages out;
    REQUIRE(fw::parse_averages(good.data(), good.size(), out));
    CHECK(out.current_a == 12.5f);
    const char* bad[] = {
        "battsim-averages 2\ncurrent_a=12.5\npower_w=300\nflights=3\n",
        "battsim-averages 1\ncurrent_a=12.5\npower_w=300\nflights=3",  // cut off
        "battsim-averages 1\ncurrent_a=12.5\npower_w=300\n",
        "battsim-averages 1\ncurrent_a=nan\npower_w=300\nflights=3\n",
        "battsim-averages 1\ncurrent_a=-1\npower_w=300\nflights=3\n",
        "battsim-averages 1\ncurrent_a=12.5x\npower_w=300\nflights=3\n",
        "battsim-averages 1\npower_w=300\ncurrent_a=12.5\nflights=3\n",
        "battsim-averages 1\ncurrent_a=12.5\npower_w=300\nflights=3\nextra\n",
        "",
    };
    for (const char* b : bad) {
        INFO(b);
        fw::StoredAverages x;
        x.current_a = 7.0f;
        CHECK_FALSE(fw::parse_averages(b, std::strlen(b), x));
        CHECK(x.current_a == 7.0f);
    }
}

TEST_CASE("firmware series formatter writes the host SeriesWriter's bytes", "[firmware]") {
    const std::string dir = fwtest::temp_dir("fwseries");
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-500.0f, 500.0f);
    for (int cells : {0, 3, 4, 6}) {
        const std::string path = dir + "/s" + std::to_string(cells) + ".csv";
        std::string fw_text;
        {
            host::SeriesWriter w(path, cells);
            telemetry::FixedText<fw::kSeriesLineCapacity> t;
            fw::format_series_header(cells, t);
            fw_text += t.c_str();
            for (int i = 0; i < 300; ++i) {
                core::Sample s;
                core::MonitorStatus st;
                s.time_us = static_cast<uint64_t>(rng()) * 997u + (i == 0 ? 0u : 1u);
                s.voltage_v = u(rng);
                s.current_a = u(rng);
                s.cell_count = static_cast<uint8_t>(i % 3 == 0 ? 0 : cells);
                for (int c = 0; c < core::kMaxCells; ++c) s.cell_voltage_v[c] = u(rng) / 100.0f;
                st.filtered_current_a = u(rng);
                st.model_voltage_v = u(rng);
                st.adapted_model_voltage_v = u(rng);
                st.consumed_mah = u(rng) * 10.0f;
                st.consumed_mwh = u(rng) * 1000.0f;
                st.soc = u(rng) / 500.0f;
                st.capacity_ah = u(rng) / 100.0f;
                st.resistance_ohm = u(rng) / 1e4f;
                st.usable_capacity_ah = u(rng) / 100.0f;
                st.time_valid = i % 4 != 1;
                st.remaining_time_s = u(rng);
                st.total_time_s = u(rng);
                st.avg_power_w = u(rng);
                st.flying = i % 2 == 0;
                st.sample_valid = i % 5 != 0;
                st.warnings = static_cast<uint8_t>(i % 32);
                st.cell_count = static_cast<uint8_t>(i % 2 == 0 ? cells : 0);
                for (int c = 0; c < core::kMaxCells; ++c) st.cell_score[c] = u(rng) / 500.0f;
                st.capacity_sigma_ah = u(rng) / 1000.0f;
                st.expected_time_s = u(rng) * 10.0f;
                st.remaining_energy_wh = i == 9 ? 3.0e38f : u(rng);  // the widest a float prints
                st.rest_capacity_ah = u(rng) / 100.0f;
                st.outlier_cell = static_cast<int8_t>(i % 7 - 1);
                st.pack_capacity_deficit = u(rng) / 500.0f;
                for (int c = 0; c < core::kMaxCells; ++c) {
                    st.cell_resistance_ohm[c] = u(rng) / 1e4f;
                    st.cell_capacity_deficit[c] = u(rng) / 500.0f;
                    st.cell_capacity_deficit_sigma[c] = u(rng) / 1000.0f;
                }
                if (i == 7) st.soc = -0.0f;  // sign of zero survives both
                w.add(s, st);
                fw::format_series_line(s, st, cells, t);
                REQUIRE_FALSE(t.overflow());
                fw_text += t.c_str();
            }
            w.commit();
        }
        INFO("cells " << cells);
        REQUIRE(fw_text == fwtest::read_file(path));
    }
}

TEST_CASE("The OLED's warning row names a sensor fault by its cause, in a pilot's glance", "[firmware]") {
    fw::host::MockClock clock;
    fw::host::TextDisplay display(clock);
    core::Sample sample;
    sample.voltage_v = 16.4f;
    core::MonitorStatus status;
    fw::MonitorPage page;
    page.sample = &sample;
    page.status = &status;
    const auto warning_row = [&]() {
        fw::draw_monitor_page(display, page);
        const std::string f = display.frame();
        const size_t start = f.rfind('\n', f.size() - 2) + 1;  // row 6, the last
        return f.substr(start, f.size() - 1 - start);
    };
    CHECK(warning_row().rfind("ok ", 0) == 0);
    status.warnings = 1u << core::kWarnSensorFault;
    const struct {
        uint8_t cause;
        const char* shown;
    } cases[] = {{core::kFaultReading, "SENS "}, {core::kFaultCells, "TAP "}, {core::kFaultCurrentOffset, "OFS "},
                 {core::kFaultSampleGap, "GAP "}, {core::kFaultReading | core::kFaultSampleGap, "SENS "}, {0, "SENS "}};
    for (const auto& c : cases) {
        status.sensor_fault_cause = c.cause;
        INFO("cause " << int(c.cause));
        CHECK(warning_row().rfind(c.shown, 0) == 0);
    }
    // Everything at once is cut at 21 columns: the short-flight verdict comes first.
    status.warnings = 0x1F;
    status.outlier_cell = 5;
    status.sensor_fault_cause = core::kFaultCurrentOffset;
    CHECK(warning_row() == "SHORT CAP RES CELL6 O");
}

TEST_CASE("The OLED's cell row keeps all four cells when a tap reads nonsense", "[firmware]") {
    fw::host::MockClock clock;
    fw::host::TextDisplay display(clock);
    core::Sample sample;
    sample.voltage_v = 16.4f;
    sample.cell_count = 4;
    const float cells[4] = {4.2f, 32.76f, -12.6f, 4.19f};
    for (int c = 0; c < 4; ++c) sample.cell_voltage_v[c] = cells[c];
    core::MonitorStatus status;
    fw::MonitorPage page;
    page.sample = &sample;
    page.status = &status;
    fw::draw_monitor_page(display, page);
    // Row 5 (index 4): before, the wide values pushed the fourth cell off the 21 columns.
    const std::string f = display.frame();
    size_t start = 0;
    for (int row = 0; row < 4; ++row) start = f.find('\n', start) + 1;
    CHECK(f.substr(start, f.find('\n', start) - start) == "4.20 ---- ---- 4.19  ");  // padded to 21
}

TEST_CASE("The OLED shows no resistance until there is an estimate, as the series does", "[firmware]") {
    fw::host::MockClock clock;
    fw::host::TextDisplay display(clock);
    core::Sample sample;
    core::MonitorStatus status;
    status.capacity_ah = 1.55f;
    fw::MonitorPage page;
    page.sample = &sample;
    page.status = &status;
    const auto row3 = [&]() {
        fw::draw_monitor_page(display, page);
        const std::string f = display.frame();
        const size_t start = f.find('\n', f.find('\n') + 1) + 1;
        return f.substr(start, f.find('\n', start) - start);
    };
    CHECK(row3() == "Cap 1.55Ah R --mOhm  ");  // had read "R  0mOhm", like a measurement
    // The joint estimator's configured prior is no measurement either.
    status.resistance_ohm = 0.02f;
    CHECK(row3() == "Cap 1.55Ah R --mOhm  ");
    status.resistance_ohm = 0.0214f;
    status.resistance_measured = true;
    CHECK(row3() == "Cap 1.55Ah R 21mOhm  ");
}
