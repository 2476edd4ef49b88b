#include "host/serial/line_protocol.h"

namespace battsim {
namespace host {
namespace serial {

uint8_t line_checksum(std::string_view text) {
    uint8_t x = 0;
    for (char c : text) x = static_cast<uint8_t>(x ^ static_cast<uint8_t>(c));
    return x;
}

std::string with_checksum(std::string_view text) {
    static const char kHex[] = "0123456789ABCDEF";
    const uint8_t x = line_checksum(text);
    std::string s = "$";
    s += text;
    s += '*';
    s += kHex[x >> 4];
    s += kHex[x & 0x0F];
    return s;
}

namespace {

int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;  // lower case is not what the device sends: treat as damage
}

}  // namespace

DeviceLine classify_line(std::string_view line) {
    DeviceLine d;
    if (line == "BMS") {
        d.kind = LineKind::Prompt;
        d.text = std::string(line);
        return d;
    }
    if (line == "hello") {
        d.kind = LineKind::Hello;
        d.text = std::string(line);
        return d;
    }
    if (!line.empty() && line[0] == '#') {
        d.kind = LineKind::Note;
        std::string_view t = line.substr(1);
        if (!t.empty() && t[0] == ' ') t.remove_prefix(1);
        d.text = std::string(t);
        return d;
    }
    d.text = std::string(line);
    // Corrupt unless "$...*HH": a fragment lacks the '$', a damaged line fails the sum.
    if (line.size() < 4 || line[0] != '$' || line[line.size() - 3] != '*') return d;
    const int hi = hex_value(line[line.size() - 2]);
    const int lo = hex_value(line[line.size() - 1]);
    const std::string_view body = line.substr(1, line.size() - 4);
    if (hi < 0 || lo < 0 || line_checksum(body) != static_cast<uint8_t>(hi * 16 + lo)) return d;
    d.kind = LineKind::Data;
    d.text = std::string(body);
    return d;
}

void LineSplitter::feed(std::string_view bytes, std::vector<std::string>& lines) {
    for (char c : bytes) {
        if (c == '\n') {
            if (skipping_) {
                skipping_ = false;
            } else {
                if (!pending_.empty() && pending_.back() == '\r') pending_.pop_back();
                lines.push_back(std::move(pending_));
            }
            pending_.clear();
            continue;
        }
        if (skipping_) continue;
        if (pending_.size() >= max_line_) {
            pending_.clear();
            skipping_ = true;
            ++overlong_;
            continue;
        }
        pending_ += c;
    }
}

size_t LineSplitter::discard_partial() {
    const size_t n = pending_.size();
    pending_.clear();
    skipping_ = false;
    return n;
}

DecodedStream decode_device_stream(std::string_view bytes) {
    DecodedStream out;
    LineSplitter splitter;
    std::vector<std::string> lines;
    splitter.feed(bytes, lines);
    out.partial_bytes = splitter.discard_partial();
    bool expect_header = false;
    for (const std::string& l : lines) {
        const DeviceLine d = classify_line(l);
        if (d.kind == LineKind::Hello) {
            expect_header = true;
        } else if (d.kind == LineKind::Corrupt) {
            if (!l.empty()) ++out.corrupt;
        } else if (d.kind == LineKind::Data) {
            if (expect_header) {
                expect_header = false;
                if (!out.csv_lines.empty() && out.csv_lines.front() == d.text) continue;  // repeated header
            } else if (out.csv_lines.empty()) {
                ++out.before_header;
                continue;
            }
            out.csv_lines.push_back(d.text);
        }
    }
    return out;
}

}  // namespace serial
}  // namespace host
}  // namespace battsim
