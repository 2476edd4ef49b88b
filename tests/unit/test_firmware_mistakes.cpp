// The firmware under a builder's usual mistakes, on small raw logs written here (no shared
// data): a board whose INA3221 does not answer, and the serial `status` note a host parses.
#include <memory>
#include <sstream>
#include <string>

#include "app/logger_app.h"
#include "app/monitor_app.h"
#include "battsim_config.h"
#include "host/serial/line_protocol.h"
#include "mock_hardware.h"
#include "test_firmware_support.h"

using namespace battsim;

namespace {

// 300 readings at the INA226's 67 ms, 4S at 4.15 V a cell; 10 A between readings 100 and 199
// (shunt 4.1550 mV through the reference calibration), rest otherwise.
std::string small_raw_log() {
    std::string log;
    for (int k = 0; k < 300; ++k) {
        const bool load = k >= 100 && k < 200;
        log += std::to_string(630 + 67 * k) + ",16.60,4.150,4.150,4.150,4.150," + (load ? "10000,4.1550," : "50,0.3900,") + "\n";
    }
    return log;
}

// The same rest and load with the shunt's sense wires swapped from reading `from` to `to`:
// shunt and current read negative, and the rest's -0.39 mV is -2.0 A through the reference
// calibration (its offset is -0.98 A), beyond minus the take-off current already.
std::string swapped_raw_log(int from, int to) {
    std::string log;
    for (int k = 0; k < 300; ++k) {
        const bool load = k >= 100 && k < 200;
        const bool swapped = k >= from && k < to;
        log += std::to_string(630 + 67 * k) + ",16.60,4.150,4.150,4.150,4.150," +
               (swapped ? (load ? "-10000,-4.1550," : "-50,-0.3900,") : (load ? "10000,4.1550," : "50,0.3900,")) + "\n";
    }
    return log;
}

// Runs the monitor over `log`, every OLED frame written to `oled_path`; returns the UART's
// bytes, a `status` at the end included.
std::string monitor_status_after(const std::string& log, const std::string& oled_path, std::string* buzzer_record = nullptr) {
    fw::host::RawLogSource source(log);
    fw::host::MockClock clock;
    fw::host::LogSensors sensors(source, clock);
    fw::host::DirectoryStorage storage(".", false);  // no card
    fw::host::TextDisplay display(clock, oled_path);
    fw::host::ScriptedSerial serial;
    fw::host::RecordingBuzzer buzzer(clock);
    auto app = std::make_unique<fw::MonitorApp>(sensors, clock, storage, display, serial);
    fw::MonitorAppConfig cfg;
    cfg.monitor = battsim_generated::monitor_config();
    if (buzzer_record != nullptr) app->attach_buzzer(buzzer);
    app->begin(cfg);
    serial.feed("hello\n");
    while (!sensors.finished()) app->step();
    serial.feed("status\n");
    app->step();
    if (buzzer_record != nullptr) *buzzer_record = buzzer.record();
    return serial.output();
}

// The first n comma-separated fields of a CSV line.
std::string first_fields(const std::string& line, int n) {
    size_t end = 0;
    for (int k = 0; k < n && end != std::string::npos; ++k) end = line.find(',', end == 0 ? 0 : end + 1);
    return line.substr(0, end);
}

std::string write_small_log(const std::string& dir) {
    const std::string path = dir + "/small.csv";
    fwtest::write_file(path, small_raw_log());
    return path;
}

}  // namespace

TEST_CASE("discharge logger without an INA3221 records the pack without cell columns, and says so", "[firmware]") {
    const std::string dir = fwtest::temp_dir("fwnotaps");
    const std::string log = write_small_log(dir);

    // With the taps: the config's four cells, every reading sent, no note.
    fwtest::Run r = fwtest::run(BATTSIM_FW_HOST_BINARY, "--program logger --uart " + fwtest::q(dir + "/with.txt") + " " + fwtest::q(log));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const std::string with_uart = fwtest::read_file(dir + "/with.txt");
    const host::serial::DecodedStream with = host::serial::decode_device_stream(with_uart);
    REQUIRE(with.csv_lines.size() == 301);
    CHECK(with.csv_lines[0] == "time_us,voltage_v,current_a,shunt_mv,cell1_v,cell2_v,cell3_v,cell4_v,consumed_mah,missed_readings");
    CHECK(with_uart.find("# no INA3221") == std::string::npos);

    // Without: until this fix the header named four cells and no line followed, silently.
    r = fwtest::run(BATTSIM_FW_HOST_BINARY, "--program logger --no-taps --uart " + fwtest::q(dir + "/without.txt") + " --oled " +
                                                fwtest::q(dir + "/without.oled") + " " + fwtest::q(log));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.find("lines sent 300") != std::string::npos);
    const std::string uart = fwtest::read_file(dir + "/without.txt");
    const host::serial::DecodedStream rec = host::serial::decode_device_stream(uart);
    CHECK(rec.corrupt == 0);
    REQUIRE(rec.csv_lines.size() == 301);
    CHECK(rec.csv_lines[0] == "time_us,voltage_v,current_a,shunt_mv,consumed_mah,missed_readings");
    CHECK(rec.csv_lines[1] == "630000,16.60000,0.0479859002,0.3900,0.000,0");
    CHECK(uart.find("# no INA3221: no cell columns until the next hello\n") != std::string::npos);
    // The pack's columns are the same numbers as with the taps.
    CHECK(first_fields(rec.csv_lines[150], 4) == first_fields(with.csv_lines[150], 4));
    CHECK(first_fields(rec.csv_lines[150], 4) == "10613000,16.60000,9.99918938,4.1550");
    // The OLED says why the record has no cells.
    CHECK(fwtest::read_file(dir + "/without.oled").find("no taps") != std::string::npos);

    // And battsim reads the record as it is.
    std::string csv;
    for (const std::string& l : rec.csv_lines) csv += l + "\n";
    fwtest::write_file(dir + "/record.csv", csv);
    r = fwtest::run(BATTSIM_BINARY, "replay " + fwtest::q(dir + "/record.csv") + " -c " + fwtest::q(fwtest::reference_config_path()));
    INFO(r.err);
    CHECK(r.exit_code == 0);
}

