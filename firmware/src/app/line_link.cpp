#include "app/line_link.h"

#include <string.h>

namespace battsim {
namespace fw {

uint8_t line_checksum(const char* data, size_t len) {
    uint8_t x = 0;
    for (size_t i = 0; i < len; ++i) x = static_cast<uint8_t>(x ^ static_cast<uint8_t>(data[i]));
    return x;
}

LineLink::Event LineLink::poll() {
    for (;;) {
        const int b = port_.read_byte();
        if (b < 0) return Event::None;
        const char c = static_cast<char>(b);
        if (c == '\r') continue;
        if (c != '\n') {
            // Longer than any command: noise or a wrong baud rate; drop it at its line end.
            if (input_len_ + 1 >= sizeof input_) {
                input_overflow_ = true;
            } else {
                input_[input_len_++] = c;
            }
            continue;
        }
        input_[input_len_] = '\0';
        const bool usable = !input_overflow_ && input_len_ > 0;
        const size_t len = input_len_;
        input_len_ = 0;
        input_overflow_ = false;
        if (!usable) continue;
        if (len == 5 && memcmp(input_, "hello", 5) == 0) {
            connected_ = true;
            port_.write("hello\n", 6);
            return Event::Hello;
        }
        memcpy(command_, input_, len + 1);
        return Event::Command;
    }
}

void LineLink::prompt_if_due(uint32_t now_ms) {
    if (connected_) return;
    if (prompted_ && now_ms - last_prompt_ms_ < 1000u) return;
    prompted_ = true;
    last_prompt_ms_ = now_ms;
    port_.write("BMS\n", 4);
}

void LineLink::send_data(const char* line, size_t len) {
    if (len > 0 && line[len - 1] == '\n') --len;
    static const char kHex[] = "0123456789ABCDEF";
    const uint8_t x = line_checksum(line, len);
    const char tail[4] = {'*', kHex[x >> 4], kHex[x & 0x0F], '\n'};
    port_.write("$", 1);
    port_.write(line, len);
    port_.write(tail, sizeof tail);
}

void LineLink::send_note(const char* text) {
    port_.write("# ", 2);
    port_.write(text, strlen(text));
    port_.write("\n", 1);
}

}  // namespace fw
}  // namespace battsim
