// The small hardware interface the firmware application runs on. Everything above it
// (the two programs, formatting, the line protocol) is plain C++ on src/core and runs
// unchanged on the ESP8266 (src/arduino/ drivers) and on the host (host/ CSV mocks).
//
// Readings are integers in units fine enough to hold every sensor step exactly: the
// INA226 bus step is 1.25 mV (125 × 10 µV), its shunt step 2.5 µV (25 × 0.1 µV), the
// INA3221 bus step 8 mV. Integer readings keep cell differences exact and let a logged
// decimal come back as the same float on the host (see readings.h).
#pragma once
#include <stddef.h>
#include <stdint.h>

namespace battsim {
namespace fw {

constexpr int kTapChannels = 3;  // INA3221 channels, wired to the cumulative balance taps

struct PackReading {
    int32_t bus_10uv = 0;     // INA226 bus voltage, 10 µV units
    int32_t shunt_100nv = 0;  // INA226 shunt voltage, 0.1 µV units (positive = discharge)
};

struct TapReading {
    int32_t tap_mv[kTapChannels] = {};  // INA3221 bus voltages: cell 1, cells 1–2, cells 1–3
};

class Sensors {
public:
    // Configures both chips; false if the INA226 does not answer (the taps are optional).
    virtual bool begin() = 0;
    // True once per INA226 conversion (its conversion-ready flag; reading clears it).
    virtual bool conversion_ready() = 0;
    virtual bool read_pack(PackReading& out) = 0;
    virtual bool read_taps(TapReading& out) = 0;
    // False when begin() found no tap chip: its samples carry no cells, and that is no error.
    virtual bool has_taps() const = 0;

protected:
    ~Sensors() = default;  // never deleted through the interface: no heap, no virtual dtor
};

class Clock {
public:
    virtual uint32_t micros() = 0;  // wraps every ~71.6 min; the app extends it to 64 bits
    virtual uint32_t millis() = 0;
    // Lets time pass while polling (the ESP8266 also needs the yield for its Wi-Fi stack).
    virtual void sleep_us(uint32_t us) = 0;

protected:
    ~Clock() = default;
};

class Storage {
public:
    virtual bool begin() = 0;  // false: no card
    virtual bool exists(const char* path) = 0;
    virtual bool make_dir(const char* path) = 0;
    // One append-only log file at a time.
    virtual bool open_log(const char* path) = 0;
    virtual bool append(const char* data, size_t len) = 0;
    virtual bool sync() = 0;  // push buffered log data to the card
    // Small whole files: read returns the length (−1 if missing or unreadable); write
    // replaces the file so that a power cut leaves the old or the new content.
    virtual int read_file(const char* path, char* buf, size_t capacity) = 0;
    virtual bool write_file(const char* path, const char* data, size_t len) = 0;

protected:
    ~Storage() = default;
};

class Display {
public:
    virtual bool begin() = 0;
    // A text grid: kDisplayColumns × kDisplayRows characters on the 128×64 panel.
    virtual void clear() = 0;
    virtual void text(uint8_t column, uint8_t row, const char* s) = 0;
    virtual void show() = 0;

protected:
    ~Display() = default;
};
constexpr uint8_t kDisplayColumns = 21;
constexpr uint8_t kDisplayRows = 6;

// An active buzzer on a GPIO (through a transistor): on or off until told otherwise.
class Buzzer {
public:
    virtual void set(bool on) = 0;

protected:
    ~Buzzer() = default;
};

class SerialPort {
public:
    virtual int read_byte() = 0;  // −1 when nothing is waiting
    virtual void write(const char* data, size_t len) = 0;

protected:
    ~SerialPort() = default;
};

}  // namespace fw
}  // namespace battsim
