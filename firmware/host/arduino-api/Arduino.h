// Compile-check declarations of the ESP8266 Arduino core (README.md here): only what
// firmware/src/arduino calls. Not an implementation.
#pragma once
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define HIGH 1
#define LOW 0
#define OUTPUT 1

// NodeMCU v2 pin names as GPIO numbers.
static const uint8_t D0 = 16;
static const uint8_t D1 = 5;
static const uint8_t D2 = 4;
static const uint8_t D4 = 2;
static const uint8_t D8 = 15;
static const uint8_t SS = D8;

void pinMode(uint8_t pin, uint8_t mode);
void digitalWrite(uint8_t pin, uint8_t value);
unsigned long micros();
unsigned long millis();
void delay(unsigned long ms);
void delayMicroseconds(unsigned int us);
extern "C" void yield();

class HardwareSerial {
public:
    void begin(unsigned long baud);
    int available();
    int read();
    size_t write(uint8_t byte);
    size_t write(const uint8_t* data, size_t len);
};
extern HardwareSerial Serial;
extern HardwareSerial Serial1;
