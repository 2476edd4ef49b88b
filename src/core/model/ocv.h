// Open-circuit voltage of the pack against state of charge, the shape the capacity
// estimator reads the state of charge from. Either a table (per cell, evenly spaced in
// SOC, from a slow discharge or a fit) or, without one, the Tremblay model's no-load
// curve at the rated capacity.
#pragma once
#include "core/model/tremblay.h"

namespace battsim {
namespace core {

constexpr int kOcvTableMaxPoints = 21;

struct OcvTable {
    int points = 0;                            // 0 = no table; else 2..kOcvTableMaxPoints
    float cell_voltage_v[kOcvTableMaxPoints] = {};  // at SOC 0, 1/(n−1), …, 1 (ascending SOC)
};

class OcvCurve {
public:
    void configure(const OcvTable& table, int cells_in_series, const TremblayParams& rated);
    float voltage_v(float soc) const;
    float slope_v_per_soc(float soc) const;  // dOCV/dSOC, ≥ 0
    // SOC at which the curve gives `voltage_v` (bisection; clamped to [0, 1]).
    float soc_at_voltage(float voltage_v) const;
    bool from_table() const { return table_.points >= 2; }

private:
    OcvTable table_;
    int cells_ = 1;
    TremblayModel model_;
};

}  // namespace core
}  // namespace battsim
