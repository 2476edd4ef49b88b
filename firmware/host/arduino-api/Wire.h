// Compile-check declarations of the ESP8266 core's I²C master (README.md here).
#pragma once
#include <stddef.h>
#include <stdint.h>

class TwoWire {
public:
    void begin(int sda_pin, int scl_pin);
    void setClock(uint32_t frequency_hz);
    void beginTransmission(uint8_t address);
    void beginTransmission(int address);
    uint8_t endTransmission();  // 0: acknowledged
    uint8_t endTransmission(uint8_t send_stop);
    size_t write(uint8_t byte);
    size_t write(const uint8_t* data, size_t len);
    uint8_t requestFrom(uint8_t address, uint8_t count);  // bytes received
    uint8_t requestFrom(int address, int count);
    int read();  // -1 when none is left
};
extern TwoWire Wire;
