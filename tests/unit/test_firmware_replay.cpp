// The firmware application (firmware/src/app on the host mocks) against battsim replay on
// the shared predictive-bms flights: the same core, the same numbers.
//
// Two ways, because a raw flight log holds five rounded voltages (bus and four cells) for
// the four readings the hardware takes (bus and three cumulative taps; the top cell is
// bus − tap 3), and in ~40 % of its rows the rounded cells do not add up to the rounded
// bus. The firmware therefore sees the logged bus and cells 1–3 exactly but a cell 4 that
// can differ by 10–20 mV from the logged one:
//  1. directly on the raw flights, every sample value but cell 4 and every status field
//     that does not depend on cell voltages must be bit-identical to replay's;
//  2. the firmware's own discharge-logger record of the same readings, replayed by
//     `battsim replay`, must give the firmware monitor's SD series byte for byte, and
//     every status field, cells included, bit for bit.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/averages_file.h"
#include "app/monitor_app.h"
#include "battsim_config.h"
#include "exit_codes.h"
#include "host/config_json.h"
#include "host/replay.h"
#include "host/serial/line_protocol.h"
#include "mavlink_decode.h"
#include "mock_hardware.h"
#include "test_firmware_support.h"

using namespace battsim;
using fwtest::flight_path;

namespace {

struct FirmwareRun {
    std::vector<core::Sample> samples;
    std::vector<core::MonitorStatus> statuses;
    std::vector<core::RollingAverage::Status> twin;
    fw::ReadingCounters counters;
    fw::MonitorAppState state;
    core::MonitorConfig config_used;
    std::string uart;
    std::string mavlink;  // the telemetry UART's bytes (with `telemetry`)
    long display_frames = 0;
};

// Runs the monitor program in-process over `log`. `sd_dir` empty = no card. `commands`
// maps a sample count to host input fed after that many samples.
FirmwareRun run_monitor(const std::string& log, const std::string& sd_dir,
                        const std::vector<std::pair<size_t, std::string>>& commands = {{0, "hello\n"}},
                        bool telemetry = false) {
    fw::host::RawLogSource source(log);
    fw::host::MockClock clock;
    fw::host::LogSensors sensors(source, clock);
    fw::host::DirectoryStorage storage(sd_dir.empty() ? std::string(".") : sd_dir, !sd_dir.empty());
    fw::host::TextDisplay display(clock);
    fw::host::ScriptedSerial serial;
    auto app = std::make_unique<fw::MonitorApp>(sensors, clock, storage, display, serial);
    fw::MonitorAppConfig cfg;
    cfg.monitor = battsim_generated::monitor_config();
    fw::host::ScriptedSerial telemetry_port;
    if (telemetry) app->attach_telemetry(telemetry_port);
    app->begin(cfg);
    FirmwareRun r;
    size_t next_command = 0;
    while (!sensors.finished()) {
        while (next_command < commands.size() && commands[next_command].first == r.samples.size()) {
            serial.feed(commands[next_command++].second);
        }
        if (app->step() != fw::MonitorApp::Step::Sample) continue;
        r.samples.push_back(app->last_sample());
        r.statuses.push_back(app->status());
        r.twin.push_back(app->current_average());
    }
    app->sync_storage();
    REQUIRE(storage.close_log());
    INFO(source.error());
    REQUIRE_FALSE(source.failed());
    r.counters = app->counters();
    r.state = app->state();
    r.config_used = app->monitor_config();
    r.uart = serial.output();
    r.mavlink = telemetry_port.output();
    r.display_frames = display.frames();
    return r;
}

struct ReplayRun {
    std::vector<core::Sample> samples;
    std::vector<core::MonitorStatus> statuses;
};

ReplayRun run_replay(const std::string& log, const host::LoadedConfig& config, host::CurrentSource source) {
    host::ReplayOptions opt;
    opt.config = config;
    opt.reader.current_source = source;
    ReplayRun r;
    host::replay_log(log, opt, [&](const core::Sample& s, const core::MonitorStatus& st) {
        r.samples.push_back(s);
        r.statuses.push_back(st);
    });
    return r;
}

host::LoadedConfig reference_config() { return host::load_config_file(fwtest::reference_config_path()); }

long cents(float v) { return std::lround(static_cast<double>(v) * 100.0); }

// The SD series of a monitor run, and the discharge logger's record decoded as `battsim log` would.
std::string run_fw_host(const std::string& args) {
    const fwtest::Run r = fwtest::run(BATTSIM_FW_HOST_BINARY, args);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    return r.out;
}

// The firmware discharge logger's record of `flight`, decoded and kept as the CSV `battsim
// log` writes (DIR/logger-TAG.csv); returns its path and, in *lines, its row count.
std::string logger_record(const std::string& raw_log, const std::string& dir, const std::string& tag, size_t* lines = nullptr) {
    const std::string uart = dir + "/logger-" + tag + ".uart";
    run_fw_host("--program logger --uart " + fwtest::q(uart) + " " + fwtest::q(raw_log));
    const host::serial::DecodedStream rec = host::serial::decode_device_stream(fwtest::read_file(uart));
    REQUIRE(rec.corrupt == 0);
    REQUIRE(rec.partial_bytes == 0);
    REQUIRE(rec.before_header == 0);
    std::string csv;
    for (const std::string& l : rec.csv_lines) csv += l + "\n";
    const std::string path = dir + "/logger-" + tag + ".csv";
    fwtest::write_file(path, csv);
    if (lines) *lines = rec.csv_lines.size();
    return path;
}

// The series CSV of `battsim replay LOG --config CONFIG ARGS`.
std::string replay_series(const std::string& log, const std::string& config, const std::string& args) {
    const std::string out = log + ".series.csv";
    const fwtest::Run r = fwtest::run(BATTSIM_BINARY, "replay " + fwtest::q(log) + " --config " + fwtest::q(config) + " " +
                                                          args + " --series " + fwtest::q(out));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    return fwtest::read_file(out);
}

}  // namespace

