// The real hardware behind the firmware's interface (app/hardware.h), on a NodeMCU
// ESP8266: INA226 (pack bus and 200 A / 75 mV shunt) and INA3221 (balance taps) on I²C
// (their register-level driver is app/ina_sensors.h, on the Wire bus below), an SSD1306
// 128×64 OLED on the same bus, an SD card on SPI. This layer is kept thin: pass bytes.
// Wiring: docs/firmware.md.
#pragma once
#include <Arduino.h>
#include <SdFat.h>
#include <U8g2lib.h>

#include "app/hardware.h"
#include "app/ina_sensors.h"

namespace battsim {
namespace fw {

// NodeMCU pins: I²C on D2 (SDA, GPIO4) / D1 (SCL, GPIO5), SD chip select on D8 (GPIO15).
constexpr uint8_t kSdaPin = D2;
constexpr uint8_t kSclPin = D1;
constexpr uint8_t kSdChipSelect = D8;
constexpr uint8_t kOledAddress = 0x3C;

// The ESP8266 core's Wire at 400 kHz; a read is good only when both bytes arrived.
class WireBus : public I2cBus {
public:
    void begin();
    bool write_register(uint8_t address, uint8_t reg, uint16_t value) override;
    bool read_register(uint8_t address, uint8_t reg, uint16_t& value) override;
};

class ArduinoClock : public Clock {
public:
    uint32_t micros() override { return ::micros(); }
    uint32_t millis() override { return ::millis(); }
    void sleep_us(uint32_t us) override;
};

class SdStorage : public Storage {
public:
    bool begin() override;
    bool exists(const char* path) override { return sd_.exists(path); }
    bool make_dir(const char* path) override { return sd_.mkdir(path); }
    bool open_log(const char* path) override;
    bool append(const char* data, size_t len) override;
    bool sync() override { return log_.sync(); }
    int read_file(const char* path, char* buf, size_t capacity) override;
    bool write_file(const char* path, const char* data, size_t len) override;

private:
    int read_one(const char* path, char* buf, size_t capacity);
    SdFs sd_;
    FsFile log_;
};

class OledDisplay : public Display {
public:
    bool begin() override;
    void clear() override { oled_.clearBuffer(); }
    void text(uint8_t column, uint8_t row, const char* s) override;
    void show() override { oled_.sendBuffer(); }

private:
    // Full frame buffer (1 KiB): one sendBuffer() per page, no flicker.
    U8G2_SSD1306_128X64_NONAME_F_HW_I2C oled_{U8G2_R0, U8X8_PIN_NONE};
};

class UartPort : public SerialPort {
public:
    int read_byte() override { return Serial.available() > 0 ? Serial.read() : -1; }
    void write(const char* data, size_t len) override {
        Serial.write(reinterpret_cast<const uint8_t*>(data), len);
    }
};

// The ESP8266's second UART: transmit only, on D4 (GPIO2), for the MAVLink telemetry to an
// autopilot's or a telemetry radio's RX. (D4 also drives the NodeMCU's blue LED, which
// flickers with the traffic.)
class TelemetryUartPort : public SerialPort {
public:
    int read_byte() override { return -1; }
    void write(const char* data, size_t len) override {
        Serial1.write(reinterpret_cast<const uint8_t*>(data), len);
    }
};

// An active 3.3 V buzzer on D0 (GPIO16) through an NPN transistor (the pin gives 12 mA at
// most). GPIO16 has no role at boot, unlike D3/D4/D8.
class GpioBuzzer : public Buzzer {
public:
    void begin() {
        pinMode(kBuzzerPin, OUTPUT);
        digitalWrite(kBuzzerPin, LOW);
    }
    void set(bool on) override { digitalWrite(kBuzzerPin, on ? HIGH : LOW); }

private:
    static constexpr uint8_t kBuzzerPin = D0;
};

// Wi-Fi off: it is not used, and its current spikes show up on the shunt.
void radio_off();

}  // namespace fw
}  // namespace battsim
