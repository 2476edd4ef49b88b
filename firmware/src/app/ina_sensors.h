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
#include "app/readings.h"

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

// The fields decoded back, against the timing constants the firmware's reading loop and
// docs use (readings.h): averaging code 010 = 16, conversion code 101 = 2116 µs, 100 = 1100 µs.
constexpr uint32_t kAveragesByCode[8] = {1, 4, 16, 64, 128, 256, 512, 1024};
constexpr uint32_t kConversionUsByCode[8] = {140, 204, 332, 588, 1100, 2116, 4156, 8244};
static_assert(kAveragesByCode[(kIna226Config >> 9) & 7u] == kIna226Averages, "INA226 averaging and kIna226Averages");
static_assert(kConversionUsByCode[(kIna226Config >> 6) & 7u] == kIna226ConversionUs &&
                  kConversionUsByCode[(kIna226Config >> 3) & 7u] == kIna226ConversionUs,
              "INA226 conversion times and kIna226ConversionUs");
static_assert(kAveragesByCode[(kIna3221Config >> 9) & 7u] == kIna3221Averages, "INA3221 averaging");
static_assert(kConversionUsByCode[(kIna3221Config >> 6) & 7u] == kIna3221ConversionUs, "INA3221 conversion time");
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
    // The taps converted since the last call, which then starts the next conversion; false
    // on a failed read or a conversion not yet done (the sample goes without cells). An
    // unfinished conversion is left to finish, and restarted only if it is still unfinished
    // at the next call (a chip reset, or a lost start). Without a tap chip, it is looked for
    // again every kTapRetryReadings calls.
    bool read_taps(TapReading& out) override;
    bool has_taps() const override { return taps_present_; }
    static constexpr uint16_t kTapRetryReadings = 128;  // ~9 s at 67.7 ms
    // Every this many pack readings the INA226's configuration is read back and written
    // again if it differs: a brown-out resets the chip to its defaults (a reading every
    // 2.2 ms, unaveraged), which no timeout would notice.
    static constexpr uint16_t kConfigCheckReadings = 256;  // ~17 s

private:
    bool identify(uint8_t address, uint16_t die_id);
    bool start_taps();

    I2cBus& bus_;
    uint8_t ina226_;
    uint8_t ina3221_;
    bool taps_present_ = false;
    bool tap_pending_ = false;  // the last call found the conversion unfinished
    uint16_t tap_retry_ = 0;
    uint16_t config_check_ = 0;
};

}  // namespace fw
}  // namespace battsim