TEST_CASE("firmware on the raw flights: samples and cell-independent status equal battsim replay bit for bit",
          "[firmware][replay][data]") {
    const host::LoadedConfig config = reference_config();
    for (int flight : {29, 30, 32, 34}) {
        INFO("flight " << flight);
        const FirmwareRun fw = run_monitor(flight_path(flight), "");
        const ReplayRun rp = run_replay(flight_path(flight), config, host::CurrentSource::Shunt);
        REQUIRE(fw.samples.size() == rp.samples.size());
        REQUIRE(fw.samples.size() > 3000);
        size_t cell4_differs = 0;
        size_t inconsistent_rows = 0;
        for (size_t i = 0; i < fw.samples.size(); ++i) {
            const core::Sample& a = fw.samples[i];
            const core::Sample& b = rp.samples[i];
            INFO("sample " << i << " at " << b.time_us << " us");
            REQUIRE(a.time_us == b.time_us);
            REQUIRE(fwtest::same_bits(a.voltage_v, b.voltage_v));
            REQUIRE(fwtest::same_bits(a.current_a, b.current_a));
            REQUIRE(a.cell_count == 4);
            REQUIRE(b.cell_count == 4);
            for (int c = 0; c < 3; ++c) REQUIRE(fwtest::same_bits(a.cell_voltage_v[c], b.cell_voltage_v[c]));
            // The top cell is bus − tap 3: equal to the logged cell exactly where the log adds up.
            const bool adds_up = cents(b.cell_voltage_v[0]) + cents(b.cell_voltage_v[1]) + cents(b.cell_voltage_v[2]) +
                                     cents(b.cell_voltage_v[3]) ==
                                 cents(b.voltage_v);
            if (!adds_up) ++inconsistent_rows;
            const bool same4 = fwtest::same_bits(a.cell_voltage_v[3], b.cell_voltage_v[3]);
            if (!same4) ++cell4_differs;
            REQUIRE(same4 == adds_up);
            const std::string diff = fwtest::status_difference(fw.statuses[i], rp.statuses[i], false);
            INFO(diff);
            REQUIRE(diff.empty());
        }
        CHECK(cell4_differs == inconsistent_rows);
        CHECK(inconsistent_rows > 0);  // else this test would not need its second half
        CHECK_FALSE(fw.state.current_reversed);  // no SIGN on a rightly wired flight
    }
}

