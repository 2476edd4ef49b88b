#include "app/ina_sensors.h"

namespace battsim {
namespace fw {

bool InaSensors::identify(uint8_t address, uint16_t die_id) {
    uint16_t maker = 0, die = 0;
    return bus_.read_register(address, ina::kRegManufacturerId, maker) && maker == ina::kManufacturerTi &&
           bus_.read_register(address, ina::kRegDieId, die) && die == die_id;
}

bool InaSensors::begin() {
    taps_present_ = false;
    config_check_ = 0;
    if (!identify(ina226_, ina::kDieIna226)) return false;
    // Writing the configuration also restarts the averaging and clears the ready flag.
    uint16_t config = 0;
    if (!bus_.write_register(ina226_, ina::kRegConfig, ina::kIna226Config) ||
        !bus_.read_register(ina226_, ina::kRegConfig, config) || config != ina::kIna226Config)
        return false;
    // The first tap conversion starts now; each tap reading starts the next one.
    start_taps();
    return true;
}

bool InaSensors::start_taps() {
    tap_retry_ = 0;
    tap_pending_ = false;
    taps_present_ = identify(ina3221_, ina::kDieIna3221) &&
                    bus_.write_register(ina3221_, ina::kRegConfig, ina::kIna3221Config);
    return taps_present_;
}

bool InaSensors::conversion_ready() {
    uint16_t flags = 0;
    return bus_.read_register(ina226_, ina::kIna226RegMaskEnable, flags) && (flags & ina::kIna226ConversionReady) != 0;
}

bool InaSensors::read_pack(PackReading& out) {
    if (++config_check_ >= kConfigCheckReadings) {
        config_check_ = 0;
        uint16_t config = 0;
        if (bus_.read_register(ina226_, ina::kRegConfig, config) && config != ina::kIna226Config)
            bus_.write_register(ina226_, ina::kRegConfig, ina::kIna226Config);
    }
    uint16_t shunt = 0, bus = 0;
    if (!bus_.read_register(ina226_, ina::kIna226RegShunt, shunt) || !bus_.read_register(ina226_, ina::kIna226RegBus, bus))
        return false;
    if (bus & 0x8000u) return false;  // always 0 on a real reading: the bus garbled it
    // 1.25 mV = 125 × 10 µV; 2.5 µV = 25 × 0.1 µV (hardware.h's units hold each step exactly).
    out.bus_10uv = static_cast<int32_t>(bus) * 125;
    out.shunt_100nv = static_cast<int32_t>(static_cast<int16_t>(shunt)) * 25;
    return true;
}

bool InaSensors::read_taps(TapReading& out) {
    if (!taps_present_) {
        if (++tap_retry_ >= kTapRetryReadings) start_taps();  // plugged in, or a boot-time glitch
        return false;
    }
    uint16_t flags = 0;
    if (!bus_.read_register(ina3221_, ina::kIna3221RegMaskEnable, flags)) {
        bus_.write_register(ina3221_, ina::kRegConfig, ina::kIna3221Config);  // for the next reading
        return false;
    }
    if ((flags & ina::kIna3221ConversionReady) == 0) {
        // Still converting (a reading that came early): let it finish. Unfinished twice in a
        // row, it was lost (the chip reset): start another.
        if (tap_pending_) bus_.write_register(ina3221_, ina::kRegConfig, ina::kIna3221Config);
        tap_pending_ = !tap_pending_;
        return false;
    }
    tap_pending_ = false;
    bool ok = true;
    for (int k = 0; ok && k < kTapChannels; ++k) {
        uint16_t raw = 0;
        ok = bus_.read_register(ina3221_, ina::kIna3221RegBus[k], raw);
        // Bits 15:3 hold the value in 8 mV steps, so the register as a signed number with its
        // three low bits cleared is the voltage in millivolts.
        out.tap_mv[k] = static_cast<int32_t>(static_cast<int16_t>(raw & 0xFFF8u));
    }
    // The next conversion, whatever this one gave: a failed read must not stop the taps.
    bus_.write_register(ina3221_, ina::kRegConfig, ina::kIna3221Config);
    return ok;
}

}  // namespace fw
}  // namespace battsim
