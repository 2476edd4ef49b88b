// Host mocks of the firmware's hardware interface, so the application runs on a PC:
// sensors and clock replay a raw predictive-bms log (header-less
// time_ms,bus_v,cell1..cell4,current_ma,shunt_mv[,]), storage is a directory standing in
// for the SD card, the display dumps its text frames, the serial port is a byte script in
// and a byte string out. Host code: the standard library is fine here, but errors are
// reported through failed()/error() rather than thrown, because they surface inside the
// firmware's call stack, which is built without exceptions.
#pragma once
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "app/hardware.h"

namespace battsim {
namespace fw {
namespace host {

// One row of the raw log in the sensors' integer units.
struct LogRow {
    uint64_t time_us = 0;
    PackReading pack;
    TapReading taps;  // cumulative sums of the logged cells 1..3
    long line = 0;
};

// Streams the log; the cells become cumulative taps (tap k = cell 1 + … + cell k, in mV),
// so the firmware's tap differences give back the logged cells 1–3 exactly. Cell 4 is
// then bus − tap 3 as on the device, which differs from the logged cell 4 wherever the
// log's rounded cells do not add up to its rounded bus voltage.
class RawLogSource {
public:
    explicit RawLogSource(const std::string& path);
    bool next(LogRow& out);  // false at the end or on an error (see failed())
    bool failed() const { return !error_.empty(); }
    const std::string& error() const { return error_; }  // "file:line:column: what was expected"
    long rows() const { return rows_; }

private:
    bool fail(long column, const std::string& what);

    std::string path_;
    std::ifstream in_;
    std::string line_;
    long line_no_ = 0;
    long rows_ = 0;
    uint64_t last_time_us_ = 0;
    std::string error_;
};

class MockClock : public Clock {
public:
    uint32_t micros() override { return static_cast<uint32_t>(now_us_); }
    uint32_t millis() override { return static_cast<uint32_t>(now_us_ / 1000u); }
    void sleep_us(uint32_t us) override { now_us_ += us; }
    void set_us(uint64_t t) { now_us_ = t; }
    uint64_t now_us() const { return now_us_; }

private:
    uint64_t now_us_ = 0;
};

// A conversion is "ready" when the log has a next row; the clock jumps to its time stamp,
// so the firmware sees the log's own timing (gaps become missed readings).
class LogSensors : public Sensors {
public:
    // `taps_present` false: a board whose INA3221 does not answer (none fitted, a loose
    // module, a wrong address), as the real driver reports it.
    LogSensors(RawLogSource& source, MockClock& clock, bool taps_present = true)
        : source_(source), clock_(clock), taps_present_(taps_present) {}
    bool begin() override { return true; }
    bool conversion_ready() override;
    bool read_pack(PackReading& out) override;
    bool read_taps(TapReading& out) override;
    bool has_taps() const override { return taps_present_; }
    // True once every row has been read. Looks one row ahead, so the app is not left
    // waiting out a conversion timeout after the last row.
    bool finished() {
        if (!pending_ && !ended_) conversion_ready();
        return !pending_ && ended_;
    }

private:
    RawLogSource& source_;
    MockClock& clock_;
    bool taps_present_;
    LogRow row_;
    bool pending_ = false;
    bool ended_ = false;
};

// A directory as the SD card. Paths are relative to it.
class DirectoryStorage : public Storage {
public:
    explicit DirectoryStorage(std::string root, bool present = true) : root_(std::move(root)), present_(present) {}
    ~DirectoryStorage();
    bool begin() override;
    bool exists(const char* path) override;
    bool make_dir(const char* path) override;
    bool open_log(const char* path) override;
    bool append(const char* data, size_t len) override;
    bool sync() override;
    int read_file(const char* path, char* buf, size_t capacity) override;
    bool write_file(const char* path, const char* data, size_t len) override;
    bool close_log();  // flushes and closes; false if a write failed

private:
    std::string full(const char* path) const { return root_ + "/" + path; }
    std::string root_;
    bool present_;
    std::FILE* log_ = nullptr;
};

// Keeps the current text grid; each show() appends the frame to `path` (if given) with
// the clock's time, so a run leaves a reviewable dump of everything the OLED showed.
class TextDisplay : public Display {
public:
    TextDisplay(MockClock& clock, const std::string& path = std::string());
    bool begin() override { return true; }
    void clear() override;
    void text(uint8_t column, uint8_t row, const char* s) override;
    void show() override;
    std::string frame() const;  // the grid as 6 lines
    long frames() const { return frames_; }
    bool write_failed() const { return write_failed_; }

private:
    MockClock& clock_;
    std::ofstream out_;
    bool to_file_ = false;
    bool write_failed_ = false;
    char grid_[kDisplayRows][kDisplayColumns + 1];
    long frames_ = 0;
};

// Bytes the host "sends" are queued with feed(); what the device writes collects in output().
// Keeps the buzzer's switchings with the mock clock's time: "time_s,on" lines.
class RecordingBuzzer : public Buzzer {
public:
    explicit RecordingBuzzer(const MockClock& clock) : clock_(clock) {}
    void set(bool on) override;
    const std::string& record() const { return record_; }

private:
    const MockClock& clock_;
    std::string record_ = "time_s,on\n";
};

class ScriptedSerial : public SerialPort {
public:
    void feed(const std::string& bytes) { input_ += bytes; }
    int read_byte() override;
    void write(const char* data, size_t len) override { output_.append(data, len); }
    const std::string& output() const { return output_; }
    std::string take_output() {
        std::string s;
        s.swap(output_);
        return s;
    }

private:
    std::string input_;
    size_t read_pos_ = 0;
    std::string output_;
};

}  // namespace host
}  // namespace fw
}  // namespace battsim