TEST_CASE("firmware monitor's SD series equals battsim replay of the firmware logger's record, byte for byte",
          "[firmware][replay][data]") {
    const std::string dir = fwtest::temp_dir("fwreplay");
    for (int flight : {29, 30, 32, 34}) {
        INFO("flight " << flight);
        const std::string sd = dir + "/sd" + std::to_string(flight);
        REQUIRE(mkdir(sd.c_str(), 0755) == 0);
        const std::string monitor_uart = dir + "/monitor-" + std::to_string(flight) + ".uart";
        const std::string fw_mavlink = dir + "/monitor-" + std::to_string(flight) + ".mavlink";
        const std::string replay_mavlink = dir + "/replay-" + std::to_string(flight) + ".mavlink";
        run_fw_host("--sd " + fwtest::q(sd) + " --uart " + fwtest::q(monitor_uart) + " --mavlink " + fwtest::q(fw_mavlink) +
                    " " + fwtest::q(flight_path(flight)));
        size_t logged_rows = 0;
        const std::string logged = logger_record(flight_path(flight), dir, std::to_string(flight), &logged_rows);
        const std::string expected = replay_series(logged, fwtest::reference_config_path(), "--mavlink " + fwtest::q(replay_mavlink));
        const std::string sd_series = fwtest::read_file(sd + "/battsim/log0001.csv");
        REQUIRE(std::count(expected.begin(), expected.end(), '\n') == static_cast<long>(logged_rows));
        REQUIRE(sd_series.size() == expected.size());
        REQUIRE(sd_series == expected);

        // The UART carries the same series (framed), for `battsim log` on the monitor.
        const host::serial::DecodedStream mon = host::serial::decode_device_stream(fwtest::read_file(monitor_uart));
        REQUIRE(mon.corrupt == 0);
        std::string uart_series;
        for (const std::string& l : mon.csv_lines) uart_series += l + "\n";
        REQUIRE(uart_series == expected);

        // The telemetry UART's MAVLink: the same bytes as `battsim replay --mavlink`, about
        // one heartbeat and battery status a second, every checksum right.
        const std::string mav = fwtest::read_file(fw_mavlink);
        REQUIRE(mav == fwtest::read_file(replay_mavlink));
        const mavtest::Stream m = mavtest::decode(mav, false);
        REQUIRE(m.error.empty());
        const double log_s = static_cast<double>(logged_rows) * 0.067;
        const long pairs = std::count_if(m.frames.begin(), m.frames.end(), [](const mavtest::Frame& f) { return f.msgid == 147; });
        CHECK(pairs > 0.9 * log_s);
        CHECK(pairs < 1.1 * log_s);
    }
}

TEST_CASE("firmware built with a fitted config runs its model extensions as battsim replay does, byte for byte",
          "[firmware][replay][extension][data]") {
    // configs/fitted/pbms-flight30-cnhl5.json: two RC branches, self-heating, Arrhenius R and K.
    const std::string dir = fwtest::temp_dir("fwfitted");
    const int flight = 30;
    const std::string sd = dir + "/sd";
    REQUIRE(mkdir(sd.c_str(), 0755) == 0);
    const fwtest::Run m = fwtest::run(BATTSIM_FW_HOST_FITTED_BINARY, "--sd " + fwtest::q(sd) + " " + fwtest::q(flight_path(flight)));
    INFO(m.err);
    REQUIRE(m.exit_code == 0);
    const std::string expected = replay_series(logger_record(flight_path(flight), dir, "30"), BATTSIM_FW_FITTED_CONFIG, "");
    const std::string sd_series = fwtest::read_file(sd + "/battsim/log0001.csv");
    REQUIRE(sd_series.size() == expected.size());
    REQUIRE(sd_series == expected);
    // And the extensions were really on: the plain build's series differs.
    const std::string plain_sd = dir + "/sd-plain";
    REQUIRE(mkdir(plain_sd.c_str(), 0755) == 0);
    run_fw_host("--sd " + fwtest::q(plain_sd) + " " + fwtest::q(flight_path(flight)));
    CHECK(fwtest::read_file(plain_sd + "/battsim/log0001.csv") != sd_series);
}

