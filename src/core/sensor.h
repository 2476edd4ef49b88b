// Sensor conversions shared by the firmware and the host readers, so both turn a
// raw shunt reading into the same current, bit for bit.
#pragma once

namespace battsim {
namespace core {

struct ShuntCalibration {
    // current_ma = shunt_mv / scale_mv_per_10a * 10000 + offset_ma (reference hardware:
    // 200 A / 75 mV shunt on an INA226, calibrated against a clamp meter).
    float offset_ma = -982.8158579f;
    float scale_mv_per_10a = 3.7834625f;
};

inline float current_ma_from_shunt_mv(float shunt_mv, const ShuntCalibration& cal) {
    return (shunt_mv / cal.scale_mv_per_10a) * 10000.0f + cal.offset_ma;
}

}  // namespace core
}  // namespace battsim
