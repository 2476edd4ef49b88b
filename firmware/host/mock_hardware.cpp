#include "mock_hardware.h"

#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

namespace battsim {
namespace fw {
namespace host {

namespace {

// A plain decimal ("-12.34", "+5", "0.5") as value × 10^decimals, exactly: no float in
// between, so a logged "16.66" becomes 1666000 ten-microvolt units and nothing else.
// Returns an empty string on success, else what was expected.
std::string parse_fixed(const std::string& text, int decimals, int64_t limit, int64_t& out) {
    size_t i = 0;
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    size_t end = text.size();
    while (end > i && (text[end - 1] == ' ' || text[end - 1] == '\t')) --end;
    bool negative = false;
    if (i < end && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
    int64_t v = 0;
    int digits = 0;
    int frac = -1;  // digits after the point; −1 = no point yet
    for (; i < end; ++i) {
        const char c = text[i];
        if (c == '.' && frac < 0) {
            frac = 0;
            continue;
        }
        if (c < '0' || c > '9') return "expected a plain decimal number, found \"" + text + "\"";
        ++digits;
        if (frac >= 0) {
            if (frac >= decimals) {
                if (c != '0') {
                    return "expected at most " + std::to_string(decimals) + " decimals (the sensor's resolution), found \"" +
                           text + "\"";
                }
                continue;
            }
            ++frac;
        }
        v = v * 10 + (c - '0');
        if (v > limit) return "expected a number within the sensor's range, found \"" + text + "\"";
    }
    if (digits == 0) return "expected a number, found \"" + text + "\"";
    for (int k = frac < 0 ? 0 : frac; k < decimals; ++k) {
        v *= 10;
        if (v > limit) return "expected a number within the sensor's range, found \"" + text + "\"";
    }
    out = negative ? -v : v;
    return std::string();
}

void split(const std::string& line, std::vector<std::string>& fields) {
    fields.clear();
    size_t start = 0;
    for (;;) {
        const size_t comma = line.find(',', start);
        if (comma == std::string::npos) {
            fields.push_back(line.substr(start));
            return;
        }
        fields.push_back(line.substr(start, comma - start));
        start = comma + 1;
    }
}

// Integer units must stay below 2^24 so that their float conversion is exact.
constexpr int64_t kFloatExactLimit = (int64_t{1} << 24) - 1;

}  // namespace

RawLogSource::RawLogSource(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) error_ = path + ": cannot open the log";
}

bool RawLogSource::fail(long column, const std::string& what) {
    error_ = path_ + ":" + std::to_string(line_no_) + (column > 0 ? ":" + std::to_string(column) : std::string()) +
             ": " + what;
    return false;
}

bool RawLogSource::next(LogRow& out) {
    if (failed()) return false;
    std::vector<std::string> f;
    while (std::getline(in_, line_)) {
        ++line_no_;
        if (!line_.empty() && line_.back() == '\r') line_.pop_back();
        if (line_.find_first_not_of(" \t") == std::string::npos) continue;
        split(line_, f);
        if (f.size() == 9 && f[8].find_first_not_of(" \t") == std::string::npos) f.pop_back();
        if (f.size() != 8) {
            return fail(0, "expected 8 fields (9 with a trailing comma): time_ms, bus_voltage_v, cell1_v..cell4_v, "
                           "current_ma, shunt_mv; found " + std::to_string(f.size()));
        }
        int64_t v = 0;
        std::string why = parse_fixed(f[0], 3, INT64_MAX / 10, v);
        if (!why.empty()) return fail(1, why);
        if (v < 0) return fail(1, "expected a time that is not negative, found \"" + f[0] + "\"");
        const uint64_t t = static_cast<uint64_t>(v);
        if (rows_ > 0 && t < last_time_us_) return fail(1, "time goes backwards");
        out.time_us = t;
        why = parse_fixed(f[1], 5, kFloatExactLimit, v);
        if (!why.empty()) return fail(2, why);
        out.pack.bus_10uv = static_cast<int32_t>(v);
        int64_t tap = 0;
        for (int c = 0; c < 4; ++c) {
            int64_t cell_mv = 0;
            why = parse_fixed(f[static_cast<size_t>(2 + c)], 3, kFloatExactLimit, cell_mv);
            if (!why.empty()) return fail(3 + c, why);
            tap += cell_mv;
            if (c < kTapChannels) out.taps.tap_mv[c] = static_cast<int32_t>(tap);
        }
        why = parse_fixed(f[6], 6, INT64_MAX / 10, v);  // logged current: checked, not used
        if (!why.empty()) return fail(7, why);
        why = parse_fixed(f[7], 4, kFloatExactLimit, v);
        if (!why.empty()) return fail(8, why);
        out.pack.shunt_100nv = static_cast<int32_t>(v);
        out.line = line_no_;
        last_time_us_ = t;
        ++rows_;
        return true;
    }
    if (in_.bad()) return fail(0, "read error");
    if (rows_ == 0 && !failed()) {
        error_ = path_ + ": the log holds no samples";
        return false;
    }
    return false;
}

bool LogSensors::conversion_ready() {
    if (pending_) return true;
    if (ended_) return false;
    if (!source_.next(row_)) {
        ended_ = true;
        return false;
    }
    clock_.set_us(row_.time_us);
    pending_ = true;
    return true;
}

bool LogSensors::read_pack(PackReading& out) {
    out = row_.pack;
    pending_ = false;
    return true;
}

bool LogSensors::read_taps(TapReading& out) {
    if (!taps_present_) return false;
    out = row_.taps;
    return true;
}

DirectoryStorage::~DirectoryStorage() { close_log(); }

bool DirectoryStorage::begin() {
    if (!present_) return false;
    struct stat st;
    return ::stat(root_.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool DirectoryStorage::exists(const char* path) {
    struct stat st;
    return ::stat(full(path).c_str(), &st) == 0;
}

bool DirectoryStorage::make_dir(const char* path) { return ::mkdir(full(path).c_str(), 0777) == 0 || errno == EEXIST; }

bool DirectoryStorage::open_log(const char* path) {
    close_log();
    log_ = std::fopen(full(path).c_str(), "ab");
    return log_ != nullptr;
}

bool DirectoryStorage::append(const char* data, size_t len) {
    return log_ != nullptr && std::fwrite(data, 1, len, log_) == len;
}

bool DirectoryStorage::sync() { return log_ != nullptr && std::fflush(log_) == 0; }

bool DirectoryStorage::close_log() {
    if (log_ == nullptr) return true;
    const bool ok = std::fflush(log_) == 0 && !std::ferror(log_);
    const bool closed = std::fclose(log_) == 0;
    log_ = nullptr;
    return ok && closed;
}

int DirectoryStorage::read_file(const char* path, char* buf, size_t capacity) {
    std::FILE* f = std::fopen(full(path).c_str(), "rb");
    if (f == nullptr) return -1;
    const size_t n = std::fread(buf, 1, capacity, f);
    const bool more = std::fgetc(f) != EOF;
    std::fclose(f);
    return more ? -1 : static_cast<int>(n);  // too long for the buffer: unreadable
}

bool DirectoryStorage::write_file(const char* path, const char* data, size_t len) {
    // Temporary file and rename, as the SD driver does: old or new content, never half.
    const std::string target = full(path);
    const std::string tmp = target + ".tmp";
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (f == nullptr) return false;
    bool ok = std::fwrite(data, 1, len, f) == len;
    ok = std::fflush(f) == 0 && ok;
    ok = ::fsync(fileno(f)) == 0 && ok;
    ok = std::fclose(f) == 0 && ok;
    if (!ok || std::rename(tmp.c_str(), target.c_str()) != 0) {
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

TextDisplay::TextDisplay(MockClock& clock, const std::string& path) : clock_(clock) {
    if (!path.empty()) {
        out_.open(path, std::ios::binary | std::ios::trunc);
        to_file_ = true;
        write_failed_ = !out_;
    }
    clear();
}

void TextDisplay::clear() {
    for (auto& row : grid_) {
        std::memset(row, ' ', kDisplayColumns);
        row[kDisplayColumns] = '\0';
    }
}

void TextDisplay::text(uint8_t column, uint8_t row, const char* s) {
    if (row >= kDisplayRows) return;
    for (uint8_t c = column; c < kDisplayColumns && *s; ++c) grid_[row][c] = *s++;
}

std::string TextDisplay::frame() const {
    std::string f;
    for (const auto& row : grid_) {
        f += row;
        f += '\n';
    }
    return f;
}

void TextDisplay::show() {
    ++frames_;
    if (!to_file_ || write_failed_) return;
    const uint64_t t = clock_.now_us();
    char stamp[48];
    std::snprintf(stamp, sizeof stamp, "t=%llu.%03llu s\n", static_cast<unsigned long long>(t / 1000000u),
                  static_cast<unsigned long long>(t / 1000u % 1000u));
    out_ << stamp << frame() << '\n';
    if (!out_) write_failed_ = true;
}

void RecordingBuzzer::set(bool on) {
    char line[48];
    std::snprintf(line, sizeof line, "%.3f,%d\n", static_cast<double>(clock_.now_us()) * 1e-6, on ? 1 : 0);
    record_ += line;
}

int ScriptedSerial::read_byte() {
    if (read_pos_ >= input_.size()) return -1;
    return static_cast<unsigned char>(input_[read_pos_++]);
}

}  // namespace host
}  // namespace fw
}  // namespace battsim