TEST_CASE("firmware built with the joint estimator runs it, cell check included, as battsim replay does, byte for byte",
          "[firmware][replay][joint][data]") {
    // configs/sim-4s.json exported with --estimator joint, on flights 30 and 34 and on a
    // simulated flight in the logger's raw format whose cell 3 holds 30 % less charge: the
    // cell check names it, so the cell check's output is in that series too.
    const std::string dir = fwtest::temp_dir("fwjoint");
    const std::string weak = dir + "/weak-cell3.csv";
    const fwtest::Run sim = fwtest::run(
        BATTSIM_BINARY, "simulate " + fwtest::q(std::string(BATTSIM_SOURCE_DIR) + "/configs/scenarios/4s-racing-weak-cell3-capacity-70.json") +
                            " --format raw -o " + fwtest::q(weak));
    INFO(sim.err);
    REQUIRE(sim.exit_code == 0);
    const std::string logs[] = {flight_path(30), flight_path(34), weak};
    for (int n = 0; n < 3; ++n) {
        const std::string& log = logs[n];
        INFO(log);
        const std::string tag = std::to_string(n);
        const std::string sd = dir + "/sd" + tag;
        REQUIRE(mkdir(sd.c_str(), 0755) == 0);
        const std::string fw_mavlink = dir + "/monitor-" + tag + ".mavlink";
        const std::string replay_mavlink = dir + "/replay-" + tag + ".mavlink";
        const fwtest::Run m = fwtest::run(BATTSIM_FW_HOST_JOINT_BINARY,
                                          "--sd " + fwtest::q(sd) + " --mavlink " + fwtest::q(fw_mavlink) + " " + fwtest::q(log));
        INFO(m.err);
        REQUIRE(m.exit_code == 0);
        const std::string expected = replay_series(logger_record(log, dir, tag), BATTSIM_FW_JOINT_CONFIG,
                                                   "--estimator joint --mavlink " + fwtest::q(replay_mavlink));
        const std::string sd_series = fwtest::read_file(sd + "/battsim/log0001.csv");
        REQUIRE(sd_series.size() == expected.size());
        REQUIRE(sd_series == expected);
        // The joint estimator was really on: the reference build's series differs, and on
        // the weak-cell flight the cell-outlier bit (4) is raised.
        const std::string plain_sd = dir + "/sd-plain" + tag;
        REQUIRE(mkdir(plain_sd.c_str(), 0755) == 0);
        run_fw_host("--sd " + fwtest::q(plain_sd) + " " + fwtest::q(log));
        CHECK(fwtest::read_file(plain_sd + "/battsim/log0001.csv") != sd_series);
        std::istringstream lines(sd_series);
        std::string line;
        std::getline(lines, line);
        size_t column = 0;
        {
            std::istringstream head(line);
            std::string name;
            while (std::getline(head, name, ',') && name != "warnings") ++column;
        }
        bool cell_outlier = false;
        while (std::getline(lines, line)) {
            std::istringstream row(line);
            std::string field;
            for (size_t k = 0; k <= column && std::getline(row, field, ','); ++k) {
            }
            if (!field.empty() && (std::stoi(field) & 4) != 0) cell_outlier = true;
        }
        // Flight 34's cell 1 reads 23 % more resistance than cells 2 and 3; with the logger's
        // ground path declared it is not blamed.
        CHECK(cell_outlier == (log == weak));
        // The device's MAVLink equals replay's, and a ground station is told of the weak cell.
        const std::string mav = fwtest::read_file(fw_mavlink);
        REQUIRE(mav == fwtest::read_file(replay_mavlink));
        const mavtest::Stream stream = mavtest::decode(mav, false);
        REQUIRE(stream.error.empty());
        bool texted = false;
        for (const mavtest::Frame& f : stream.frames) {
            if (f.msgid == 253 && mavtest::text(f).rfind("battsim: cell 3 weak", 0) == 0) texted = true;
        }
        CHECK(texted == (log == weak));
    }
}

