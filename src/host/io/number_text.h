// A whole field as a finite number: no trailing text, no NaN or infinity, no overflow.
#pragma once
#include <cmath>
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

}  // namespace host
}  // namespace battsim
