#include "host/stats.h"

#include <algorithm>
#include <cmath>

namespace battsim {
namespace host {

double median(std::vector<double> v) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double robust_spread(std::vector<double> v) {
    const size_t n = v.size();
    if (n < 4) return NAN;
    std::sort(v.begin(), v.end());
    auto quartile = [&v, n](double q) {
        const double pos = q * static_cast<double>(n + 1);
        const size_t lo = static_cast<size_t>(pos);  // ≥ 1 for n ≥ 4
        const double frac = pos - static_cast<double>(lo);
        return lo >= n ? v[n - 1] : v[lo - 1] + frac * (v[lo] - v[lo - 1]);
    };
    return (quartile(0.75) - quartile(0.25)) / 1.349;
}

}  // namespace host
}  // namespace battsim