TEST_CASE("firmware statuses equal replay's bit for bit on the logger's record, cells included", "[firmware][replay][data]") {
    const host::LoadedConfig config = reference_config();
    const std::string dir = fwtest::temp_dir("fwexact");
    for (int flight : {29, 34}) {
        INFO("flight " << flight);
        const std::string logged = logger_record(flight_path(flight), dir, std::to_string(flight));

        const FirmwareRun fw = run_monitor(flight_path(flight), "");
        const ReplayRun rp = run_replay(logged, config, host::CurrentSource::Auto);
        REQUIRE(fw.samples.size() == rp.samples.size());
        bool any_outlier_score = false;
        for (size_t i = 0; i < fw.samples.size(); ++i) {
            INFO("sample " << i);
            const core::Sample& a = fw.samples[i];
            const core::Sample& b = rp.samples[i];
            REQUIRE(a.time_us == b.time_us);
            REQUIRE(fwtest::same_bits(a.voltage_v, b.voltage_v));
            REQUIRE(fwtest::same_bits(a.current_a, b.current_a));
            REQUIRE(a.cell_count == b.cell_count);
            for (int c = 0; c < a.cell_count; ++c) REQUIRE(fwtest::same_bits(a.cell_voltage_v[c], b.cell_voltage_v[c]));
            const std::string diff = fwtest::status_difference(fw.statuses[i], rp.statuses[i], true);
            INFO(diff);
            REQUIRE(diff.empty());
            if (fw.statuses[i].cell_score[3] != 0.0f) any_outlier_score = true;
        }
        CHECK(any_outlier_score);  // the cell path was exercised, not just zeros
    }
}

TEST_CASE("firmware's twin of the current average follows the monitor's exactly", "[firmware][data]") {
    const FirmwareRun fw = run_monitor(flight_path(30), "");
    size_t valid = 0;
    for (size_t i = 0; i < fw.statuses.size(); ++i) {
        INFO("sample " << i);
        REQUIRE(fwtest::same_bits(fw.twin[i].short_avg, fw.statuses[i].avg_current_a));
        if (fw.twin[i].valid) ++valid;
    }
    CHECK(valid > 1000);
}

TEST_CASE("firmware keeps the long-term averages on the SD card across flights", "[firmware][replay][data]") {
    const std::string sd = fwtest::temp_dir("fwavg");
    const FirmwareRun first = run_monitor(flight_path(29), sd);
    REQUIRE_FALSE(first.state.averages_loaded);
    REQUIRE(first.state.averages_saved >= 1);
    REQUIRE(first.state.log_path == std::string("battsim/log0001.csv"));

    // Saved at the last landing: the twin's long current average and the monitor's long power average.
    size_t landing = 0;
    size_t takeoffs = 0;
    for (size_t i = 1; i < first.statuses.size(); ++i) {
        if (first.statuses[i - 1].flying && !first.statuses[i].flying) landing = i;
        if (!first.statuses[i - 1].flying && first.statuses[i].flying) ++takeoffs;
    }
    REQUIRE(landing > 0);
    const std::string text = fwtest::read_file(sd + "/" + fw::kAveragesPath);
    fw::StoredAverages stored;
    REQUIRE(fw::parse_averages(text.data(), text.size(), stored));
    CHECK(fwtest::same_bits(stored.current_a, first.twin[landing].long_avg));
    CHECK(fwtest::same_bits(stored.power_w, first.statuses[landing].long_avg_power_w));
    CHECK(stored.flights == takeoffs);
    CHECK(stored.current_a > 5.0f);
    CHECK(stored.power_w > 100.0f);

    // The next boot starts its averages from the card, and still equals replay given the
    // same remembered values in its config.
    const FirmwareRun second = run_monitor(flight_path(30), sd);
    REQUIRE(second.state.averages_loaded);
    REQUIRE(second.state.log_path == std::string("battsim/log0002.csv"));
    CHECK(fwtest::same_bits(second.config_used.current_average.initial_value, stored.current_a));
    CHECK(fwtest::same_bits(second.config_used.power_average.initial_value, stored.power_w));
    CHECK(second.state.flights > stored.flights);

    host::LoadedConfig config = reference_config();
    CHECK_FALSE(fwtest::same_bits(config.monitor.power_average.initial_value, stored.power_w));
    config.monitor.current_average.initial_value = stored.current_a;
    config.monitor.power_average.initial_value = stored.power_w;
    const ReplayRun rp = run_replay(flight_path(30), config, host::CurrentSource::Shunt);
    REQUIRE(rp.statuses.size() == second.statuses.size());
    for (size_t i = 0; i < rp.statuses.size(); ++i) {
        INFO("sample " << i);
        const std::string diff = fwtest::status_difference(second.statuses[i], rp.statuses[i], false);
        INFO(diff);
        REQUIRE(diff.empty());
    }
    // And it differs from a fresh start: the memory is used, not just stored.
    const FirmwareRun fresh = run_monitor(flight_path(30), "");
    bool differs = false;
    for (size_t i = 0; i < fresh.statuses.size() && !differs; ++i) {
        differs = !fwtest::same_bits(fresh.statuses[i].avg_power_w, second.statuses[i].avg_power_w);
    }
    CHECK(differs);
}

