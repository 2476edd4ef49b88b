// Compile-check declarations of olikraus/U8g2's C++ interface (README.md here): the
// SSD1306 128×64 display with a full frame buffer on hardware I²C.
#pragma once
#include <stdint.h>

typedef uint16_t u8g2_uint_t;  // 16-bit coordinates, as U8g2 builds for the ESP8266
struct u8g2_cb_struct;
extern "C" const u8g2_cb_struct u8g2_cb_r0;
#define U8G2_R0 (&u8g2_cb_r0)
#define U8X8_PIN_NONE 255
extern "C" const uint8_t u8g2_font_6x10_tf[];

class U8G2 {
public:
    bool begin();
    void clearBuffer();
    void sendBuffer();
    void setFont(const uint8_t* font);
    u8g2_uint_t drawStr(u8g2_uint_t x, u8g2_uint_t y, const char* s);
};

class U8G2_SSD1306_128X64_NONAME_F_HW_I2C : public U8G2 {
public:
    explicit U8G2_SSD1306_128X64_NONAME_F_HW_I2C(const u8g2_cb_struct* rotation, uint8_t reset_pin = U8X8_PIN_NONE,
                                                  uint8_t clock_pin = U8X8_PIN_NONE, uint8_t data_pin = U8X8_PIN_NONE);
};
