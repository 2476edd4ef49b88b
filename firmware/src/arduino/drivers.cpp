#include "arduino/drivers.h"

#include <ESP8266WiFi.h>
#include <Wire.h>
#include <math.h>
#include <string.h>

#include "app/readings.h"

namespace battsim {
namespace fw {

namespace {

bool i2c_present(uint8_t address) {
    Wire.beginTransmission(address);
    return Wire.endTransmission() == 0;
}

}  // namespace

bool InaSensors::begin() {
    Wire.begin(kSdaPin, kSclPin);
    Wire.setClock(400000);
    if (!ina226_.init()) return false;
    // 2116 µs shunt + 2116 µs bus conversions, averaged over 16: a reading every ~67.7 ms.
    static_assert(kIna226ConversionUs == 2116 && kIna226Averages == 16, "INA226 settings and kIna226PeriodUs agree");
    ina226_.setAverage(AVERAGE_16);
    ina226_.setConversionTime(CONV_TIME_2116);
    ina226_.setMeasureMode(CONTINUOUS);
    ina226_.readAndClearFlags();

    // Taps: bus voltages only (the shunt inputs are shorted), 1100 µs × 16 per channel.
    static_assert(kIna3221ConversionUs == 1100 && kIna3221Averages == 16, "INA3221 settings as documented");
    taps_present_ = i2c_present(INA3221_ADDR41_VCC);
    if (taps_present_) {
        ina3221_.begin(&Wire);
        ina3221_.reset();
        ina3221_.setShuntMeasDisable();
        ina3221_.setBusMeasEnable();
        ina3221_.setBusConversionTime(INA3221_REG_CONF_CT_1100US);
        ina3221_.setAveragingMode(INA3221_REG_CONF_AVG_16);
        ina3221_.setModeContinious();
    }
    return true;
}

bool InaSensors::conversion_ready() {
    // Reading Mask/Enable returns the conversion-ready flag and clears it.
    ina226_.readAndClearFlags();
    return ina226_.convAlert;
}

bool InaSensors::read_pack(PackReading& out) {
    // The library scales the registers by their steps (1.25 mV, 2.5 µV); rounding undoes
    // that exactly, as the steps are whole numbers of our units (125 and 25).
    out.bus_10uv = static_cast<int32_t>(lroundf(ina226_.getBusVoltage_V() * static_cast<float>(kBusUnitsPerVolt)));
    out.shunt_100nv =
        static_cast<int32_t>(lroundf(ina226_.getShuntVoltage_mV() * static_cast<float>(kShuntUnitsPerMillivolt)));
    return true;
}

bool InaSensors::read_taps(TapReading& out) {
    if (!taps_present_) return false;
    static const ina3221_ch_t kChannels[kTapChannels] = {INA3221_CH1, INA3221_CH2, INA3221_CH3};
    for (int k = 0; k < kTapChannels; ++k) {
        // 8 mV steps: whole millivolts.
        out.tap_mv[k] = static_cast<int32_t>(lroundf(ina3221_.getVoltage(kChannels[k]) * 1000.0f));
    }
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
