// battsim_fw_host: runs the firmware application on the host against the mocks, fed by a
// raw predictive-bms log at the log's own timing. The monitor writes what the device
// would: the SD card's series CSV (and averages file) under --sd DIR, the UART bytes to
// --uart FILE, the OLED frames to --oled FILE, the telemetry UART's MAVLink to --mavlink FILE,
// the buzzer's switchings to --buzzer FILE.
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "app/logger_app.h"
#include "app/monitor_app.h"
#include "battsim_config.h"
#include "mock_hardware.h"

namespace {

// The CLI's exit codes (cli/exit_codes.h), so scripts treat both tools alike. A copy: the
// firmware includes nothing from cli/; the unit test "battsim_fw_host exits with battsim's exit
// codes" (tests/unit/test_firmware_replay.cpp) fails when the two differ.
constexpr int kExitOk = 0;
constexpr int kExitUsage = 2;
constexpr int kExitInputError = 3;
constexpr int kExitOutputError = 5;

const char* kUsage =
    "usage: battsim_fw_host [options] LOG.csv\n"
    "Runs the firmware on a raw predictive-bms log (time_ms,bus_v,cell1..cell4,current_ma,shunt_mv).\n"
    "  --program monitor|logger  which firmware program (default monitor)\n"
    "  --sd DIR                  directory standing in for the SD card (default: no card)\n"
    "  --uart FILE               write the device's UART output here\n"
    "  --oled FILE               write every OLED frame here as text\n"
    "  --mavlink FILE            write the telemetry UART's MAVLink bytes here (monitor)\n"
    "  --buzzer FILE             write the buzzer's switchings here as time_s,on (monitor)\n"
    "  --no-hello                do not greet the device: it then only prompts \"BMS\"\n"
    "  --no-taps                 the INA3221 does not answer: readings without cell taps\n"
    "  --no-sd-output, --no-uart-output, --no-oled-output   switch an output off\n"
    "  --forget-averages         neither read nor write the averages file on the card\n";

struct Args {
    std::string log;
    std::string program = "monitor";
    std::string sd;
    std::string uart;
    std::string oled;
    std::string mavlink;
    std::string buzzer;
    bool hello = true;
    bool taps = true;
    bool sd_out = true;
    bool uart_out = true;
    bool oled_out = true;
    bool remember = true;
};

bool parse_args(int argc, char** argv, Args& a) {
    for (int i = 1; i < argc; ++i) {
        const std::string s = argv[i];
        auto value = [&](std::string& out) {
            if (i + 1 >= argc) {
                std::cerr << "battsim_fw_host: " << s << " needs a value\n";
                return false;
            }
            out = argv[++i];
            return true;
        };
        if (s == "--program") {
            if (!value(a.program)) return false;
        } else if (s == "--sd") {
            if (!value(a.sd)) return false;
        } else if (s == "--uart") {
            if (!value(a.uart)) return false;
        } else if (s == "--oled") {
            if (!value(a.oled)) return false;
        } else if (s == "--mavlink") {
            if (!value(a.mavlink)) return false;
        } else if (s == "--buzzer") {
            if (!value(a.buzzer)) return false;
        } else if (s == "--no-hello") {
            a.hello = false;
        } else if (s == "--no-taps") {
            a.taps = false;
        } else if (s == "--no-sd-output") {
            a.sd_out = false;
        } else if (s == "--no-uart-output") {
            a.uart_out = false;
        } else if (s == "--no-oled-output") {
            a.oled_out = false;
        } else if (s == "--forget-averages") {
            a.remember = false;
        } else if (s == "-h" || s == "--help") {
            std::cout << kUsage;
            std::exit(kExitOk);
        } else if (!s.empty() && s[0] == '-') {
            std::cerr << "battsim_fw_host: unknown option " << s << "\n" << kUsage;
            return false;
        } else if (a.log.empty()) {
            a.log = s;
        } else {
            std::cerr << "battsim_fw_host: one log only\n";
            return false;
        }
    }
    if (a.log.empty()) {
        std::cerr << kUsage;
        return false;
    }
    if (a.program != "monitor" && a.program != "logger") {
        std::cerr << "battsim_fw_host: --program: expected monitor or logger, found \"" << a.program << "\"\n";
        return false;
    }
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace battsim::fw;
    Args a;
    if (!parse_args(argc, argv, a)) return kExitUsage;

    if (!a.sd.empty()) {
        struct stat st;
        if (::stat(a.sd.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
            std::cerr << "battsim_fw_host: --sd " << a.sd << ": expected an existing directory (the card)\n";
            return kExitOutputError;
        }
    }
    host::RawLogSource source(a.log);
    if (source.failed()) {
        std::cerr << "battsim_fw_host: " << source.error() << "\n";
        return kExitInputError;
    }
    host::MockClock clock;
    host::LogSensors sensors(source, clock, a.taps);
    host::DirectoryStorage storage(a.sd.empty() ? std::string(".") : a.sd, !a.sd.empty());
    host::TextDisplay display(clock, a.oled);
    host::ScriptedSerial serial;
    host::ScriptedSerial telemetry;  // transmit only, as the device's second UART
    host::RecordingBuzzer buzzer(clock);
    // The host's greeting arrives before the first reading, as when `battsim log` is
    // already waiting when the device boots.
    if (a.hello) serial.feed("hello\n");

    long samples = 0;
    battsim::fw::ReadingCounters counters;
    std::string summary;
    if (a.program == "monitor") {
        // Static: the app holds the whole monitor, as the device keeps it in .bss.
        static MonitorApp app(sensors, clock, storage, display, serial);
        MonitorAppConfig cfg;
        cfg.monitor = battsim_generated::monitor_config();
        cfg.outputs.sd = a.sd_out;
        cfg.outputs.uart = a.uart_out;
        cfg.outputs.display = a.oled_out;
        cfg.remember_averages = a.remember;
        cfg.telemetry = battsim_generated::telemetry_config();
        cfg.outputs.mavlink = !a.mavlink.empty();
        app.attach_telemetry(telemetry);
        if (!a.buzzer.empty()) app.attach_buzzer(buzzer);
        app.begin(cfg);
        while (!sensors.finished()) {
            if (app.step() == MonitorApp::Step::Sample) ++samples;
        }
        app.sync_storage();
        counters = app.counters();
        const MonitorAppState& st = app.state();
        summary = std::string("sd log: ") + (st.log_path[0] ? st.log_path : "none") +
                  (st.averages_loaded ? "; averages read from the card" : "") +
                  "; averages saved " + std::to_string(st.averages_saved) + " times; flights " +
                  std::to_string(st.flights) + "; sd errors " + std::to_string(st.sd_errors);
    } else {
        static LoggerApp app(sensors, clock, display, serial);
        LoggerAppConfig cfg;
        const battsim::core::MonitorConfig mc = battsim_generated::monitor_config();
        cfg.cells_in_series = mc.cells_in_series;
        cfg.shunt = mc.shunt;
        cfg.display = a.oled_out;
        app.begin(cfg);
        while (!sensors.finished()) {
            if (app.step() == LoggerApp::Step::Reading) ++samples;
        }
        counters = app.counters();
        summary = "lines sent " + std::to_string(app.lines_sent()) + "; consumed " +
                  std::to_string(app.consumed_mah()) + " mAh";
    }
    if (source.failed()) {
        std::cerr << "battsim_fw_host: " << source.error() << "\n";
        return kExitInputError;
    }
    int rc = kExitOk;
    if (!storage.close_log()) {
        std::cerr << "battsim_fw_host: writing the SD log under " << a.sd << " failed\n";
        rc = kExitOutputError;
    }
    // What a port sent, to the file named by an option (none: not asked for).
    auto write_port = [&rc](const std::string& path, const std::string& bytes) {
        if (path.empty()) return;
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out << bytes;
        out.close();
        if (!out) {
            std::cerr << "battsim_fw_host: cannot write " << path << "\n";
            rc = kExitOutputError;
        }
    };
    write_port(a.uart, serial.output());
    write_port(a.mavlink, telemetry.output());
    write_port(a.buzzer, buzzer.record());
    if (display.write_failed()) {
        std::cerr << "battsim_fw_host: cannot write " << a.oled << "\n";
        rc = kExitOutputError;
    }
    std::cout << a.log << ": " << a.program << ", " << samples << " readings, " << counters.missed
              << " missed, " << counters.ready_timeouts << " ready timeouts; " << summary << "\n";
    return rc;
}
