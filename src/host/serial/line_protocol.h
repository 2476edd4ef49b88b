// Host side of the firmware's serial line protocol (firmware/src/app/line_link.h is the
// device side; docs/firmware.md describes both):
//   device → host: "BMS" (waiting for a host), "hello" (greeting answered),
//                  "# text" (a note for people), "$CSV*HH" (data: HH = XOR of the CSV bytes
//                  in two upper-case hex digits; the '$' marks a line start, so a line
//                  joined half-way after a reconnect never passes for a whole one)
//   host → device: "hello" (start, or restart after a reconnect: the device answers and
//                  sends its header again), commands.
// Line ends may be "\n" or "\r\n".
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace battsim {
namespace host {
namespace serial {

uint8_t line_checksum(std::string_view text);
// "$text*HH" for `text`.
std::string with_checksum(std::string_view text);

enum class LineKind { Prompt, Hello, Note, Data, Corrupt };

struct DeviceLine {
    LineKind kind = LineKind::Corrupt;
    std::string text;  // Data: the CSV without its checksum; Note: without "# "; else the line
};

// Classifies one complete line (without its line end).
DeviceLine classify_line(std::string_view line);

// Cuts a byte stream into complete lines. Bytes after the last line end stay pending
// until more arrive; discard_partial() drops them (the link broke mid-line).
class LineSplitter {
public:
    explicit LineSplitter(size_t max_line = 8192) : max_line_(max_line) {}
    // Appends `bytes` and moves every completed line (without "\r\n") to `lines`. A line
    // longer than max_line is dropped whole and counted in overlong().
    void feed(std::string_view bytes, std::vector<std::string>& lines);
    // Returns how many bytes were pending (0 if none).
    size_t discard_partial();
    size_t overlong() const { return overlong_; }

private:
    size_t max_line_;
    std::string pending_;
    bool skipping_ = false;  // inside an overlong line: drop up to its end
    size_t overlong_ = 0;
};

// Decodes a recorded device stream (e.g. battsim_fw_host --uart) into the CSV lines
// `battsim log` would write: data lines without checksums, in order; prompts, greetings
// and notes dropped; corrupt lines counted. A repeated header (after each hello) is
// written once.
struct DecodedStream {
    std::vector<std::string> csv_lines;  // header first
    size_t corrupt = 0;
    size_t before_header = 0;  // data lines before any header: dropped
    size_t partial_bytes = 0;  // an unterminated last line
};
DecodedStream decode_device_stream(std::string_view bytes);

}  // namespace serial
}  // namespace host
}  // namespace battsim
