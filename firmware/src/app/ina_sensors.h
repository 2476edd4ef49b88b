// The INA226 (pack bus and shunt) and INA3221 (balance taps) at register level, over a small
// I²C interface, written from TI's data sheets (INA226: SBOS547; INA3221: SBOS576) rather
// than on third-party drivers: every register read is checked (a library that returns 0 on
// a failed read makes a glitch a 0 V sample), the chips are identified by their ID
// registers (an INA3221 strapped to the INA226's address is refused, not read as a pack),
// and the taps are converted once per pack reading instead of free-running beside it.
// Plain C++ on the I2cBus interface, so the host tests run it against register fakes; the
// ESP8266 build passes Wire (src/arduino/drivers.h).
#pragma once
#include <stdint.h>

#include "app/hardware.h"

namespace battsim {
namespace fw {

// 16-bit registers behind an 8-bit pointer, most significant byte first (both chips).
class I2cBus {
public:
    virtual bool write_register(uint8_t address, uint8_t reg, uint16_t value) = 0;
    virtual bool read_register(uint8_t address, uint8_t reg, uint16_t& value) = 0;

protected:
    ~I2cBus() = default;
};

namespace ina {
// Both chips: manufacturer ID "TI", and their die IDs.
constexpr uint8_t kRegManufacturerId = 0xFE;
constexpr uint8_t kRegDieId = 0xFF;
constexpr uint16_t kManufacturerTi = 0x5449;
constexpr uint16_t kDieIna226 = 0x2260;
constexpr uint16_t kDieIna3221 = 0x3220;
constexpr uint8_t kRegConfig = 0x00;

// INA226: configuration = bit 14 (reads 1) | AVG (11:9) | VBUSCT (8:6) | VSHCT (5:3) | MODE
// (2:0). AVG 010 = 16 averages; CT 101 = 2.116 ms; MODE 111 = shunt and bus, continuous.
constexpr uint8_t kIna226RegShunt = 0x01;      // signed, 2.5 µV per step
constexpr uint8_t kIna226RegBus = 0x02;        // 1.25 mV per step, bit 15 always 0
constexpr uint8_t kIna226RegMaskEnable = 0x06;  // bit 3: conversion ready (cleared by reading)
constexpr uint16_t kIna226ConversionReady = 1u << 3;
constexpr uint16_t kIna226Config = 0x4000 | (0x2u << 9) | (0x5u << 6) | (0x5u << 3) | 0x7u;  // 0x456F

// INA3221: configuration = channel enables (14:12) | AVG (11:9) | VBUSCT (8:6) | VSHCT (5:3) |
// MODE (2:0). All three channels; 16 averages; 1.1 ms (100); MODE 010 = bus voltages,
// single-shot: writing the register starts one conversion of the three channels
// (3 × 16 × 1.1 ms = 52.8 ms, inside the INA226's 67.7 ms).
constexpr uint8_t kIna3221RegBus[3] = {0x02, 0x04, 0x06};  // bits 15:3, signed, 8 mV per step
constexpr uint8_t kIna3221RegMaskEnable = 0x0F;             // bit 0: conversion ready
constexpr uint16_t kIna3221ConversionReady = 1u << 0;
constexpr uint16_t kIna3221Config = (0x7u << 12) | (0x2u << 9) | (0x4u << 6) | (0x4u << 3) | 0x2u;  // 0x7522
}  // namespace ina

class InaSensors : public Sensors {
public:
    // Addresses: the INA226 with A0, A1 to GND (0x40), the INA3221 with A0 to VCC (0x41).
    explicit InaSensors(I2cBus& bus, uint8_t ina226_address = 0x40, uint8_t ina3221_address = 0x41)
        : bus_(bus), ina226_(ina226_address), ina3221_(ina3221_address) {}

    // False unless an INA226 answers at its address with its IDs and takes the
    // configuration; the INA3221 is optional (has_taps()).
    bool begin() override;
    bool conversion_ready() override;
    bool read_pack(PackReading& out) override;
    // The taps converted since the last call (each call starts the next conversion); false
    // on a failed read or a conversion not yet done, so the sample goes without cells.
    bool read_taps(TapReading& out) override;
    bool has_taps() const override { return taps_present_; }

private:
    bool identify(uint8_t address, uint16_t die_id);

    I2cBus& bus_;
    uint8_t ina226_;
    uint8_t ina3221_;
    bool taps_present_ = false;
};

}  // namespace fw
}  // namespace battsim
