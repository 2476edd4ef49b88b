// A whole field as a finite number: no trailing text, no NaN or infinity, no overflow.
#pragma once
#include <charconv>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace battsim {
namespace host {

inline bool parse_finite_number(const std::string& text, double* out) {
    size_t used = 0;
    double v = 0;
    try {
        v = std::stod(text, &used);
    } catch (const std::exception&) {
        return false;  // not a number, or beyond a double's range
    }
    if (used != text.size() || !std::isfinite(v)) return false;
    *out = v;
    return true;
}

// A whole field as a whole number 0 .. 2^64 − 1: digits only (no sign), no overflow.
inline bool parse_whole_number(const std::string& text, std::uint64_t* out) {
    std::uint64_t v = 0;
    const char* end = text.data() + text.size();
    const std::from_chars_result r = std::from_chars(text.data(), end, v);
    if (text.empty() || r.ec != std::errc() || r.ptr != end) return false;
    *out = v;
    return true;
}

}  // namespace host
}  // namespace battsim