TEST_CASE("firmware reset in the air counts the flight once, in a second log", "[firmware][data]") {
    // Flight 30 cut at 202 s: the first boot takes off and never lands, the second boots in
    // the air. The count is saved at a landing, so the first boot's take-off is never saved.
    const std::string dir = fwtest::temp_dir("fwreset");
    const std::string sd = dir + "/card";
    REQUIRE(std::filesystem::create_directory(sd));
    std::istringstream whole(fwtest::read_file(flight_path(30)));
    std::string before, after, line;
    while (std::getline(whole, line)) {
        (std::stol(line.substr(0, line.find(','))) < 202000 ? before : after) += line + "\n";
    }
    REQUIRE_FALSE(before.empty());
    REQUIRE_FALSE(after.empty());
    fwtest::write_file(dir + "/before.csv", before);
    fwtest::write_file(dir + "/after.csv", after);

    const FirmwareRun first = run_monitor(dir + "/before.csv", sd);
    CHECK(first.state.flights == 1);
    CHECK(first.state.averages_saved == 0);
    const FirmwareRun second = run_monitor(dir + "/after.csv", sd);
    CHECK_FALSE(second.state.averages_loaded);
    CHECK(second.state.log_path == std::string("battsim/log0002.csv"));
    CHECK(second.state.averages_saved >= 1);
    const std::string text = fwtest::read_file(sd + "/" + fw::kAveragesPath);
    fw::StoredAverages stored;
    REQUIRE(fw::parse_averages(text.data(), text.size(), stored));
    CHECK(stored.flights == 1);
}

TEST_CASE("firmware on flight 30 with the shunt's sense wires swapped says so and flies no flight", "[firmware][data]") {
    // Every shunt and current reading's sign turned (columns 7 and 8 of the raw log).
    const std::string dir = fwtest::temp_dir("fwswapped");
    std::istringstream whole(fwtest::read_file(flight_path(30)));
    std::string swapped, line;
    while (std::getline(whole, line)) {
        std::vector<std::string> f;
        for (size_t a = 0, b; a <= line.size(); a = b + 1) {
            b = std::min(line.find(',', a), line.size());
            f.push_back(line.substr(a, b - a));
        }
        REQUIRE(f.size() >= 8);
        for (size_t k : {6u, 7u}) f[k] = f[k][0] == '-' ? f[k].substr(1) : "-" + f[k];
        for (size_t k = 0; k < f.size(); ++k) swapped += (k ? "," : "") + f[k];
        swapped += "\n";
    }
    fwtest::write_file(dir + "/swapped.csv", swapped);
    const FirmwareRun fw = run_monitor(dir + "/swapped.csv", "", {{0, "hello\n"}}, true);
    CHECK(fw.state.current_reversed);
    CHECK(fw.state.flights == 0);
    // From 2 s after the first sample: the rest already reads -2.0 A.
    REQUIRE(fw.samples.size() > 100);
    CHECK(fw.samples[0].current_a < -1.9f);
    // The MAVLink output says it once, 2 s after the first sample, and then only the
    // sensor fault the OLED shows as SENS from 171.8 s: the monitor saw no flight to warn
    // about.
    const mavtest::Stream m = mavtest::decode(fw.mavlink, false);
    REQUIRE(m.error.empty());
    std::vector<std::string> texts;
    for (const mavtest::Frame& f : m.frames)
        if (f.msgid == telemetry::kStatusTextId) texts.push_back(mavtest::text(f));
    CHECK(texts == std::vector<std::string>{telemetry::kReversedText, "battsim: sensor fault: reading out of range"});
    // So does `battsim replay --said` on the log itself, its current read from the shunt
    // column as the firmware reads it, at the same time.
    const fwtest::Run r = fwtest::run(BATTSIM_BINARY, "replay " + fwtest::q(dir + "/swapped.csv") + " --config " +
                                                          fwtest::q(fwtest::reference_config_path()) +
                                                          " --current-source shunt --said --json");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const nlohmann::json said = nlohmann::json::parse(r.out)["said"];
    REQUIRE(said.size() == 2);
    CHECK(said[0]["text"] == telemetry::kReversedText);
    CHECK(said[1]["text"] == texts[1]);
    CHECK(said[0]["time_s"].get<double>() ==
          Approx((fw.samples[0].time_us + telemetry::ReversedCurrentCheck::kHoldUs) * 1e-6).margin(0.07));
}

