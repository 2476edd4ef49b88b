// Flight-log readers: ArduPilot DataFlash (binary + text) and PX4 ULog.
// Real logs from the shared data folder (tagged [data]: CMake leaves them out when the folder
// is absent; a missing file is a failure), and malformed inputs built byte by byte in this file.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "host/io/dataflash_reader.h"
#include "host/io/sample_reader.h"
#include "host/io/ulog_reader.h"
#include "test_files.h"

using namespace battsim;
using namespace battsim::host;

namespace {

using LogTempDir = testsupport::TempDir;

enum class Kind { DfText, DfBinary, Ulog };

std::unique_ptr<SampleReader> open_kind(Kind k, const std::string& path) {
    ReaderOptions o;
    switch (k) {
        case Kind::DfText: return open_dataflash_text(path, o);
        case Kind::DfBinary: return open_dataflash_binary(path, o);
        default: return open_ulog(path, o);
    }
}

struct ReadResult {
    std::vector<core::Sample> samples;
    std::vector<std::string> notes;
    int cell_count = 0;
    bool has_temperature = false;
    SourceInfo info;  // as it stands after next() returned false
};

ReadResult read_all(Kind k, const std::string& path) {
    auto r = open_kind(k, path);
    ReadResult res;
    core::Sample s;
    while (r->next(s)) res.samples.push_back(s);
    res.notes = r->info().notes;
    res.cell_count = r->info().cell_count;
    res.has_temperature = r->info().has_temperature;
    res.info = r->info();
    return res;
}

// The InputError message from opening and reading `path`; "" if there was none.
std::string error_of(Kind k, const std::string& path) {
    try {
        read_all(k, path);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

bool any_note(const ReadResult& r, const std::string& needle) {
    for (const auto& n : r.notes)
        if (n.find(needle) != std::string::npos) return true;
    return false;
}

std::string data_path(const char* rel) { return std::string(BATTSIM_DATA_DIR) + rel; }

double param(const ReadResult& r, const std::string& name) { return log_parameter(r.info, name); }

double seconds(const core::Sample& s) { return static_cast<double>(s.time_us) / 1e6; }

bool non_decreasing(const std::vector<core::Sample>& v) {
    for (size_t i = 1; i < v.size(); ++i)
        if (v[i].time_us < v[i - 1].time_us) return false;
    return true;
}

double median_dt(const std::vector<core::Sample>& v) {
    std::vector<double> d;
    for (size_t i = 1; i < v.size(); ++i) d.push_back(seconds(v[i]) - seconds(v[i - 1]));
    std::sort(d.begin(), d.end());
    return d.empty() ? 0 : d[d.size() / 2];
}

// --- little-endian byte builders ---------------------------------------------------------------
void put(std::string& s, uint64_t v, int n) {
    for (int i = 0; i < n; ++i) s += static_cast<char>((v >> (8 * i)) & 0xFF);
}
void put_f(std::string& s, float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    put(s, u, 4);
}
std::string padded(const std::string& s, size_t n) {
    std::string r = s.substr(0, n);
    r.resize(n, '\0');
    return r;
}

// --- DataFlash binary ---------------------------------------------------------------------------
int df_size(const std::string& format) {
    int n = 3;
    for (char c : format) {
        switch (c) {
            case 'b': case 'B': case 'M': n += 1; break;
            case 'h': case 'H': case 'c': case 'C': n += 2; break;
            case 'i': case 'I': case 'f': case 'e': case 'E': case 'L': case 'n': n += 4; break;
            case 'd': case 'q': case 'Q': n += 8; break;
            case 'N': n += 16; break;
            case 'Z': case 'a': n += 64; break;
            default: break;
        }
    }
    return n;
}

std::string df_fmt(int type, int length, const std::string& name, const std::string& format,
                   const std::string& labels) {
    std::string m = "\xA3\x95\x80";
    m += static_cast<char>(type);
    m += static_cast<char>(length);
    m += padded(name, 4) + padded(format, 16) + padded(labels, 64);
    return m;
}
std::string df_fmt(int type, const std::string& name, const std::string& format, const std::string& labels) {
    return df_fmt(type, df_size(format), name, format, labels);
}

const int kCurrId = 166;
std::string df_curr_fmt() { return df_fmt(kCurrId, "CURR", "IhhhHfh", "TimeMS,Throttle,Volt,Curr,Vcc,CurrTot,Volt2"); }
// CURR as APM:Copter 3.3 logs it: Volt/Curr in centi-units.
std::string df_curr(uint32_t time_ms, int volt_cv, int curr_ca, float curr_tot = 0) {
    std::string m = "\xA3\x95";
    m += static_cast<char>(kCurrId);
    put(m, time_ms, 4);
    put(m, 0, 2);
    put(m, static_cast<uint16_t>(volt_cv), 2);
    put(m, static_cast<uint16_t>(curr_ca), 2);
    put(m, 5000, 2);
    put_f(m, curr_tot);
    put(m, 0, 2);
    return m;
}

const int kBatId = 147, kBclId = 148;
std::string df_bat_fmt() { return df_fmt(kBatId, "BAT", "QBfffc", "TimeUS,Instance,Volt,VoltR,Curr,Temp"); }
std::string df_bat(uint64_t time_us, int inst, float volt, float curr, double temp_c = 25.0) {
    std::string m = "\xA3\x95";
    m += static_cast<char>(kBatId);
    put(m, time_us, 8);
    put(m, static_cast<uint8_t>(inst), 1);
    put_f(m, volt);
    put_f(m, volt);
    put_f(m, curr);
    put(m, static_cast<uint16_t>(static_cast<int16_t>(std::lround(temp_c * 100))), 2);
    return m;
}
std::string df_bcl_fmt() {
    return df_fmt(kBclId, "BCL", "QBfHHHHHHHHHHHH", "TimeUS,Instance,Volt,V1,V2,V3,V4,V5,V6,V7,V8,V9,V10,V11,V12");
}
std::string df_bcl(uint64_t time_us, const std::vector<int>& mv) {
    std::string m = "\xA3\x95";
    m += static_cast<char>(kBclId);
    put(m, time_us, 8);
    put(m, 0, 1);
    put_f(m, 0);
    for (int i = 0; i < 12; ++i) put(m, i < static_cast<int>(mv.size()) ? static_cast<uint16_t>(mv[static_cast<size_t>(i)]) : 0xFFFF, 2);
    return m;
}

std::string df_three_curr() {
    return df_curr_fmt() + df_curr(1000, 1650, 120, 1) + df_curr(1100, 1649, 130, 2) + df_curr(1200, 1648, 140, 3);
}

// --- ULog ----------------------------------------------------------------------------------------
std::string ulog_header(uint8_t version = 1) {
    std::string h = "ULog";
    h += '\x01';
    h += '\x12';
    h += '\x35';
    h += static_cast<char>(version);
    put(h, 123456, 8);
    return h;
}
std::string ulog_msg(char type, const std::string& payload) {
    std::string m;
    put(m, payload.size(), 2);
    m += type;
    return m + payload;
}
const char* kBatteryFormat =
    "battery_status:uint64_t timestamp;float voltage_v;float current_a;float discharged_mah;"
    "float temperature;int32_t cell_count;float[4] voltage_cell_v;uint8_t warning;uint8_t[3] _padding0;";
std::string ulog_sub(int multi_id, int msg_id, const std::string& name = "battery_status") {
    std::string p;
    put(p, static_cast<uint8_t>(multi_id), 1);
    put(p, static_cast<uint16_t>(msg_id), 2);
    return ulog_msg('A', p + name);
}
// battery_status data without the trailing 3 padding bytes (as PX4 logs it).
std::string ulog_battery(int msg_id, uint64_t ts, float v, float i, float temp = std::numeric_limits<float>::quiet_NaN(),
                         int cells = 4, float cell_v = 3.9f, float cell_step_v = 0.01f) {
    std::string p;
    put(p, static_cast<uint16_t>(msg_id), 2);
    put(p, ts, 8);
    put_f(p, v);
    put_f(p, i);
    put_f(p, 10.0f);
    put_f(p, temp);
    put(p, static_cast<uint32_t>(cells), 4);
    for (int k = 0; k < 4; ++k) put_f(p, cell_v + cell_step_v * static_cast<float>(k));
    put(p, 0, 1);  // warning
    return ulog_msg('D', p);
}
std::string ulog_flags(uint8_t incompat0 = 0) {
    std::string p(8, '\0');
    p += static_cast<char>(incompat0);
    p += std::string(7, '\0');
    p += std::string(24, '\0');
    return ulog_msg('B', p);
}
// Parameter ('P') and default parameter ('Q') messages; `value` is the 4 raw value bytes.
std::string ulog_key(const std::string& key) { return std::string(1, static_cast<char>(key.size())) + key; }
std::string ulog_param_f(const std::string& name, float v) {
    std::string p = ulog_key("float " + name);
    put_f(p, v);
    return ulog_msg('P', p);
}
std::string ulog_param_i(const std::string& name, int32_t v) {
    std::string p = ulog_key("int32_t " + name);
    put(p, static_cast<uint32_t>(v), 4);
    return ulog_msg('P', p);
}
std::string ulog_default_i(const std::string& name, int32_t v) {
    std::string p(1, '\x03');  // default_types: system and current configuration
    p += ulog_key("int32_t " + name);
    put(p, static_cast<uint32_t>(v), 4);
    return ulog_msg('Q', p);
}
std::string ulog_good_prefix() {
    return ulog_header() + ulog_flags() + ulog_msg('F', kBatteryFormat) + ulog_sub(0, 3);
}

}  // namespace

// =================================================================================================
// Real logs

TEST_CASE("DataFlash binary log171.bin: CURR rows with TimeMS", "[io-logs][data]") {
    const std::string p = data_path("/ardupilot/log171.bin");
    const auto r = read_all(Kind::DfBinary, p);
    REQUIRE(r.samples.size() == 2384);
    CHECK(r.samples.front().voltage_v == Approx(16.54).margin(0.005));
    CHECK(r.samples.back().voltage_v == Approx(14.94).margin(0.005));
    CHECK(seconds(r.samples.front()) == Approx(11.477).margin(0.001));
    CHECK(seconds(r.samples.back()) == Approx(254.071).margin(0.001));
    CHECK(median_dt(r.samples) == Approx(0.1).margin(0.005));
    CHECK(non_decreasing(r.samples));
    float vmin = 1e9f, vmax = 0, imax = 0;
    for (const auto& s : r.samples) {
        vmin = std::min(vmin, s.voltage_v);
        vmax = std::max(vmax, s.voltage_v);
        imax = std::max(imax, s.current_a);
        CHECK(s.cell_count == 0);
        CHECK_FALSE(s.has_temperature);
    }
    CHECK(vmin == Approx(14.91).margin(0.005));
    CHECK(vmax == Approx(16.54).margin(0.005));
    CHECK(imax == Approx(27.44).margin(0.01));
    CHECK(r.notes.empty());
}

TEST_CASE("DataFlash text underpowered.log: no time source, spacing inferred", "[io-logs][data]") {
    const std::string p = data_path("/ardupilot/underpowered.log");
    const auto r = read_all(Kind::DfText, p);
    REQUIRE(r.samples.size() == 430);
    CHECK(r.samples.front().voltage_v == Approx(11.98).margin(0.005));
    CHECK(r.samples.back().voltage_v == Approx(10.50).margin(0.005));
    CHECK(r.samples.front().time_us == 0);
    // Evenly spaced at the median dCurrTot/Curr, which is 1.00 s for this log.
    CHECK(median_dt(r.samples) == Approx(1.0).margin(0.002));
    CHECK(seconds(r.samples.back()) == Approx(429.0).margin(0.5));
    CHECK(any_note(r, "no time source"));
    CHECK(any_note(r, "inferred, not measured"));
    float vmin = 1e9f, imax = 0;
    for (const auto& s : r.samples) {
        vmin = std::min(vmin, s.voltage_v);
        imax = std::max(imax, s.current_a);
    }
    CHECK(vmin == Approx(8.94).margin(0.005));
    CHECK(imax == Approx(32.40).margin(0.01));
}

TEST_CASE("DataFlash text robert_lefebvre_octo_PM.log: GPS time, pre-fix rows placed before it", "[io-logs][data]") {
    const std::string p = data_path("/ardupilot/robert_lefebvre_octo_PM.log");
    const auto r = read_all(Kind::DfText, p);
    // All 68 CURR rows are kept: the 11 rows logged before the GPS fix get inferred times
    // (the inferred spacing before the first GPS time) and a note says so.
    REQUIRE(r.samples.size() == 68);
    CHECK(r.samples.front().voltage_v == Approx(14.99).margin(0.005));
    CHECK(r.samples.back().voltage_v == Approx(14.50).margin(0.005));
    CHECK(non_decreasing(r.samples));
    CHECK(r.samples.front().time_us == 0);
    // The 57 GPS-timed rows span 155.2 s.
    CHECK(seconds(r.samples[67]) - seconds(r.samples[11]) == Approx(155.2).margin(0.01));
    // The 11 pre-fix rows are evenly spaced, ending one spacing before the first GPS time.
    const double sp = seconds(r.samples[1]) - seconds(r.samples[0]);
    CHECK(sp > 0.5);
    CHECK(sp < 5.0);
    for (int i = 1; i <= 10; ++i)
        CHECK(seconds(r.samples[static_cast<size_t>(i)]) - seconds(r.samples[static_cast<size_t>(i - 1)]) ==
              Approx(sp).margin(1e-6));
    CHECK(any_note(r, "the first 11 CURR rows come before the first timed message"));
    CHECK(any_note(r, "GPS time of week"));
    float vmin = 1e9f, vmax = 0, imax = 0;
    for (const auto& s : r.samples) {
        vmin = std::min(vmin, s.voltage_v);
        vmax = std::max(vmax, s.voltage_v);
        imax = std::max(imax, s.current_a);
    }
    CHECK(vmin == Approx(13.34).margin(0.005));
    CHECK(vmax == Approx(15.11).margin(0.005));
    CHECK(imax == Approx(25.64).margin(0.01));
}

TEST_CASE("PX4 ULog test.ulg: battery_status multi_id 0", "[io-logs][data]") {
    const std::string p = data_path("/px4/test.ulg");
    const auto r = read_all(Kind::Ulog, p);
    REQUIRE(r.samples.size() == 46);
    CHECK(r.samples.front().voltage_v == Approx(13.75).margin(0.005));
    CHECK(r.samples.back().voltage_v == Approx(14.01).margin(0.005));
    CHECK(seconds(r.samples.back()) - seconds(r.samples.front()) == Approx(8.8).margin(0.01));
    CHECK(median_dt(r.samples) == Approx(0.2).margin(0.005));  // 5 Hz
    CHECK(non_decreasing(r.samples));
    // Its voltage_cell_v is pack / 4 in every sample (PX4 measured no cell): left out.
    CHECK(r.cell_count == 0);
    CHECK_FALSE(r.has_temperature);  // temperature is NaN in this log
    float vmin = 1e9f, vmax = 0, imax = 0;
    for (const auto& s : r.samples) {
        vmin = std::min(vmin, s.voltage_v);
        vmax = std::max(vmax, s.voltage_v);
        imax = std::max(imax, s.current_a);
        CHECK(s.cell_count == 0);
        CHECK(s.cell_voltage_v[0] == 0.0f);
        CHECK_FALSE(s.has_temperature);
    }
    CHECK(vmin == Approx(12.95).margin(0.005));
    CHECK(vmax == Approx(14.31).margin(0.005));
    CHECK(imax == Approx(12.19).margin(0.01));
    CHECK(any_note(r, "carry no per-cell information and are left out"));
}

TEST_CASE("DataFlash text logs: PARM parameters", "[io-logs][data]") {
    const auto u = read_all(Kind::DfText, data_path("/ardupilot/underpowered.log"));
    CHECK(u.info.parameters.size() == 271);  // 271 PARM lines, no name repeated
    CHECK(u.info.parameters.front().first == "SYSID_SW_MREV");
    CHECK(param(u, "BATT_CAPACITY") == 4000.0);
    CHECK(param(u, "LOW_VOLT") == Approx(9.4));
    const auto o = read_all(Kind::DfText, data_path("/ardupilot/robert_lefebvre_octo_PM.log"));
    CHECK(o.info.parameters.size() == 271);
    CHECK(param(o, "BATT_CAPACITY") == 1760.0);
    CHECK(param(o, "LOW_VOLT") == Approx(10.5));
}

TEST_CASE("DataFlash binary log171.bin: PARM parameters", "[io-logs][data]") {
    // Read independently with a short Python script walking the FMT/PARM messages: 491 PARM
    // messages, 491 distinct names.
    const auto r = read_all(Kind::DfBinary, data_path("/ardupilot/log171.bin"));
    CHECK(r.info.parameters.size() == 491);
    CHECK(param(r, "BATT_CAPACITY") == 5200.0);
    CHECK(param(r, "FS_BATT_VOLTAGE") == Approx(14.0));
    CHECK(param(r, "FS_BATT_MAH") == 520.0);
    CHECK(param(r, "BATT_MONITOR") == 5.0);
    CHECK(r.notes.empty());
}

TEST_CASE("PX4 ULog test.ulg: parameters", "[io-logs][data]") {
    // Values read independently with a short Python script walking the ULog messages (867 'P',
    // 80 'Q'); BAT1_CAPACITY and BAT1_R_INTERNAL are -1 (PX4: unset). The 'Q' default of
    // BAT1_N_CELLS is 0 and must not win over the 'P' value 4.
    const auto r = read_all(Kind::Ulog, data_path("/px4/test.ulg"));
    CHECK(r.info.parameters.size() == 867);
    CHECK(param(r, "BAT1_CAPACITY") == -1.0);
    CHECK(param(r, "BAT1_N_CELLS") == 4.0);
    CHECK(param(r, "BAT1_V_EMPTY") == 3.5);
    CHECK(param(r, "BAT1_V_CHARGED") == Approx(4.05).epsilon(1e-6));  // float 4.05
    CHECK(param(r, "BAT1_R_INTERNAL") == -1.0);
    CHECK_FALSE(any_note(r, "parameter"));
}

// =================================================================================================
// DataFlash binary, built byte by byte

TEST_CASE("DataFlash binary: minimal CURR log reads and scales centi-units", "[io-logs]") {
    LogTempDir d;
    const auto r = read_all(Kind::DfBinary, d.write("ok.bin", df_three_curr()));
    REQUIRE(r.samples.size() == 3);
    CHECK(r.samples[0].time_us == 1000000);
    CHECK(r.samples[0].voltage_v == Approx(16.50));
    CHECK(r.samples[0].current_a == Approx(1.20));
    CHECK(r.samples[2].time_us == 1200000);
    CHECK(r.notes.empty());
}

TEST_CASE("DataFlash binary: BAT with BCL cells and temperature, other instances ignored", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_bat_fmt() + df_bcl_fmt() + df_bat(1000000, 0, 16.4f, 3.0f) +
                              df_bcl(1050000, {4100, 4110, 4090, 4100}) + df_bat(1100000, 1, 12.0f, 1.0f) +
                              df_bat(1100000, 0, 16.3f, 3.5f, 26.5);
    const auto r = read_all(Kind::DfBinary, d.write("bat.bin", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[0].cell_count == 0);  // no BCL yet
    CHECK(r.samples[1].cell_count == 4);
    CHECK(r.samples[1].cell_voltage_v[1] == Approx(4.11));
    CHECK(r.samples[1].voltage_v == Approx(16.3));
    CHECK(r.samples[1].has_temperature);
    CHECK(r.samples[1].temperature_c == Approx(26.5));
    CHECK(r.cell_count == 4);
    CHECK(r.has_temperature);
    CHECK(any_note(r, "instances other than 0"));
}

TEST_CASE("DataFlash binary: a BCL row after its BAT row (ArduPilot's order) belongs to that BAT row", "[io-logs]") {
    // ArduPilot writes each battery update as BAT, then BCL with the same TimeUS: the cells
    // of a BAT row are in the BCL after it, not in the one before (an update older).
    LogTempDir d;
    const std::string bytes = df_bat_fmt() + df_bcl_fmt() + df_bat(1000000, 0, 16.4f, 3.0f) +
                              df_bcl(1000000, {4100, 4110, 4090, 4100}) + df_bat(1100000, 0, 16.0f, 9.0f) +
                              df_bcl(1100000, {4000, 4010, 3990, 4000}) + df_bat(1200000, 0, 15.9f, 9.5f);
    const auto r = read_all(Kind::DfBinary, d.write("order.bin", bytes));
    REQUIRE(r.samples.size() == 3);
    CHECK(r.samples[0].cell_count == 4);
    CHECK(r.samples[0].cell_voltage_v[1] == Approx(4.11));
    CHECK(r.samples[1].cell_voltage_v[1] == Approx(4.01));
    // No BCL of its own: the latest cells stand, as before.
    CHECK(r.samples[2].cell_count == 4);
    CHECK(r.samples[2].cell_voltage_v[1] == Approx(4.01));
    CHECK(r.notes.empty());
}

TEST_CASE("DataFlash binary: a voltage-only battery monitor's NaN current is read as 0 A and said", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_bat_fmt() + df_bat(1000000, 0, 16.4f, std::nanf("")) + df_bat(1100000, 0, 16.3f, std::nanf("")) +
                              df_bat(1200000, 0, 16.2f, 2.5f);
    const auto r = read_all(Kind::DfBinary, d.write("vonly.bin", bytes));
    REQUIRE(r.samples.size() == 3);
    CHECK(r.samples[0].current_a == 0.0f);
    CHECK(r.samples[1].voltage_v == Approx(16.3));
    CHECK(r.samples[2].current_a == Approx(2.5));
    CHECK(any_note(r, "BAT.Curr is NaN (the battery monitor measures no current) in 2 of 3 rows: read as 0 A"));
}

TEST_CASE("DataFlash binary malformed: file truncated mid-message keeps what came before", "[io-logs]") {
    LogTempDir d;
    std::string bytes = df_three_curr() + df_curr(1300, 1647, 150);
    bytes.resize(bytes.size() - 9);
    const auto r = read_all(Kind::DfBinary, d.write("trunc.bin", bytes));
    CHECK(r.samples.size() == 3);
    CHECK(any_note(r, "file ends inside a message of type CURR"));
}

namespace {
const int kParmId = 64;
// PARM as newer firmware logs it: Value found by label, not position.
std::string df_parm_fmt() { return df_fmt(kParmId, "PARM", "QNff", "TimeUS,Name,Value,Default"); }
std::string df_parm(uint64_t time_us, const std::string& name, float value) {
    std::string m = "\xA3\x95";
    m += static_cast<char>(kParmId);
    put(m, time_us, 8);
    m += padded(name, 16);
    put_f(m, value);
    put_f(m, 0);
    return m;
}
}  // namespace

TEST_CASE("DataFlash binary: PARM parameters by label, first value kept", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_parm_fmt() + df_parm(10, "BATT_CAPACITY", 5200) + df_curr_fmt() +
                              df_curr(1000, 1650, 120) + df_parm(20, "BATT_LOW_VOLT_16", 14.0f) +  // 16 chars, no NUL
                              df_parm(30, "BATT_CAPACITY", 3000) +
                              df_parm(40, "FS_BATT_MAH", std::numeric_limits<float>::quiet_NaN()) +
                              df_curr(1100, 1649, 130);
    const auto r = read_all(Kind::DfBinary, d.write("parm.bin", bytes));
    REQUIRE(r.samples.size() == 2);
    REQUIRE(r.info.parameters.size() == 2);
    CHECK(r.info.parameters[0].first == "BATT_CAPACITY");
    CHECK(r.info.parameters[0].second == 5200.0);
    CHECK(r.info.parameters[1].first == "BATT_LOW_VOLT_16");
    CHECK(r.info.parameters[1].second == 14.0);
    CHECK(std::isnan(param(r, "FS_BATT_MAH")));
    CHECK(any_note(r, "FS_BATT_MAH.Value: expected a finite number, found nan"));
    // Same log without any PARM FMT: no parameters, no notes about them.
    const auto plain = read_all(Kind::DfBinary, d.write("plain.bin", df_three_curr()));
    CHECK(plain.info.parameters.empty());
    CHECK(std::isnan(param(plain, "BATT_CAPACITY")));
}

TEST_CASE("DataFlash binary malformed: wrong magic", "[io-logs]") {
    LogTempDir d;
    const std::string e = error_of(Kind::DfBinary, d.write("magic.bin", "FMT, 128, 89, FMT, BBnNZ\n"));
    CHECK(e.find("not a DataFlash binary log") != std::string::npos);
    CHECK(e.find("46 4D 54") != std::string::npos);  // shows what it found
    CHECK(error_of(Kind::DfBinary, d.write("empty.bin", "")).find("empty file") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: FMT length shorter than its format", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_fmt(kCurrId, 10, "CURR", "IhhhHfh", "TimeMS,Throttle,Volt,Curr,Vcc,CurrTot,Volt2") +
                              df_curr(1000, 1650, 120);
    const std::string e = error_of(Kind::DfBinary, d.write("short.bin", bytes));
    CHECK(e.find("byte 0") != std::string::npos);
    CHECK(e.find("declares length 10") != std::string::npos);
    CHECK(e.find("needs 21") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: FMT length zero", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_fmt(kCurrId, 0, "CURR", "IhhhHfh", "TimeMS,Throttle,Volt,Curr,Vcc,CurrTot,Volt2") +
                              df_curr(1000, 1650, 120);
    const std::string e = error_of(Kind::DfBinary, d.write("zero.bin", bytes));
    CHECK(e.find("declares length 0") != std::string::npos);
    CHECK(e.find("3..255") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: FMT with a huge length (255 for a 21-byte format)", "[io-logs]") {
    LogTempDir d;
    const std::string bytes =
        df_fmt(kCurrId, 255, "CURR", "IhhhHfh", "TimeMS,Throttle,Volt,Curr,Vcc,CurrTot,Volt2") + df_curr(1000, 1650, 120);
    const std::string e = error_of(Kind::DfBinary, d.write("huge.bin", bytes));
    CHECK(e.find("declares length 255") != std::string::npos);
    CHECK(e.find("needs 21") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: message id used before its FMT is skipped", "[io-logs]") {
    LogTempDir d;
    // A CURR message before the FMT that defines id 166 (the file still starts with an FMT).
    const std::string bytes = df_bat_fmt() + df_curr(900, 1651, 110) + df_three_curr();
    const auto r = read_all(Kind::DfBinary, d.write("early.bin", bytes));
    CHECK(r.samples.size() == 3);
    CHECK(any_note(r, "message id 166 has no FMT"));
}

TEST_CASE("DataFlash binary malformed: garbage between messages is skipped (resync)", "[io-logs]") {
    LogTempDir d;
    const std::string garbage = "\x01\x02\xA3\x00garbage\xFF\xFE";
    const std::string bytes = df_curr_fmt() + df_curr(1000, 1650, 120) + garbage + df_curr(1100, 1649, 130) +
                              garbage + garbage + df_curr(1200, 1648, 140);
    const auto r = read_all(Kind::DfBinary, d.write("garbage.bin", bytes));
    REQUIRE(r.samples.size() == 3);
    CHECK(r.samples[1].voltage_v == Approx(16.49));
    CHECK(any_note(r, "skipped " + std::to_string(garbage.size()) + " bytes"));
    CHECK(any_note(r, "resynchronised"));
}

TEST_CASE("DataFlash binary malformed: message cut short by lost bytes is dropped", "[io-logs]") {
    LogTempDir d;
    std::string cut = df_curr(1100, 1649, 130);
    cut.resize(cut.size() - 5);  // the next message starts inside this one's span
    const std::string bytes = df_curr_fmt() + df_curr(1000, 1650, 120) + cut + df_curr(1200, 1648, 140);
    const auto r = read_all(Kind::DfBinary, d.write("cut.bin", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[1].time_us == 1200000);
    CHECK(any_note(r, "cut short"));
}

TEST_CASE("DataFlash binary malformed: NaN voltage in BAT is dropped with a note", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_bat_fmt() + df_bat(1000000, 0, 16.4f, 3.0f) +
                              df_bat(1100000, 0, std::numeric_limits<float>::quiet_NaN(), 3.0f) +
                              df_bat(1200000, 0, 16.3f, 3.0f);
    const auto r = read_all(Kind::DfBinary, d.write("nan.bin", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[1].time_us == 1200000);
    CHECK(any_note(r, "BAT.Volt = nan"));
    // Only NaN rows: nothing usable is an error, not an empty result.
    const std::string only_nan =
        df_bat_fmt() + df_bat(1000000, 0, std::numeric_limits<float>::quiet_NaN(), 3.0f);
    CHECK(error_of(Kind::DfBinary, d.write("allnan.bin", only_nan)).find("no usable BAT rows") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: time going backwards is dropped with a note", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_curr_fmt() + df_curr(1000, 1650, 120) + df_curr(2000, 1649, 130) +
                              df_curr(1500, 1648, 140) + df_curr(2000, 1647, 140) + df_curr(2100, 1646, 140);
    const auto r = read_all(Kind::DfBinary, d.write("back.bin", bytes));
    REQUIRE(r.samples.size() == 4);
    CHECK(non_decreasing(r.samples));
    CHECK(r.samples[2].time_us == 2000000);  // equal time is kept
    CHECK(any_note(r, "goes back"));
}

TEST_CASE("DataFlash binary malformed: unknown format character in an unrelated FMT", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_curr_fmt() + df_fmt(50, 7, "XYZ", "Ig", "TimeMS,Odd") + df_curr(1000, 1650, 120) +
                              std::string("\xA3\x95\x32\x01\x02\x03\x04", 7) + df_curr(1100, 1649, 130);
    const auto r = read_all(Kind::DfBinary, d.write("oddfmt.bin", bytes));
    CHECK(r.samples.size() == 2);
    CHECK(any_note(r, "unknown format character 'g'"));
    // The same problem in the battery message itself is an error.
    const std::string bad = df_fmt(kCurrId, 7, "CURR", "Ig", "TimeMS,Volt") + std::string("\xA3\x95\xA6\x01\x02\x03\x04", 7);
    CHECK(error_of(Kind::DfBinary, d.write("badcurr.bin", bad)).find("CURR rows cannot be read") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: no battery messages", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = df_fmt(50, "XYZ", "IB", "TimeMS,Id") + std::string("\xA3\x95\x32\x01\x00\x00\x00\x07", 8);
    CHECK(error_of(Kind::DfBinary, d.write("nobat.bin", bytes)).find("no BAT or CURR messages") != std::string::npos);
}

TEST_CASE("DataFlash binary malformed: heavy corruption keeps the note list bounded", "[io-logs]") {
    LogTempDir d;
    std::string bytes = df_curr_fmt();
    for (int i = 0; i < 500; ++i) bytes += df_curr(1000 + static_cast<uint32_t>(i) * 100, 1650, 120) + "junk";
    const auto r = read_all(Kind::DfBinary, d.write("junk.bin", bytes));
    CHECK(r.samples.size() == 500);
    CHECK(r.notes.size() < 20);
    CHECK(any_note(r, "more notes of the same kind (resync)"));
}

// =================================================================================================
// DataFlash text

namespace {
const char* kTextFmts =
    "FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format\n"
    "FMT, 130, 35, GPS, BIBcLLeeEe, Status,Time,NSats,HDop,Lat,Lng,RelAlt,Alt,Spd,GCrs\n"
    "FMT, 9, 19, CURR, hIhhhf, Thr,ThrInt,Volt,Curr,Vcc,CurrTot\n";
std::string gps_line(long ms) {
    return "GPS, 3, " + std::to_string(ms) + ", 6, 4.68, 44.0290459, -77.7367640, 3.13, 91.56, 0.00, 0.00\n";
}
}  // namespace

TEST_CASE("DataFlash text: untimed CURR takes the latest GPS time, CRLF accepted", "[io-logs]") {
    LogTempDir d;
    std::string t = std::string(kTextFmts) + gps_line(500000000) + "CURR, 0, 0, 1499, 200, 4940, 1.0\n" +
                    gps_line(500001000) + gps_line(500001200) + "CURR, 0, 0, 1498, 210, 4940, 2.0\r\n";
    const auto r = read_all(Kind::DfText, d.write("gps.log", t));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[0].time_us == 0);
    CHECK(r.samples[1].time_us == 1200000);
    CHECK(r.samples[1].voltage_v == Approx(14.98));
    CHECK(r.samples[1].current_a == Approx(2.10));
}

TEST_CASE("DataFlash text: untimed CURR takes the latest boot time of a neighbour", "[io-logs]") {
    LogTempDir d;
    std::string t = std::string(kTextFmts) + "FMT, 4, 7, TICK, I, TimeMS\n" + "TICK, 5000\n" +
                    "CURR, 0, 0, 1499, 200, 4940, 1.0\n" + "TICK, 5100\n" + "TICK, 5200\n" +
                    "CURR, 0, 0, 1498, 210, 4940, 2.0\n";
    const auto r = read_all(Kind::DfText, d.write("tick.log", t));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[0].time_us == 5000000);
    CHECK(r.samples[1].time_us == 5200000);
    CHECK(any_note(r, "latest boot time"));
}

TEST_CASE("DataFlash text: PARM parameters, first value kept", "[io-logs]") {
    LogTempDir d;
    const std::string t = std::string(kTextFmts) + "FMT, 129, 23, PARM, Nf, Name,Value\n" +
                          "PARM, BATT_CAPACITY, 4000.000000\n" + "CURR, 0, 0, 1499, 200, 4940, 1.0\n" +
                          "PARM, LOW_VOLT, 10.500000\n" + "PARM, BATT_CAPACITY, 3300.000000\n" +
                          "CURR, 0, 0, 1498, 210, 4940, 2.0\n";
    const auto r = read_all(Kind::DfText, d.write("parm.log", t));
    CHECK(r.samples.size() == 2);
    REQUIRE(r.info.parameters.size() == 2);
    CHECK(r.info.parameters[0] == std::make_pair(std::string("BATT_CAPACITY"), 4000.0));
    CHECK(r.info.parameters[1] == std::make_pair(std::string("LOW_VOLT"), 10.5));
    CHECK(std::isnan(param(r, "NO_SUCH_PARAM")));
    CHECK(std::isnan(log_parameter(SourceInfo(), "BATT_CAPACITY")));
    CHECK_FALSE(any_note(r, "PARM"));
}

TEST_CASE("DataFlash text malformed: PARM with a non-numeric Value is skipped with a note", "[io-logs]") {
    LogTempDir d;
    const std::string t = std::string(kTextFmts) + "FMT, 129, 23, PARM, Nf, Name,Value\n" +
                          "PARM, BATT_CAPACITY, 4000\n" + "PARM, LOW_VOLT, abc\n" + "PARM, FS_BATT_MAH, nan\n" +
                          "PARM, ARMING_CHECK, 1\n" + "CURR, 0, 0, 1499, 200, 4940, 1.0\n" +
                          "CURR, 0, 0, 1498, 210, 4940, 2.0\n";
    const auto r = read_all(Kind::DfText, d.write("parmbad.log", t));
    CHECK(r.samples.size() == 2);
    REQUIRE(r.info.parameters.size() == 2);
    CHECK(param(r, "BATT_CAPACITY") == 4000.0);
    CHECK(param(r, "ARMING_CHECK") == 1.0);
    CHECK(std::isnan(param(r, "LOW_VOLT")));
    CHECK(std::isnan(param(r, "FS_BATT_MAH")));
    CHECK(any_note(r, "line 6 column 3: PARM LOW_VOLT.Value: expected a finite number, found 'abc'"));
    CHECK(any_note(r, "line 7 column 3: PARM FS_BATT_MAH.Value"));
    // A PARM FMT without a Value column: parameters are skipped with a note, samples still read.
    const std::string nov = std::string(kTextFmts) + "FMT, 129, 23, PARM, Nf, Name,Val\n" + "PARM, BATT_CAPACITY, 4000\n" +
                            "CURR, 0, 0, 1499, 200, 4940, 1.0\n";
    const auto r2 = read_all(Kind::DfText, d.write("parmnov.log", nov));
    CHECK(r2.samples.size() == 1);
    CHECK(r2.info.parameters.empty());
    CHECK(any_note(r2, "PARM messages are skipped"));
}

TEST_CASE("DataFlash text malformed: non-UTF-8 bytes", "[io-logs]") {
    LogTempDir d;
    std::string t = std::string(kTextFmts) + "\xFE\xFF\x80 binary junk\n" + "CURR, 0, 0, 1499, 200, 4940, 1.0\n" +
                    "CURR, 0, 0, 1\xFF" "98, 200, 4940, 2.0\n" + "CURR, 0, 0, 1497, 200, 4940, 3.0\n";
    const auto r = read_all(Kind::DfText, d.write("utf.log", t));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[1].voltage_v == Approx(14.97));
    CHECK(any_note(r, "line 6 column 4: CURR.Volt: expected a number, found '1\\xFF98'"));
    CHECK(any_note(r, "1 line(s) are not messages"));
}

TEST_CASE("DataFlash text malformed: no battery messages", "[io-logs]") {
    LogTempDir d;
    std::string t = std::string(kTextFmts) + gps_line(500000000) + gps_line(500000200);
    const std::string e = error_of(Kind::DfText, d.write("nobat.log", t));
    CHECK(e.find("no BAT or CURR messages") != std::string::npos);
    CHECK(error_of(Kind::DfText, d.write("empty.log", "")).find("empty file") != std::string::npos);
}

TEST_CASE("DataFlash text malformed: FMT with a huge or lying length", "[io-logs]") {
    LogTempDir d;
    const std::string huge = "FMT, 9, 100000, CURR, hIhhhf, Thr,ThrInt,Volt,Curr,Vcc,CurrTot\nCURR, 0, 0, 1499, 200, 4940, 1.0\n";
    InputError err("", 0, 0, "");
    bool thrown = false;
    try {
        read_all(Kind::DfText, d.write("huge.log", huge));
    } catch (const InputError& e) {
        err = e;
        thrown = true;
    }
    REQUIRE(thrown);
    CHECK(err.line() == 1);
    CHECK(std::string(err.what()).find("declares length 100000") != std::string::npos);
    const std::string lie = "FMT, 9, 12, CURR, hIhhhf, Thr,ThrInt,Volt,Curr,Vcc,CurrTot\nCURR, 0, 0, 1499, 200, 4940, 1.0\n";
    CHECK(error_of(Kind::DfText, d.write("lie.log", lie)).find("needs 19") != std::string::npos);
}

TEST_CASE("DataFlash text malformed: time going backwards and wrong field count", "[io-logs]") {
    LogTempDir d;
    const std::string t =
        "FMT, 147, 23, BAT, Qfff, TimeUS,Volt,Curr,CurrTot\n"
        "BAT, 1000000, 16.4, 3.0, 1\n"
        "BAT, 2000000, 16.3, 3.0, 2\n"
        "BAT, 1500000, 16.2, 3.0, 3\n"
        "BAT, 2500000, 16.1\n"
        "BAT, 3000000, 16.0, 3.0, 4\n";
    const auto r = read_all(Kind::DfText, d.write("back.log", t));
    REQUIRE(r.samples.size() == 3);
    CHECK(r.samples[2].time_us == 3000000);
    CHECK(r.samples[0].voltage_v == Approx(16.4));  // float Volt: already volts
    CHECK(any_note(r, "line 4: BAT time 1.500000 s goes back"));
    CHECK(any_note(r, "line 5: BAT has 2 values"));
}

TEST_CASE("DataFlash text malformed: a garbled row mid-log is located, not only the preamble", "[io-logs]") {
    // A helper's sweep: the note had named only line 1 (the logger's banner), not the row it
    // had dropped among the battery rows.
    LogTempDir d;
    const std::string t =
        "ArduCopter V3.2\n"
        "FMT, 147, 23, BAT, Qfff, TimeUS,Volt,Curr,CurrTot\n"
        "BAT, 1000000, 16.4, 3.0, 1\n"
        "B\x01T, 2000000, 16.3, 3.0, 2\n"
        "BAT, 3000000, 16.2, 3.0, 3\n";
    const auto r = read_all(Kind::DfText, d.write("garbled.log", t));
    CHECK(r.samples.size() == 2);
    CHECK(any_note(r, "2 line(s) are not messages of a type defined by an FMT line (first: line 1 'ArduCopter V3.2'; "
                      "last: line 4 "));
}

TEST_CASE("DataFlash text malformed: overlong line", "[io-logs]") {
    LogTempDir d;
    const std::string t = std::string(kTextFmts) + std::string(70000, 'x') + "\n";
    CHECK(error_of(Kind::DfText, d.write("long.log", t)).find("longer than") != std::string::npos);
}

// =================================================================================================
// ULog, built byte by byte

TEST_CASE("ULog: minimal battery_status log, padding omitted, other instances ignored", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = ulog_good_prefix() + ulog_sub(1, 4) + ulog_battery(3, 1000000, 16.2f, 5.0f, 31.5f) +
                              ulog_battery(4, 1100000, 12.0f, 1.0f) + ulog_msg('O', std::string("\x0A\x00", 2)) +
                              ulog_battery(3, 1200000, 16.1f, 5.5f, 31.6f);
    const auto r = read_all(Kind::Ulog, d.write("ok.ulg", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[0].time_us == 1000000);
    CHECK(r.samples[0].voltage_v == Approx(16.2));
    CHECK(r.samples[0].current_a == Approx(5.0));
    CHECK(r.samples[0].cell_count == 4);
    CHECK(r.samples[0].cell_voltage_v[3] == Approx(3.93));
    CHECK(r.samples[1].has_temperature);
    CHECK(r.samples[1].temperature_c == Approx(31.6));
    CHECK(r.has_temperature);
    CHECK(any_note(r, "instance 1 ignored"));
    CHECK(any_note(r, "dropouts"));
}

TEST_CASE("ULog: current_a = -1 means unknown: 0 A with a note", "[io-logs]") {
    LogTempDir d;
    const std::string bytes =
        ulog_good_prefix() + ulog_battery(3, 1000000, 16.2f, -1.0f) + ulog_battery(3, 1200000, 16.1f, 4.0f);
    const auto r = read_all(Kind::Ulog, d.write("cur.ulg", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[0].current_a == 0.0f);
    CHECK(r.samples[1].current_a == Approx(4.0));
    CHECK(any_note(r, "current_a = -1"));
}

TEST_CASE("ULog: cells PX4 filled with pack / count are left out; measured ones are kept", "[io-logs]") {
    LogTempDir d;
    // Every cell equal in every sample: what PX4 writes when it measures no cell.
    std::string filled = ulog_good_prefix();
    for (int k = 0; k < 3; ++k) filled += ulog_battery(3, 1000000 + 100000 * k, 15.6f, 5.0f, 20.0f, 4, 3.9f, 0.0f);
    const auto r = read_all(Kind::Ulog, d.write("filled.ulg", filled));
    REQUIRE(r.samples.size() == 3);
    CHECK(r.cell_count == 0);
    for (const auto& s : r.samples) CHECK(s.cell_count == 0);
    CHECK(any_note(r, "are left out"));
    // One sample whose cells differ is a measurement: every sample keeps its cells.
    std::string measured = filled + ulog_battery(3, 1300000, 15.6f, 5.0f, 20.0f, 4, 3.9f);
    const auto m = read_all(Kind::Ulog, d.write("measured.ulg", measured));
    REQUIRE(m.samples.size() == 4);
    CHECK(m.cell_count == 4);
    CHECK(m.samples[0].cell_count == 4);
    CHECK(m.samples[3].cell_voltage_v[3] == Approx(3.93));
    CHECK_FALSE(any_note(m, "per-cell information"));
}

TEST_CASE("ULog: cells only up to cell_count and only while > 0", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = ulog_good_prefix() + ulog_battery(3, 1000000, 8.0f, 1.0f, 20.0f, 2) +
                              ulog_battery(3, 1100000, 8.0f, 1.0f, 20.0f, 4, 0.0f);
    const auto r = read_all(Kind::Ulog, d.write("cells.ulg", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[0].cell_count == 2);
    CHECK(r.samples[1].cell_count == 0);  // first cell is 0 V: no cells
}

TEST_CASE("ULog: float and int32 parameters, defaults ignored, first value kept", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = ulog_header() + ulog_flags() + ulog_msg('F', kBatteryFormat) +
                              ulog_param_f("BAT1_CAPACITY", 5000.0f) + ulog_param_i("BAT1_N_CELLS", 4) +
                              ulog_default_i("BAT1_N_CELLS", 6) + ulog_default_i("BAT1_SOURCE", 1) + ulog_sub(0, 3) +
                              ulog_battery(3, 1000000, 16.2f, 5.0f) + ulog_param_f("BAT1_CAPACITY", 6000.0f) +
                              ulog_param_f("BAT1_R_INTERNAL", 0.005f) + ulog_battery(3, 1100000, 16.1f, 5.0f);
    const auto r = read_all(Kind::Ulog, d.write("param.ulg", bytes));
    CHECK(r.samples.size() == 2);
    REQUIRE(r.info.parameters.size() == 3);
    CHECK(r.info.parameters[0].first == "BAT1_CAPACITY");
    CHECK(r.info.parameters[0].second == 5000.0);  // the later change to 6000 is ignored
    CHECK(r.info.parameters[1].first == "BAT1_N_CELLS");
    CHECK(r.info.parameters[1].second == 4.0);  // not the default 6
    CHECK(r.info.parameters[2].first == "BAT1_R_INTERNAL");  // first seen in the data section
    CHECK(r.info.parameters[2].second == Approx(0.005));
    CHECK(std::isnan(param(r, "BAT1_SOURCE")));  // only a default
    CHECK(r.notes.empty());
}

TEST_CASE("ULog malformed: bad parameter messages are skipped with a note", "[io-logs]") {
    LogTempDir d;
    std::string overrun = ulog_key("float BAT1_CAPACITY");
    overrun[0] = static_cast<char>(60);  // key_len past the end of the message
    std::string wrong_type = ulog_key("double BAT1_V_EMPTY");
    put(wrong_type, 0, 8);
    std::string short_value = ulog_key("float BAT1_V_CHARGED");
    put(short_value, 0, 2);
    const std::string bytes = ulog_good_prefix() + ulog_msg('P', overrun) + ulog_msg('P', wrong_type) +
                              ulog_msg('P', short_value) + ulog_msg('P', ulog_key("BAT1_NO_TYPE") + "abcd") +
                              ulog_msg('P', "") + ulog_param_i("BAT1_N_CELLS", 3) +
                              ulog_battery(3, 1000000, 16.2f, 5.0f);
    const auto r = read_all(Kind::Ulog, d.write("badparam.ulg", bytes));
    CHECK(r.samples.size() == 1);
    REQUIRE(r.info.parameters.size() == 1);
    CHECK(param(r, "BAT1_N_CELLS") == 3.0);
    CHECK(any_note(r, "declares a 60-byte key"));
    CHECK(any_note(r, "BAT1_V_EMPTY has type 'double'"));
    CHECK(any_note(r, "BAT1_V_CHARGED has a 2-byte value, float needs 4"));
    CHECK(any_note(r, "is not 'type name'"));
    CHECK(any_note(r, "parameter message is empty"));
}

TEST_CASE("ULog malformed: truncated header and wrong magic", "[io-logs]") {
    LogTempDir d;
    const std::string h = ulog_header();
    std::string e = error_of(Kind::Ulog, d.write("short.ulg", h.substr(0, 10)));
    CHECK(e.find("truncated ULog header") != std::string::npos);
    CHECK(e.find("10 bytes") != std::string::npos);
    e = error_of(Kind::Ulog, d.write("magic.ulg", "ULog\x02\x12\x35\x01xxxxxxxx"));
    CHECK(e.find("not a ULog file") != std::string::npos);
    CHECK(error_of(Kind::Ulog, d.write("empty.ulg", "")).find("empty file") != std::string::npos);
}

TEST_CASE("ULog malformed: message size past the end of the file", "[io-logs]") {
    LogTempDir d;
    std::string bytes = ulog_good_prefix() + ulog_battery(3, 1000000, 16.2f, 5.0f) +
                        ulog_battery(3, 1100000, 16.1f, 5.0f);
    std::string last = ulog_battery(3, 1200000, 16.0f, 5.0f);
    last[0] = static_cast<char>(0xF0);  // declares 0x??F0 bytes: far more than the file holds
    last[1] = static_cast<char>(0x7F);
    const auto r = read_all(Kind::Ulog, d.write("past.ulg", bytes + last));
    CHECK(r.samples.size() == 2);
    CHECK(any_note(r, "declares 32752 payload bytes but the file ends"));
}

TEST_CASE("ULog malformed: format string with an unclosed array type", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = ulog_header() + ulog_msg('F', "battery_status:uint64_t timestamp;float[4 voltage_v;") +
                              ulog_sub(0, 3);
    const std::string e = error_of(Kind::Ulog, d.write("unclosed.ulg", bytes));
    CHECK(e.find("byte 16") != std::string::npos);
    CHECK(e.find("unclosed") != std::string::npos);
    const std::string no_colon = ulog_header() + ulog_msg('F', "battery_status uint64_t timestamp;");
    CHECK(error_of(Kind::Ulog, d.write("nocolon.ulg", no_colon)).find("no ':'") != std::string::npos);
    const std::string no_type = ulog_header() + ulog_msg('F', "battery_status:timestamp;");
    CHECK(error_of(Kind::Ulog, d.write("notype.ulg", no_type)).find("has no type") != std::string::npos);
}

TEST_CASE("ULog malformed: format larger than any message", "[io-logs]") {
    LogTempDir d;
    const std::string bytes =
        ulog_header() +
        ulog_msg('F', "battery_status:uint64_t timestamp;float voltage_v;float current_a;double[65535] a;") +
        ulog_sub(0, 3);
    CHECK(error_of(Kind::Ulog, d.write("big.ulg", bytes)).find("larger than 65535 bytes") != std::string::npos);
    const std::string nested = ulog_header() + ulog_msg('F', "big:double[65535] a;") +
                               ulog_msg('F', "battery_status:uint64_t timestamp;float voltage_v;float current_a;big[65535] b;") +
                               ulog_sub(0, 3);
    CHECK(error_of(Kind::Ulog, d.write("big2.ulg", nested)).find("larger than 65535 bytes") != std::string::npos);
}

TEST_CASE("ULog malformed: unknown type in battery_status", "[io-logs]") {
    LogTempDir d;
    const std::string bytes =
        ulog_header() + ulog_msg('F', "battery_status:uint64_t timestamp;float voltage_v;float current_a;quux_t q;") +
        ulog_sub(0, 3);
    const std::string e = error_of(Kind::Ulog, d.write("unknown.ulg", bytes));
    CHECK(e.find("unknown type 'quux_t'") != std::string::npos);
}

TEST_CASE("ULog malformed: recursive nested formats", "[io-logs]") {
    LogTempDir d;
    const std::string bytes =
        ulog_header() +
        ulog_msg('F', "battery_status:uint64_t timestamp;float voltage_v;float current_a;loop_a a;") +
        ulog_msg('F', "loop_a:loop_b[2] b;") + ulog_msg('F', "loop_b:uint8_t x;loop_a back;") + ulog_sub(0, 3);
    const std::string e = error_of(Kind::Ulog, d.write("loop.ulg", bytes));
    CHECK(e.find("recursive format definition: battery_status -> loop_a -> loop_b -> loop_a") != std::string::npos);
}

TEST_CASE("ULog: nested formats are sized correctly", "[io-logs]") {
    LogTempDir d;
    // battery_status with a nested struct before voltage_v: 8 + 2*(1+2) = 14 bytes before it.
    std::string data;
    put(data, 3, 2);
    put(data, 500000, 8);
    data += std::string(6, '\x07');
    put_f(data, 15.5f);
    put_f(data, 2.5f);
    const std::string bytes = ulog_header() + ulog_msg('F', "inner:uint8_t a;int16_t b;") +
                              ulog_msg('F', "battery_status:uint64_t timestamp;inner[2] n;float voltage_v;float current_a;") +
                              ulog_sub(0, 3) + ulog_msg('D', data);
    const auto r = read_all(Kind::Ulog, d.write("nested.ulg", bytes));
    REQUIRE(r.samples.size() == 1);
    CHECK(r.samples[0].voltage_v == Approx(15.5));
    CHECK(r.samples[0].current_a == Approx(2.5));
    CHECK(r.samples[0].cell_count == 0);
}

TEST_CASE("ULog malformed: payload missing a real field, NaN voltage, time backwards", "[io-logs]") {
    LogTempDir d;
    std::string shortd = ulog_battery(3, 1100000, 16.1f, 5.0f);
    // Cut the payload to 20 data bytes (the format needs 45 without padding) and fix its size.
    shortd = shortd.substr(0, 3 + 2 + 20);
    shortd[0] = 22;
    shortd[1] = 0;
    const std::string bytes = ulog_good_prefix() + ulog_battery(3, 1000000, 16.2f, 5.0f) + shortd +
                              ulog_battery(3, 1200000, std::numeric_limits<float>::quiet_NaN(), 5.0f) +
                              ulog_battery(3, 900000, 16.0f, 5.0f) + ulog_battery(3, 1300000, 15.9f, 5.0f);
    const auto r = read_all(Kind::Ulog, d.write("bad.ulg", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[1].time_us == 1300000);
    CHECK(any_note(r, "needs at least 45"));
    CHECK(any_note(r, "voltage_v = nan"));
    CHECK(any_note(r, "goes back"));
}

TEST_CASE("ULog malformed: unknown incompatible flag bits are refused", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = ulog_header() + ulog_flags(0x02) + ulog_msg('F', kBatteryFormat) + ulog_sub(0, 3) +
                              ulog_battery(3, 1000000, 16.2f, 5.0f);
    CHECK(error_of(Kind::Ulog, d.write("flags.ulg", bytes)).find("incompatible flag bits") != std::string::npos);
}

TEST_CASE("ULog malformed: no battery_status", "[io-logs]") {
    LogTempDir d;
    const std::string bytes = ulog_header() + ulog_msg('F', "vehicle_status:uint64_t timestamp;uint8_t x;") +
                              ulog_sub(0, 0, "vehicle_status");
    CHECK(error_of(Kind::Ulog, d.write("none.ulg", bytes)).find("no battery_status data") != std::string::npos);
}

TEST_CASE("ULog: appended data after a cut-off message", "[io-logs]") {
    LogTempDir d;
    std::string head = ulog_header();
    std::string flags(8, '\0');
    flags += '\x01';
    flags += std::string(7, '\0');
    const std::string body_prefix = ulog_msg('F', kBatteryFormat) + ulog_sub(0, 3) + ulog_battery(3, 1000000, 16.2f, 5.0f);
    std::string cut = ulog_battery(3, 1100000, 16.1f, 5.0f);
    cut.resize(10);  // interrupted mid-message
    const uint64_t appended_at = head.size() + 3 + 40 + body_prefix.size() + cut.size();
    put(flags, appended_at, 8);
    put(flags, 0, 8);
    put(flags, 0, 8);
    const std::string bytes =
        head + ulog_msg('B', flags) + body_prefix + cut + ulog_battery(3, 1200000, 16.0f, 5.0f);
    const auto r = read_all(Kind::Ulog, d.write("append.ulg", bytes));
    REQUIRE(r.samples.size() == 2);
    CHECK(r.samples[1].time_us == 1200000);
    CHECK(any_note(r, "appended"));
}

TEST_CASE("One corrupt time stamp in a real log costs its own row, not the rest of the log", "[io-logs][data]") {
    LogTempDir d;
    const auto bytes = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    };
    const auto write = [](const std::string& path, const std::string& content) {
        std::ofstream(path, std::ios::binary) << content;
    };
    // log171.bin: one bit of one CURR row's TimeMS flipped, 16,777 s ahead. Before, the 1,383
    // rows after it all "went back" and the replay read a 16,808 s flight.
    const std::string bin = data_path("/ardupilot/log171.bin");
    std::string b = bytes(bin);
    REQUIRE(b.size() > 1268717u);
    b[1268717] = static_cast<char>(b[1268717] ^ 1);
    write(d.path("flip.bin"), b);
    const auto clean = read_all(Kind::DfBinary, bin);
    const auto flipped = read_all(Kind::DfBinary, d.path("flip.bin"));
    CHECK(flipped.samples.size() + 1 == clean.samples.size());
    CHECK(non_decreasing(flipped.samples));
    CHECK(seconds(flipped.samples.back()) == seconds(clean.samples.back()));
    CHECK(any_note(flipped, "byte 1268711: CURR time 16891.816000 s jumps 16777.317 s ahead of the previous row"));
    CHECK(any_note(flipped, "a corrupt time stamp; 1 row dropped"));

    // test.ulg: one battery_status timestamp 1000 s ahead; and one at 2^64 - 1 us, which no
    // uint64 of microseconds holds (it had come out as time 0).
    const std::string ulg = data_path("/px4/test.ulg");
    const auto ulog_clean = read_all(Kind::Ulog, ulg);
    for (const uint64_t bad : {uint64_t{0}, ~uint64_t{0}}) {
        std::string u = bytes(ulg);
        REQUIRE(u.size() > 217638u);
        uint64_t t = 0;
        std::memcpy(&t, &u[217630], 8);  // the shared data is little-endian, and so is this host
        t = bad == 0 ? t + 1000000000u : bad;
        std::memcpy(&u[217630], &t, 8);
        write(d.path("bad.ulg"), u);
        const auto r = read_all(Kind::Ulog, d.path("bad.ulg"));
        INFO(bad);
        CHECK(r.samples.size() + 1 == ulog_clean.samples.size());
        CHECK(non_decreasing(r.samples));
        CHECK(any_note(r, bad == 0 ? "a corrupt time stamp; 1 sample dropped" : "is not a time a log can hold"));
    }
    // ... and the first battery_status 1000 s ahead: before, the other 45 samples all "went back".
    {
        std::string u = bytes(ulg);
        uint64_t t = 0;
        std::memcpy(&t, &u[83777], 8);
        REQUIRE(t == 3268356u);
        t += 1000000000u;
        std::memcpy(&u[83777], &t, 8);
        write(d.path("first.ulg"), u);
        const auto r = read_all(Kind::Ulog, d.path("first.ulg"));
        CHECK(r.samples.size() + 1 == ulog_clean.samples.size());
        CHECK(r.samples.front().time_us == ulog_clean.samples[1].time_us);
        CHECK(any_note(r, "is the log's first, 999.990 s ahead of the samples after it"));
    }

    // robert_lefebvre_octo_PM.log: one digit of one GPS time (its CURR rows take the latest
    // GPS time). The clock had stuck at the bad time: 5,038 s instead of 174 s.
    const std::string txt = data_path("/ardupilot/robert_lefebvre_octo_PM.log");
    std::string t = bytes(txt);
    const size_t at = t.find("594458200");
    REQUIRE(at != std::string::npos);
    t[at + 2] = '9';  // 599458200: 5,000 s ahead
    write(d.path("gps.log"), t);
    const auto gps_clean = read_all(Kind::DfText, txt);
    const auto gps = read_all(Kind::DfText, d.path("gps.log"));
    REQUIRE(gps.samples.size() == gps_clean.samples.size());
    CHECK(seconds(gps.samples.back()) == seconds(gps_clean.samples.back()));
}

TEST_CASE("ULog: a message size that lied costs the bytes to the next sync message, said", "[io-logs][data]") {
    LogTempDir d;
    const std::string ulg = data_path("/px4/test.ulg");
    std::ifstream in(ulg, std::ios::binary);
    const std::string clean((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto with_size = [&](size_t at, uint16_t size) {
        std::string u = clean;
        REQUIRE(u.size() > at + 2);
        u[at] = static_cast<char>(size & 0xFF);
        u[at + 1] = static_cast<char>(size >> 8);
        const std::string path = d.path("lied.ulg");
        std::ofstream(path, std::ios::binary) << u;
        return path;
    };
    // A data message of 47 bytes said to be 2: the next header falls inside its payload. Before,
    // the reader never found its place again and kept 4 of the 46 samples.
    REQUIRE(clean[105246] == 'D');
    const auto r = read_all(Kind::Ulog, with_size(105244, 2));
    CHECK(r.samples.size() == 44);
    CHECK(non_decreasing(r.samples));
    CHECK(any_note(r, "byte 105249: a message header of type ':', which no ULog message has: the log is corrupt "
                      "before it (a message size that lied); skipped 13967 bytes to the next sync message at byte "
                      "119216"));
    // Early in the log the lost bytes held the subscription: the error says the log is corrupt.
    REQUIRE(clean[56534] == 'Q');
    CHECK(error_of(Kind::Ulog, with_size(56532, 2)) ==
          d.path("lied.ulg") + ": no battery_status data (multi_id 0) in this ULog: the topic is not logged (or not "
                               "where it can be read: the log is corrupt at byte 56537, and 28232 bytes were skipped "
                               "to find its messages again)");
}

TEST_CASE("DataFlash text: a BCL cell that reads nothing before one that reads, and text for millivolts, are said", "[io-logs]") {
    // Both had ended the cells there without a word: the log read as 2 cells, every sample
    // then kept out by the cell-sum check.
    LogTempDir d;
    const std::string fmts = "FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns\n"
                             "FMT, 147, 38, BAT, QBfffffcf, TimeUS,Inst,Volt,VoltR,Curr,CurrTot,EnrgTot,Temp,Res\n"
                             "FMT, 150, 24, BCL, QBfHHHH, TimeUS,Instance,Volt,V1,V2,V3,V4\n";
    const std::string bat0 = "BAT, 0, 0, 16.8, 16.8, 0.5, 0, 0, 25.0, 0.02\n";
    const std::string bat1 = "BAT, 100000, 0, 16.8, 16.8, 0.5, 0, 0, 25.0, 0.02\n";
    const auto hole = read_all(Kind::DfText, d.write("hole.log", fmts + bat0 + "BCL, 0, 0, 16.8, 4200, 4200, nan, 4200\n" + bat1));
    CHECK(any_note(hole, "line 5 column 7: BCL.V3 reads 'nan' while a later cell reads a voltage"));
    // Text where the millivolts belong: that row is skipped, the cells before it stand.
    const auto text = read_all(Kind::DfText, d.write("text.log", fmts + "BCL, 0, 0, 16.8, 4200, 4200, 4200, 4200\n" + bat0 +
                                                                     "BCL, 50000, 0, 16.8, 4200, 4200, abc, 4200\n" + bat1));
    CHECK(any_note(text, "line 6 column 7: BCL.V3: expected a number, found 'abc'; cell row skipped"));
    REQUIRE(text.samples.size() == 2);
    CHECK(text.samples[1].cell_count == 4);
    // The pack's last cells unused (0): the end of its cells, no note.
    const auto three = read_all(Kind::DfText, d.write("three.log", fmts + "BCL, 0, 0, 12.6, 4200, 4200, 4200, 0\n" + bat0));
    CHECK_FALSE(any_note(three, "BCL.V4"));
    CHECK(three.samples[0].cell_count == 3);
}

TEST_CASE("A binary log cut short before its battery data says it is cut short", "[io-logs][data]") {
    // It had said "the topic is not logged" / "no BAT or CURR messages" of a file cut in two.
    LogTempDir d;
    const auto head_of = [&](const std::string& from, const std::string& name, size_t bytes) {
        std::ifstream in(from, std::ios::binary);
        std::string data(bytes, '\0');
        in.read(&data[0], static_cast<std::streamsize>(bytes));
        return d.write(name, data);
    };
    const std::string ulog = head_of(data_path("/px4/test.ulg"), "cut.ulg", 60000);
    CHECK_THAT(error_of(Kind::Ulog, ulog), Catch::Contains("no battery_status data") &&
                                               Catch::Contains("the file ends inside a message at byte") &&
                                               Catch::Contains("cut short"));
    // Nor does it say the topic is not logged, which the part missing may hold.
    CHECK_THAT(error_of(Kind::Ulog, ulog), !Catch::Contains("not logged"));
    const std::string bin = head_of(data_path("/ardupilot/log171.bin"), "cut.bin", 1000);
    CHECK_THAT(error_of(Kind::DfBinary, bin), Catch::Contains("no BAT or CURR messages") && Catch::Contains("cut short"));
}
