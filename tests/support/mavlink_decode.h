// A MAVLink 2 stream reader for the tests, written apart from src/telemetry so the two
// check each other: its checksum is the bitwise CRC-16/MCRF4XX (reflected polynomial
// 0x8408), not the spec's byte-wise accumulate the encoder uses, and its field offsets
// are typed in from the message definitions again. Also reads .tlog (8-byte big-endian µs
// before each frame).
#pragma once
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace mavtest {

inline uint16_t crc_bitwise(const uint8_t* p, size_t n, uint16_t crc = 0xFFFF) {
    for (size_t i = 0; i < n; ++i) {
        crc ^= p[i];
        for (int b = 0; b < 8; ++b) crc = (crc & 1) ? static_cast<uint16_t>((crc >> 1) ^ 0x8408) : static_cast<uint16_t>(crc >> 1);
    }
    return crc;
}

struct Frame {
    uint64_t tlog_time_us = 0;
    uint8_t seq = 0, sysid = 0, compid = 0;
    uint32_t msgid = 0;
    size_t wire_length = 0;        // payload bytes on the wire (trailing zeros dropped)
    std::vector<uint8_t> payload;  // zero-filled back to the message's full length
};

struct Stream {
    std::vector<Frame> frames;
    std::string error;  // empty: every byte was a valid frame
};

inline Stream decode(const std::string& bytes, bool tlog) {
    static const std::map<uint32_t, std::pair<uint8_t, size_t>> known = {
        {0, {50, 9}}, {147, {154, 54}}, {253, {83, 54}}};  // id → CRC_EXTRA, full length
    Stream s;
    const auto* d = reinterpret_cast<const uint8_t*>(bytes.data());
    size_t i = 0;
    while (i < bytes.size()) {
        Frame f;
        if (tlog) {
            if (i + 8 > bytes.size()) return s.error = "cut-off tlog time at byte " + std::to_string(i), s;
            for (int k = 0; k < 8; ++k) f.tlog_time_us = (f.tlog_time_us << 8) | d[i + k];
            i += 8;
        }
        if (i + 12 > bytes.size() || d[i] != 0xFD) return s.error = "no MAVLink 2 frame at byte " + std::to_string(i), s;
        const size_t len = d[i + 1];
        if (i + 12 + len > bytes.size()) return s.error = "cut-off frame at byte " + std::to_string(i), s;
        if (d[i + 2] != 0 || d[i + 3] != 0) return s.error = "flags set at byte " + std::to_string(i), s;
        f.seq = d[i + 4];
        f.sysid = d[i + 5];
        f.compid = d[i + 6];
        f.msgid = d[i + 7] | (d[i + 8] << 8) | (static_cast<uint32_t>(d[i + 9]) << 16);
        const auto k = known.find(f.msgid);
        if (k == known.end()) return s.error = "unknown message " + std::to_string(f.msgid), s;
        uint16_t crc = crc_bitwise(d + i + 1, 9 + len);
        crc = crc_bitwise(&k->second.first, 1, crc);
        const uint16_t sent = static_cast<uint16_t>(d[i + 10 + len] | (d[i + 11 + len] << 8));
        if (crc != sent) return s.error = "bad checksum at byte " + std::to_string(i), s;
        f.wire_length = len;
        f.payload.assign(d + i + 10, d + i + 10 + len);
        f.payload.resize(k->second.second, 0);
        s.frames.push_back(f);
        i += 12 + len;
    }
    return s;
}

inline uint16_t u16(const Frame& f, size_t at) { return static_cast<uint16_t>(f.payload[at] | (f.payload[at + 1] << 8)); }
inline uint32_t u32(const Frame& f, size_t at) {
    return f.payload[at] | (f.payload[at + 1] << 8) | (f.payload[at + 2] << 16) | (static_cast<uint32_t>(f.payload[at + 3]) << 24);
}

// BATTERY_STATUS, offsets from common.xml's field order (sorted by size, extensions last).
struct Battery {
    int32_t current_consumed_mah, energy_consumed_hj;
    int16_t temperature_cdegc;
    uint16_t voltages_mv[10];
    int16_t current_ca;
    uint8_t id, function, type;
    int8_t remaining_pct;
    int32_t time_remaining_s;
    uint8_t charge_state;
    uint16_t voltages_ext_mv[4];
    uint8_t mode;
    uint32_t fault_bitmask;
};
inline Battery battery(const Frame& f) {
    Battery b;
    b.current_consumed_mah = static_cast<int32_t>(u32(f, 0));
    b.energy_consumed_hj = static_cast<int32_t>(u32(f, 4));
    b.temperature_cdegc = static_cast<int16_t>(u16(f, 8));
    for (int c = 0; c < 10; ++c) b.voltages_mv[c] = u16(f, 10 + 2 * c);
    b.current_ca = static_cast<int16_t>(u16(f, 30));
    b.id = f.payload[32];
    b.function = f.payload[33];
    b.type = f.payload[34];
    b.remaining_pct = static_cast<int8_t>(f.payload[35]);
    b.time_remaining_s = static_cast<int32_t>(u32(f, 36));
    b.charge_state = f.payload[40];
    for (int c = 0; c < 4; ++c) b.voltages_ext_mv[c] = u16(f, 41 + 2 * c);
    b.mode = f.payload[49];
    b.fault_bitmask = u32(f, 50);
    return b;
}

// STATUSTEXT: severity, then up to 50 characters.
inline std::string text(const Frame& f, uint8_t* severity = nullptr) {
    if (severity) *severity = f.payload[0];
    const char* t = reinterpret_cast<const char*>(f.payload.data() + 1);
    return std::string(t, strnlen(t, 50));
}

}  // namespace mavtest
