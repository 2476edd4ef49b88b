#include "app/averages_file.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

namespace battsim {
namespace fw {

namespace {

constexpr const char* kMagic = "battsim-averages 1";

// Next line of `text` (without its '\n'); false when none is left or a line is unterminated.
bool next_line(const char* text, size_t len, size_t& pos, const char*& line, size_t& line_len) {
    if (pos >= len) return false;
    const char* start = text + pos;
    const void* nl = memchr(start, '\n', len - pos);
    if (nl == nullptr) return false;
    line = start;
    line_len = static_cast<size_t>(static_cast<const char*>(nl) - start);
    pos += line_len + 1;
    return true;
}

bool parse_float_field(const char* line, size_t line_len, const char* key, float& out) {
    const size_t k = strlen(key);
    if (line_len <= k + 1 || memcmp(line, key, k) != 0 || line[k] != '=') return false;
    char buf[32];
    const size_t n = line_len - k - 1;
    if (n >= sizeof buf) return false;
    memcpy(buf, line + k + 1, n);
    buf[n] = '\0';
    char* end = nullptr;
    const float v = strtof(buf, &end);
    if (end != buf + n || !isfinite(v) || v < 0.0f) return false;
    out = v;
    return true;
}

bool parse_uint_field(const char* line, size_t line_len, const char* key, uint32_t& out) {
    const size_t k = strlen(key);
    if (line_len <= k + 1 || line_len > k + 1 + 9 || memcmp(line, key, k) != 0 || line[k] != '=') return false;
    uint32_t v = 0;
    for (size_t i = k + 1; i < line_len; ++i) {
        if (line[i] < '0' || line[i] > '9') return false;
        v = v * 10u + static_cast<uint32_t>(line[i] - '0');
    }
    out = v;
    return true;
}

}  // namespace

void format_averages(const StoredAverages& a, telemetry::TextBuffer& out) {
    out.clear();
    out.append(kMagic);
    out.appendf("\ncurrent_a=%.9g\npower_w=%.9g\nflights=", static_cast<double>(a.current_a),
                static_cast<double>(a.power_w));
    out.append_uint(a.flights);
    out.append_char('\n');
}

bool parse_averages(const char* text, size_t len, StoredAverages& out) {
    size_t pos = 0;
    const char* line = nullptr;
    size_t n = 0;
    StoredAverages a;
    if (!next_line(text, len, pos, line, n) || n != strlen(kMagic) || memcmp(line, kMagic, n) != 0) return false;
    if (!next_line(text, len, pos, line, n) || !parse_float_field(line, n, "current_a", a.current_a)) return false;
    if (!next_line(text, len, pos, line, n) || !parse_float_field(line, n, "power_w", a.power_w)) return false;
    if (!next_line(text, len, pos, line, n) || !parse_uint_field(line, n, "flights", a.flights)) return false;
    if (pos != len) return false;
    out = a;
    return true;
}

}  // namespace fw
}  // namespace battsim
