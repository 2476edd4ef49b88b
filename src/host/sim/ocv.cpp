#include "host/sim/ocv.h"

#include <cmath>

namespace battsim {
namespace host {
namespace sim {

bool OcvCurve::set_table(const double* soc, const double* voltage_v, int points) {
    n_ = 0;
    if (points < 2 || points > kMaxPoints) return false;
    for (int i = 0; i < points; ++i) {
        if (!std::isfinite(soc[i]) || !std::isfinite(voltage_v[i])) return false;
        if (i > 0 && !(soc[i] > soc[i - 1] && voltage_v[i] > voltage_v[i - 1])) return false;
    }
    for (int i = 0; i < points; ++i) {
        soc_[i] = soc[i];
        v_[i] = voltage_v[i];
    }
    // Fritsch–Carlson: secant slopes, harmonic-mean interior slopes; with strictly rising
    // data every secant is positive, so the harmonic mean keeps the cubic monotone.
    double secant[kMaxPoints] = {};
    for (int i = 0; i + 1 < points; ++i) secant[i] = (v_[i + 1] - v_[i]) / (soc_[i + 1] - soc_[i]);
    slope_[0] = secant[0];
    slope_[points - 1] = secant[points - 2];
    for (int i = 1; i + 1 < points; ++i) {
        const double h0 = soc_[i] - soc_[i - 1], h1 = soc_[i + 1] - soc_[i];
        const double w0 = 2.0 * h1 + h0, w1 = h1 + 2.0 * h0;
        slope_[i] = (w0 + w1) / (w0 / secant[i - 1] + w1 / secant[i]);
    }
    n_ = points;
    return true;
}

const OcvCurve& OcvCurve::generic_lipo() {
    static const OcvCurve curve = [] {
        // Generic LiPo rest voltages, every 5 % SOC from empty to full.
        static const double v[21] = {3.300, 3.550, 3.650, 3.690, 3.715, 3.735, 3.750, 3.765, 3.780, 3.795, 3.810,
                                     3.830, 3.850, 3.875, 3.900, 3.930, 3.960, 3.995, 4.035, 4.090, 4.200};
        double soc[21];
        for (int i = 0; i < 21; ++i) soc[i] = 0.05 * i;
        OcvCurve c;
        c.set_table(soc, v, 21);
        return c;
    }();
    return curve;
}

double OcvCurve::voltage_v(double soc) const {
    if (n_ < 2) return 0.0;
    if (soc <= soc_[0]) return v_[0] + empty_slope_v * (soc - soc_[0]);
    if (soc >= soc_[n_ - 1]) return v_[n_ - 1] + slope_[n_ - 1] * (soc - soc_[n_ - 1]);
    // Binary search: the table is small, and this stays O(log n) for custom tables.
    int lo = 0, hi = n_ - 1;
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (soc_[mid] <= soc) lo = mid;
        else hi = mid;
    }
    const double h = soc_[hi] - soc_[lo];
    const double t = (soc - soc_[lo]) / h;
    const double t2 = t * t, t3 = t2 * t;
    const double h00 = 2.0 * t3 - 3.0 * t2 + 1.0, h10 = t3 - 2.0 * t2 + t;
    const double h01 = -2.0 * t3 + 3.0 * t2, h11 = t3 - t2;
    return h00 * v_[lo] + h10 * h * slope_[lo] + h01 * v_[hi] + h11 * h * slope_[hi];
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