TEST_CASE("firmware counts the readings it missed from the log's gaps", "[firmware][data]") {
    for (int flight : {29, 32}) {
        INFO("flight " << flight);
        const FirmwareRun fw = run_monitor(flight_path(flight), "");
        // Independent count: a gap of more than 1.5 conversion periods hid round(gap/period) − 1 readings.
        const double period = 2.0 * 2116.0 * 16.0;
        uint32_t expected = 0;
        for (size_t i = 1; i < fw.samples.size(); ++i) {
            const double gap = static_cast<double>(fw.samples[i].time_us - fw.samples[i - 1].time_us);
            if (gap > 1.5 * period) expected += static_cast<uint32_t>(std::floor(gap / period + 0.5)) - 1u;
        }
        CHECK(fw.counters.missed == expected);
        CHECK(expected > 0);  // the flights do have SD-write gaps
        CHECK(fw.counters.readings == fw.samples.size());
        CHECK(fw.counters.ready_timeouts == 0);
    }
}

TEST_CASE("firmware outputs switch on and off from the serial line", "[firmware][data]") {
    const std::string sd = fwtest::temp_dir("fwswitch");
    const FirmwareRun fw = run_monitor(flight_path(32), sd,
                                       {{0, "hello\n"}, {100, "out sd off\n"}, {200, "out uart off\nstatus\n"},
                                        {300, "out oled off\n"}, {400, "out sd on\nbogus\n"}});
    const std::string series = fwtest::read_file(sd + "/battsim/log0001.csv");
    // Header + samples 0..99, then nothing until sample 400 switched it back on.
    const long sd_lines = std::count(series.begin(), series.end(), '\n');
    CHECK(sd_lines == 1 + 100 + static_cast<long>(fw.samples.size() - 400));
    const host::serial::DecodedStream uart = host::serial::decode_device_stream(fw.uart);
    CHECK(uart.csv_lines.size() == 1 + 200);
    CHECK(uart.corrupt == 0);
    CHECK(fw.uart.find("# samples=200 ") != std::string::npos);
    CHECK(fw.uart.find(" timeouts=0 pack_errors=0 tap_errors=0 taps=yes sd=") != std::string::npos);
    CHECK(fw.uart.find("# unknown command") != std::string::npos);
    CHECK_FALSE(fw.state.outputs.display);
    CHECK(fw.state.outputs.sd);
    CHECK_FALSE(fw.state.outputs.uart);
    // About two frames a second while on (300 samples × 67 ms ≈ 20 s), none after.
    CHECK(fw.display_frames >= 30);
    CHECK(fw.display_frames <= 45);
}

TEST_CASE("firmware's MAVLink output switches off and on from the serial line", "[firmware][telemetry][data]") {
    const FirmwareRun fw = run_monitor(flight_path(32), "", {{0, "hello\nstatus\n"}, {150, "out mavlink off\n"}, {300, "out mavlink on\n"}},
                                       true);
    CHECK(fw.uart.find(" out=uart,sd,oled,mavlink") != std::string::npos);  // the first status note
    CHECK(fw.uart.find(" out=uart,sd,oled\n") != std::string::npos);       // after "off"
    const mavtest::Stream m = mavtest::decode(fw.mavlink, false);
    REQUIRE(m.error.empty());
    // A battery status a second while on, none from sample 150 to sample 300 (about 10 s).
    const auto seconds = [&fw](size_t k) { return static_cast<double>(fw.samples[k].time_us) * 1e-6; };
    const double on_s = (seconds(150) - seconds(0)) + (seconds(fw.samples.size() - 1) - seconds(300));
    const long statuses = std::count_if(m.frames.begin(), m.frames.end(), [](const mavtest::Frame& f) { return f.msgid == 147; });
    CHECK(statuses == Approx(on_s).margin(2.5));
    CHECK(seconds(300) - seconds(150) > 8.0);  // so the pause is visible in the count
}