TEST_CASE("the status note's output list splits on commas with no empty items", "[firmware][serial]") {
    const std::string dir = fwtest::temp_dir("fwstatus");
    const std::string log = write_small_log(dir);
    fw::host::RawLogSource source(log);
    fw::host::MockClock clock;
    fw::host::LogSensors sensors(source, clock, false);  // and no INA3221
    fw::host::DirectoryStorage storage(".", false);      // no card
    fw::host::TextDisplay display(clock);
    fw::host::ScriptedSerial serial;
    fw::host::ScriptedSerial telemetry;
    fw::host::RecordingBuzzer buzzer(clock);
    auto app = std::make_unique<fw::MonitorApp>(sensors, clock, storage, display, serial);
    fw::MonitorAppConfig cfg;
    cfg.monitor = battsim_generated::monitor_config();
    cfg.outputs.mavlink = false;
    app->attach_telemetry(telemetry);
    app->attach_buzzer(buzzer);
    app->begin(cfg);
    const char* commands[] = {"hello\nstatus\n", "out oled off\n", "out mavlink on\n", "out oled on\n",
                              "out uart off\nout sd off\nout oled off\nout mavlink off\nout buzzer off\n"};
    size_t samples = 0, next = 0;
    while (!sensors.finished()) {
        if (next < 5 && samples == next * 10) serial.feed(commands[next++]);
        if (app->step() == fw::MonitorApp::Step::Sample) ++samples;
    }
    REQUIRE(next == 5);
    const std::string out = serial.output();
    INFO(out);
    CHECK(out.find(" taps=none sd=off ") != std::string::npos);
    CHECK(out.find(" out=uart,sd,oled,buzzer\n") != std::string::npos);
    CHECK(out.find(" out=uart,sd,buzzer\n") != std::string::npos);  // had been "uart,sd,,buzzer"
    CHECK(out.find(" out=uart,sd,mavlink,buzzer\n") != std::string::npos);
    CHECK(out.find(" out=uart,sd,oled,mavlink,buzzer\n") != std::string::npos);
    CHECK(out.find(" out=buzzer\n") != std::string::npos);  // had been ",buzzer"
    CHECK(out.find(" out=none\n") != std::string::npos);
    // Every note's list, not only those above: no empty item anywhere.
    size_t notes = 0;
    for (size_t p = out.find(" out="); p != std::string::npos; p = out.find(" out=", p + 1)) {
        const std::string list = out.substr(p + 5, out.find('\n', p) - p - 5);
        CHECK(list.find(",,") == std::string::npos);
        CHECK(list.front() != ',');
        CHECK(list.back() != ',');
        ++notes;
    }
    CHECK(notes == 9);  // "status" and one a switch
}

TEST_CASE("monitor says SIGN when the shunt's sense wires are swapped, not on a moment of braking", "[firmware]") {
    const std::string dir = fwtest::temp_dir("fwsign");
    struct Case {
        int from, to;
        bool reversed;
    };
    // Swapped from the start; only in the air (readings 120-199, 5.4 s); a brief reversal in
    // the air (readings 120-145, 1.7 s, as an ESC's braking would be, but longer); none.
    for (const Case c : {Case{0, 300, true}, Case{120, 200, true}, Case{120, 146, false}, Case{0, 0, false}}) {
        INFO("swapped from reading " << c.from << " to " << c.to);
        const std::string log = dir + "/swapped.csv";
        fwtest::write_file(log, swapped_raw_log(c.from, c.to));
        std::string buzzer;
        const std::string out = monitor_status_after(log, dir + "/oled.txt", &buzzer);
        const std::string oled = fwtest::read_file(dir + "/oled.txt");
        REQUIRE(out.find(" flights=") != std::string::npos);
        CHECK((out.find(" current=reversed out=") != std::string::npos) == c.reversed);
        CHECK((oled.find("SIGN") != std::string::npos) == c.reversed);
        // The buzzer too (a build without an OLED): one long beep, a sensor fault's, 2 s into the reversal.
        int beeps = 0;
        std::istringstream in(buzzer);
        std::string line, first_on;
        while (std::getline(in, line))
            if (line.size() > 2 && line.compare(line.size() - 2, 2, ",1") == 0 && beeps++ == 0) first_on = line;
        CHECK(beeps == (c.reversed ? 1 : 0));
        if (c.reversed) {
            INFO(buzzer);
            CHECK(std::stod(first_on) > 2.0);
        }
    }
}
