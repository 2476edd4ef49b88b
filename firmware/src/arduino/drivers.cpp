#include "arduino/drivers.h"

#include <ESP8266WiFi.h>
#include <Wire.h>
#include <string.h>

namespace battsim {
namespace fw {

namespace {

bool i2c_present(uint8_t address) {
    Wire.beginTransmission(address);
    return Wire.endTransmission() == 0;
}

}  // namespace

void WireBus::begin() {
    Wire.begin(kSdaPin, kSclPin);
    Wire.setClock(400000);
}

bool WireBus::write_register(uint8_t address, uint8_t reg, uint16_t value) {
    Wire.beginTransmission(address);
    Wire.write(reg);
    Wire.write(static_cast<uint8_t>(value >> 8));
    Wire.write(static_cast<uint8_t>(value & 0xFFu));
    return Wire.endTransmission() == 0;
}

bool WireBus::read_register(uint8_t address, uint8_t reg, uint16_t& value) {
    Wire.beginTransmission(address);
    Wire.write(reg);
    if (Wire.endTransmission() != 0) return false;  // no acknowledge: absent or bus fault
    if (Wire.requestFrom(address, static_cast<uint8_t>(2)) != 2) return false;
    const int high = Wire.read();
    const int low = Wire.read();
    if (high < 0 || low < 0) return false;
    value = static_cast<uint16_t>((high << 8) | low);
    return true;
}

void ArduinoClock::sleep_us(uint32_t us) {
    if (us >= 1000u) {
        delay(us / 1000u);  // delay() yields to the system
    } else {
        delayMicroseconds(us);
        yield();
    }
}

bool SdStorage::begin() { return sd_.begin(SdSpiConfig(kSdChipSelect, SHARED_SPI, SD_SCK_MHZ(20))); }

bool SdStorage::open_log(const char* path) {
    if (log_.isOpen()) log_.close();
    return log_.open(path, O_WRONLY | O_CREAT | O_APPEND);
}

bool SdStorage::append(const char* data, size_t len) {
    // SdFat buffers a 512-byte sector; the card is written when it fills or on sync().
    return log_.write(data, len) == len;
}

int SdStorage::read_one(const char* path, char* buf, size_t capacity) {
    FsFile f;
    if (!f.open(path, O_RDONLY)) return -1;
    const int n = f.read(buf, capacity);
    const bool more = f.available() > 0;
    f.close();
    return (n < 0 || more) ? -1 : n;
}

int SdStorage::read_file(const char* path, char* buf, size_t capacity) {
    const int n = read_one(path, buf, capacity);
    if (n >= 0) return n;
    // FAT cannot rename over a file: write_file() removes the old one first, so a power
    // cut in between leaves only the (complete, synced) temporary.
    char tmp[48];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    return read_one(tmp, buf, capacity);
}

bool SdStorage::write_file(const char* path, const char* data, size_t len) {
    char tmp[48];
    if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= static_cast<int>(sizeof tmp)) return false;
    FsFile f;
    if (!f.open(tmp, O_WRONLY | O_CREAT | O_TRUNC)) return false;
    const bool ok = f.write(data, len) == len && f.sync();
    f.close();
    if (!ok) return false;
    if (sd_.exists(path) && !sd_.remove(path)) return false;
    return sd_.rename(tmp, path);
}

bool OledDisplay::begin() {
    if (!i2c_present(kOledAddress)) return false;
    oled_.begin();
    oled_.setFont(u8g2_font_6x10_tf);  // 6×10 px: 21 columns × 6 rows on 128×64
    return true;
}

void OledDisplay::text(uint8_t column, uint8_t row, const char* s) {
    oled_.drawStr(static_cast<u8g2_uint_t>(column * 6), static_cast<u8g2_uint_t>(row * 10 + 9), s);
}

void radio_off() {
    WiFi.mode(WIFI_OFF);
    WiFi.forceSleepBegin();
}

}  // namespace fw
}  // namespace battsim