TEST_CASE("firmware sends no data before a host says hello", "[firmware][data]") {
    const FirmwareRun fw = run_monitor(flight_path(34), "", {});
    CHECK(fw.uart.find('$') == std::string::npos);
    // "BMS" once a second of log time.
    const double duration_s = static_cast<double>(fw.samples.back().time_us - fw.samples.front().time_us) * 1e-6;
    size_t prompts = 0;
    for (size_t p = fw.uart.find("BMS\n"); p != std::string::npos; p = fw.uart.find("BMS\n", p + 1)) ++prompts;
    CHECK(fw.uart.size() == prompts * 4);
    CHECK(static_cast<double>(prompts) >= duration_s - 1.0);
    CHECK(static_cast<double>(prompts) <= duration_s + 2.0);
}

// battsim_fw_host keeps its own copy of the CLI's exit codes (the firmware includes nothing
// from cli/): run into each of its exits, it must give cli/exit_codes.h's code for it.
TEST_CASE("battsim_fw_host exits with battsim's exit codes", "[firmware][exit]") {
    const std::string dir = fwtest::temp_dir("fwexit");
    const std::string good = dir + "/good.csv";
    fwtest::write_file(good, "629,16.66,4.14,4.16,4.17,4.18,781.44,0.67,\n696,16.67,4.14,4.17,4.18,4.18,457.66,0.55,\n");
    const auto exits = [](const std::string& args, int code) {
        const fwtest::Run r = fwtest::run(BATTSIM_FW_HOST_BINARY, args);
        INFO(args << ": " << r.err);
        CHECK(r.exit_code == code);
    };
    exits(fwtest::q(good), cli::kExitOk);
    exits("--help", cli::kExitOk);
    exits("--program nope " + fwtest::q(good), cli::kExitUsage);
    exits("--no-such-option " + fwtest::q(good), cli::kExitUsage);
    exits(fwtest::q(dir + "/missing.csv"), cli::kExitInputError);
    exits("--sd " + fwtest::q(dir + "/no-card") + " " + fwtest::q(good), cli::kExitOutputError);
    // A port's file that cannot be written: the run's other exit with kExitOutputError.
    exits("--uart " + fwtest::q(dir) + " " + fwtest::q(good), cli::kExitOutputError);
}

TEST_CASE("battsim_fw_host reports a bad log with file, line and column", "[firmware]") {
    const std::string dir = fwtest::temp_dir("fwbad");
    const std::string bad = dir + "/bad.csv";
    fwtest::write_file(bad, "629,16.66,4.14,4.16,4.17,4.18,781.44,0.67,\n696,16.67,4.14,x,4.18,4.18,457.66,0.55,\n");
    fwtest::Run r = fwtest::run(BATTSIM_FW_HOST_BINARY, fwtest::q(bad));
    CHECK(r.exit_code == 3);
    CHECK(r.err.find(bad + ":2:4: expected a plain decimal number, found \"x\"") != std::string::npos);

    fwtest::write_file(bad, "629,16.66,4.14,4.16,4.17,4.18,781.44\n");
    r = fwtest::run(BATTSIM_FW_HOST_BINARY, fwtest::q(bad));
    CHECK(r.exit_code == 3);
    CHECK(r.err.find(bad + ":1: expected 8 fields") != std::string::npos);

    fwtest::write_file(bad, "629,16.666666,4.14,4.16,4.17,4.18,781.44,0.67,\n");
    r = fwtest::run(BATTSIM_FW_HOST_BINARY, fwtest::q(bad));
    CHECK(r.exit_code == 3);
    CHECK(r.err.find(":1:2: expected at most 5 decimals") != std::string::npos);

    r = fwtest::run(BATTSIM_FW_HOST_BINARY, fwtest::q(dir + "/missing.csv"));
    CHECK(r.exit_code == 3);
    CHECK(r.err.find("cannot open") != std::string::npos);

    r = fwtest::run(BATTSIM_FW_HOST_BINARY, "--program nope " + fwtest::q(bad));
    CHECK(r.exit_code == 2);
    // A readable log written here, so this check needs no shared data.
    const std::string good = dir + "/good.csv";
    fwtest::write_file(good, "629,16.66,4.14,4.16,4.17,4.18,781.44,0.67,\n");
    r = fwtest::run(BATTSIM_FW_HOST_BINARY, "--sd " + fwtest::q(dir + "/no-card") + " " + fwtest::q(good));
    CHECK(r.exit_code == 5);
    CHECK(r.err.find("expected an existing directory") != std::string::npos);
}
