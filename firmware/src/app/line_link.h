// Device side of the serial line protocol that `battsim log` speaks (docs/firmware.md):
//  - until a host has said "hello", the device prints "BMS" once a second and sends no data;
//  - on "hello" it answers "hello" and (re)sends its CSV header; a host that reconnects
//    says hello again, gets the header again and drops it as a repeat;
//  - every CSV line is sent as "$CSV*HH": HH is the XOR of the CSV's bytes in two
//    upper-case hex digits, and the '$' marks the line start, so the host keeps only lines
//    that arrived whole, even when it joins the stream in the middle of one;
//  - lines starting with '#' are notes for people, never data;
//  - other lines from the host are commands ("out sd off", "status", ...).
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "app/hardware.h"

namespace battsim {
namespace fw {

uint8_t line_checksum(const char* data, size_t len);

class LineLink {
public:
    enum class Event { None, Hello, Command };

    explicit LineLink(SerialPort& port) : port_(port) {}

    // Reads what the host sent. Hello: the caller answers with its header (after this has
    // already sent "hello"). Command: command() holds the line until the next poll().
    Event poll();
    const char* command() const { return command_; }
    bool connected() const { return connected_; }

    // "BMS" once a second until the first hello.
    void prompt_if_due(uint32_t now_ms);
    // A CSV line (a trailing '\n' is ignored) framed as "$CSV*HH\n".
    void send_data(const char* line, size_t len);
    // "# text" for people.
    void send_note(const char* text);

private:
    SerialPort& port_;
    bool connected_ = false;
    bool prompted_ = false;
    uint32_t last_prompt_ms_ = 0;
    char input_[48] = {};
    size_t input_len_ = 0;
    bool input_overflow_ = false;
    char command_[48] = {};
};

}  // namespace fw
}  // namespace battsim
