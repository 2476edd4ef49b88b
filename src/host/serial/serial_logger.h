// `battsim log --port DEVICE --out FILE.csv`: records the CSV a battsim device streams
// (discharge logger or monitor) over a serial port.
//
// Guarantees: the file only ever grows by whole, checksum-verified lines, each appended
// with one write() to an O_APPEND descriptor and fsync'ed at least every fsync interval
// and whenever the link drops; a line cut by a dropped link is discarded, never written
// in part; after the device disappears the port is reopened by path until it comes back
// (a USB re-plug, a udev symlink), the device is greeted again and its header, sent
// again, must match the file's. Lines that arrive before the device has confirmed its
// header on a connection are held and written once it has. A device that restarted (its
// time went back) continues in the next part, "FILE-2.csv", with the same header: every
// file written is a log battsim reads.
#pragma once
#include <atomic>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/serial/serial_port.h"

namespace battsim {
namespace host {
namespace serial {

// The device's header differs from the file's: a different program or cell count.
class HeaderMismatch : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct SerialLogOptions {
    std::string port;
    std::string out_path;
    unsigned baud = 115200;
    bool append = false;           // continue an existing file (repairs a cut last line)
    double max_wait_s = 0.0;       // stop once the device has been gone this long; 0 = never
    double fsync_interval_s = 1.0;
    double hello_interval_s = 1.0; // re-greet until the device answers
    double reopen_interval_s = 0.2;
    size_t max_held_lines = 100000;  // lines held while waiting for the header
};

struct SerialLogStats {
    size_t lines_written = 0;      // data lines, header not counted
    size_t header_written = 0;     // 1 if this run wrote the file's header
    size_t repeated_headers = 0;   // headers re-sent after a greeting, matched and dropped
    size_t corrupt_lines = 0;      // failed the checksum or framing (incl. joined fragments)
    size_t cut_lines = 0;          // unfinished lines dropped when the link went down or at the stop
    size_t overlong_lines = 0;     // longer than the line limit (8 KiB), dropped whole
    size_t connections = 0;
    size_t notes = 0;              // "# ..." lines from the device, passed to the message sink
    size_t held_dropped = 0;       // held lines lost because no header came before the link dropped
    bool repaired_tail = false;    // --append found and removed a cut last line
    bool device_gone = false;      // stopped because of max_wait_s
    // The files written, in order: --out, then a part for each time the device restarted
    // (its first column, the time, went back: "flight-2.csv", "flight-3.csv", ...).
    std::vector<std::string> files;
    size_t restarts = 0;
};

using MessageSink = std::function<void(const std::string&)>;

// Runs until `stop` becomes true or the device has been gone for max_wait_s. Throws
// std::runtime_error for output problems (file exists without append, write or fsync
// failure), HeaderMismatch, std::invalid_argument for a bad baud rate, NotASerialDevice for a
// port that is there but no terminal (before the output is made, unless it is a character
// device: that shows only on opening it).
SerialLogStats run_serial_logger(const SerialLogOptions& options, const std::atomic<bool>& stop,
                                 const MessageSink& message = nullptr);

}  // namespace serial
}  // namespace host
}  // namespace battsim
