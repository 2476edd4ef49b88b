#include "host/sim/autopilot_log.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace battsim {
namespace host {
namespace sim {

namespace {

// Little-endian fields, written byte by byte so the file is the same on any host.
void put_uint(std::string& out, uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFFu);
}
void put_f32(std::string& out, double v) {
    const float f = static_cast<float>(v);
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    put_uint(out, bits, 4);
}
// A NUL-padded text field of exactly n bytes.
void put_text(std::string& out, const char* s, size_t n) {
    const size_t len = std::min(std::strlen(s), n);
    out.append(s, len);
    out.append(n - len, '\0');
}

// --- DataFlash (the ArduPilot log format) ------------------------------------------------------
constexpr uint8_t kHead1 = 0xA3, kHead2 = 0x95;
constexpr uint8_t kFmtId = 128, kBatId = 147, kBclId = 148;
constexpr int kBclCells = 12;
constexpr uint8_t kBatLength = 3 + 8 + 1 + 5 * 4 + 2 + 4;
constexpr uint8_t kBclLength = 3 + 8 + 1 + 4 + 2 * kBclCells;

void df_head(std::string& out, uint8_t id) {
    out += static_cast<char>(kHead1);
    out += static_cast<char>(kHead2);
    out += static_cast<char>(id);
}

void df_fmt(std::string& out, uint8_t id, uint8_t length, const char* name, const char* format, const char* columns) {
    df_head(out, kFmtId);
    put_uint(out, id, 1);
    put_uint(out, length, 1);
    put_text(out, name, 4);
    put_text(out, format, 16);
    put_text(out, columns, 64);
}

// Neither format holds a cell below 0 V (a loose balance lead's reading, bus minus a floating
// tap), and both end a pack's cells at the first 0: such a cell is written as 1 mV, which the
// monitor keeps out as a cell fault as it does the CSV log's negative reading. 1 mV, not 0.5:
// DataFlash's BCL counts whole millivolts. Above, BCL's 65.534 V is the end.
double logged_cell_v(double v) { return std::min(std::max(v, 0.001), 65.534); }

// --- ULog (the PX4 log format) -------------------------------------------------------------------
constexpr int kUlogCells = 14;  // battery_status.voltage_cell_v[14] since PX4 1.13

void ulog_message(std::string& out, char type, const std::string& payload) {
    put_uint(out, payload.size(), 2);
    out += type;
    out += payload;
}

}  // namespace

double autopilot_log_interval_s(AutopilotLog kind) { return kind == AutopilotLog::DataFlash ? 0.1 : 0.2; }

AutopilotLogWriter::AutopilotLogWriter(AutopilotLog kind, int cells) : kind_(kind), cells_(cells) {}

std::string AutopilotLogWriter::header() const {
    std::string out;
    if (kind_ == AutopilotLog::DataFlash) {
        df_fmt(out, kFmtId, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
        // ArduPilot 4.0's layout and names (4.1 appends RemPct, 4.3 health and state of health).
        df_fmt(out, kBatId, kBatLength, "BAT", "QBfffffcf", "TimeUS,Instance,Volt,VoltR,Curr,CurrTot,EnrgTot,Temp,Res");
        df_fmt(out, kBclId, kBclLength, "BCL", "QBfHHHHHHHHHHHH",
               "TimeUS,Instance,Volt,V1,V2,V3,V4,V5,V6,V7,V8,V9,V10,V11,V12");
        return out;
    }
    out.append("ULog", 4);
    out += static_cast<char>(0x01);
    out += static_cast<char>(0x12);
    out += static_cast<char>(0x35);
    out += static_cast<char>(1);  // file format version
    put_uint(out, 0, 8);          // logging start, µs
    ulog_message(out, 'B', std::string(40, '\0'));  // no compatible or incompatible flags, no appended data
    std::string info;
    const char* key = "char[16] sys_name";
    put_uint(info, std::strlen(key), 1);
    info += key;
    put_text(info, "battsim simulate", 16);
    ulog_message(out, 'I', info);
    ulog_message(out, 'F',
                 "battery_status:uint64_t timestamp;float voltage_v;float current_a;float discharged_mah;"
                 "float temperature;uint8_t cell_count;float[14] voltage_cell_v;");
    std::string sub;
    put_uint(sub, 0, 1);  // multi_id
    put_uint(sub, 0, 2);  // msg_id
    sub += "battery_status";
    ulog_message(out, 'A', sub);
    return out;
}

void AutopilotLogWriter::append(std::string& out, int64_t time_us, double voltage_v, double current_a,
                                const double* cell_v, double temperature_c) {
    // The autopilots' own counters: the current and power of each update over the time since
    // the one before.
    if (last_time_us_ >= 0) {
        const double dt_h = static_cast<double>(time_us - last_time_us_) / 3.6e9;
        consumed_mah_ += current_a * 1000.0 * dt_h;
        consumed_wh_ += voltage_v * current_a * dt_h;
    }
    last_time_us_ = time_us;
    if (kind_ == AutopilotLog::DataFlash) {
        df_head(out, kBatId);
        put_uint(out, static_cast<uint64_t>(time_us), 8);
        put_uint(out, 0, 1);
        put_f32(out, voltage_v);
        put_f32(out, voltage_v);  // VoltR: the autopilot's resting-voltage estimate; not simulated
        put_f32(out, current_a);
        put_f32(out, consumed_mah_);
        put_f32(out, consumed_wh_);
        // Centi-degrees, truncated as ArduPilot's cast does.
        put_uint(out, static_cast<uint16_t>(static_cast<int16_t>(temperature_c * 100.0)), 2);
        put_f32(out, 0.0);  // Res: ArduPilot's own resistance estimate; not simulated
        df_head(out, kBclId);
        put_uint(out, static_cast<uint64_t>(time_us), 8);
        put_uint(out, 0, 1);
        put_f32(out, voltage_v);
        for (int c = 0; c < kBclCells; ++c)
            put_uint(out, c < cells_ ? static_cast<uint64_t>(std::lround(logged_cell_v(cell_v[c]) * 1000.0)) : 0u, 2);
        return;
    }
    std::string d;
    put_uint(d, 0, 2);  // msg_id of the battery_status subscription
    put_uint(d, static_cast<uint64_t>(time_us), 8);
    put_f32(d, voltage_v);
    put_f32(d, current_a);
    put_f32(d, consumed_mah_);
    put_f32(d, temperature_c);
    put_uint(d, static_cast<uint64_t>(cells_), 1);
    for (int c = 0; c < kUlogCells; ++c) put_f32(d, c < cells_ ? logged_cell_v(cell_v[c]) : 0.0);
    ulog_message(out, 'D', d);
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
