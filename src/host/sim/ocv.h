// Open-circuit voltage of one LiPo cell against its state of charge: a table read with a
// monotone cubic (Fritsch–Carlson), so the curve is smooth and never turns back.
// The built-in table is a generic LiPo shape written for this simulator (3.30 V empty,
// 4.20 V full, a flat middle and steeper ends), not a measurement of any one product.
#pragma once

namespace battsim {
namespace host {
namespace sim {

class OcvCurve {
public:
    static constexpr int kMaxPoints = 41;

    // soc strictly increasing, voltage strictly increasing, 2..kMaxPoints points. Returns
    // false (and leaves the curve empty) if the table breaks those rules.
    bool set_table(const double* soc, const double* voltage_v, int points);
    // The generic LiPo table: 21 points, every 5 % of state of charge.
    static const OcvCurve& generic_lipo();

    // Below the first point the voltage falls linearly with `empty_slope_v` per unit of
    // state of charge (a cell past empty collapses); above the last it keeps the last
    // segment's slope.
    double voltage_v(double soc) const;
    int points() const { return n_; }
    double soc_at(int i) const { return soc_[i]; }
    double voltage_at(int i) const { return v_[i]; }

    double empty_slope_v = 8.0;

private:
    int n_ = 0;
    double soc_[kMaxPoints] = {};
    double v_[kMaxPoints] = {};
    double slope_[kMaxPoints] = {};  // dV/dSOC at each point
};

}  // namespace sim
}  // namespace host
}  // namespace battsim
