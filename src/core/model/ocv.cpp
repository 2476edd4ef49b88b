#include "core/model/ocv.h"

#include "core/numeric.h"

namespace battsim {
namespace core {

void OcvCurve::configure(const OcvTable& table, int cells_in_series, const TremblayParams& rated) {
    table_ = table;
    if (table_.points > kOcvTableMaxPoints) table_.points = kOcvTableMaxPoints;
    cells_ = cells_in_series > 0 ? cells_in_series : 1;
    model_.configure(rated);
}

float OcvCurve::voltage_v(float soc) const {
    soc = clampf(soc, 0.0f, 1.0f);
    if (table_.points >= 2) {
        const float x = soc * static_cast<float>(table_.points - 1);
        int k = static_cast<int>(x);
        if (k >= table_.points - 1) k = table_.points - 2;
        const float f = x - static_cast<float>(k);
        const float v = table_.cell_voltage_v[k] + f * (table_.cell_voltage_v[k + 1] - table_.cell_voltage_v[k]);
        return v * static_cast<float>(cells_);
    }
    // No-load Tremblay curve: i = i* = 0.
    return model_.voltage_v((1.0f - soc) * model_.capacity_ah(), 0.0f, 0.0f);
}

float OcvCurve::slope_v_per_soc(float soc) const {
    // Central difference over 1 % of SOC: smooth enough for the filter, exact for tables
    // away from their knots, and the same code for both sources.
    const float h = 0.01f;
    const float lo = clampf(soc - h, 0.0f, 1.0f);
    const float hi = clampf(soc + h, 0.0f, 1.0f);
    if (hi <= lo) return 0.0f;
    return maxf(0.0f, (voltage_v(hi) - voltage_v(lo)) / (hi - lo));
}

float OcvCurve::soc_at_voltage(float v) const {
    float lo = 0.0f;
    float hi = 1.0f;
    if (voltage_v(hi) <= v) return 1.0f;
    if (voltage_v(lo) >= v) return 0.0f;
    for (int n = 0; n < 24; ++n) {
        const float mid = 0.5f * (lo + hi);
        if (voltage_v(mid) < v) lo = mid; else hi = mid;
    }
    return 0.5f * (lo + hi);
}

}  // namespace core
}  // namespace battsim
