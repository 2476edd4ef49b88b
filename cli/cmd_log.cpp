// battsim log --port DEVICE --out FILE.csv: record a battsim device's CSV stream over a
// serial port, surviving disconnects (the library does the work: host/serial/).
#include <csignal>
#include <iostream>
#include <string>

#include "command.h"
#include "common_options.h"
#include "host/serial/serial_logger.h"

namespace battsim {
namespace cli {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_signal(int) { g_stop.store(true); }

struct LogArgs {
    host::serial::SerialLogOptions options;
    bool quiet = false;
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<LogArgs>();
    sub.add_option("--port", a->options.port, "Serial device of the battsim firmware (e.g. /dev/ttyUSB0)")->required();
    sub.add_option("--out", a->options.out_path, "CSV file to write")->required();
    sub.add_option("--baud", a->options.baud, "Baud rate")->capture_default_str();
    sub.add_flag("--append", a->options.append, "Continue an existing file (its header must match the device's)");
    sub.add_option("--max-wait", a->options.max_wait_s,
                   "Stop when the device has been gone this many seconds (default: wait until Ctrl-C)")
        ->check(number_in(0.0, 1.0e7, true));  // 0 had meant "never", as if not given
    sub.add_option("--fsync-interval", a->options.fsync_interval_s, "Seconds between fsyncs of the output")
        ->capture_default_str()
        ->check(number_in(0.0, 1.0e7));
    sub.add_flag("-q,--quiet", a->quiet, "Print only errors and the final count");
    return [a]() -> int {
        host::NamedPath out{"--out", a->options.out_path};
        out.appended = true;  // written in place, new or continued: the file's own permission counts
        if (int rc = check_outputs("battsim log", {{"--port", a->options.port}}, {out})) return rc;
        g_stop.store(false);
        std::signal(SIGINT, on_signal);
        std::signal(SIGTERM, on_signal);
        const bool quiet = a->quiet;
        host::serial::MessageSink sink = [quiet](const std::string& m) {
            if (!quiet) std::cerr << "battsim log: " << m << "\n";
        };
        host::serial::SerialLogStats stats;
        int rc = kExitOk;
        try {
            stats = host::serial::run_serial_logger(a->options, g_stop, sink);
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim log: " << e.what() << "\n";
            return kExitUsage;
        } catch (const host::serial::NotASerialDevice& e) {
            std::cerr << "battsim log: --port " << e.what() << "\n";
            return kExitUsage;
        } catch (const host::serial::HeaderMismatch& e) {
            std::cerr << "battsim log: " << e.what() << "\n";
            return kExitInputError;
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim log: " << e.what() << "\n";
            return kExitOutputError;
        }
        std::string to = a->options.out_path;
        // After a device restart the lines are in parts, each a log of its own.
        for (size_t k = 1; k < stats.files.size(); ++k)
            to += (k + 1 == stats.files.size() ? " and " : ", ") + stats.files[k];
        std::cerr << "battsim log: " << stats.lines_written << " lines written to " << to << " ("
                  << stats.connections << " connections, " << stats.cut_lines << " cut lines dropped, "
                  << stats.corrupt_lines << " corrupt lines dropped";
        if (stats.overlong_lines > 0) std::cerr << ", " << stats.overlong_lines << " over-long lines dropped";
        if (stats.held_dropped > 0) std::cerr << ", " << stats.held_dropped << " lines lost waiting for a header";
        if (stats.restarts > 0)
            std::cerr << ", " << stats.restarts << (stats.restarts == 1 ? " device restart" : " device restarts");
        std::cerr << ")\n";
        if (stats.device_gone && stats.connections == 0) {
            std::cerr << "battsim log: " << a->options.port << " never appeared (expected a serial device, tty)\n";
            rc = kExitInputError;
        }
        return rc;
    };
}

const RegisterCommand reg{{"log", "Record a battsim device's CSV stream from a serial port", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
