#include "telemetry/mavlink.h"

#include <math.h>
#include <string.h>

#include "core/cells/cell_analyzer.h"
#include "core/estimate/joint_estimator.h"
#include "telemetry/text_buffer.h"

namespace battsim {
namespace telemetry {
namespace {

// Little-endian field writers: the wire order whatever the host's.
void put_u16(uint8_t* p, uint16_t v) {
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}
void put_u32(uint8_t* p, uint32_t v) {
    for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

// Rounded and held inside the field's range (NaN reads as `fallback`).
int32_t rounded(float v, int32_t lo, int32_t hi, int32_t fallback) {
    if (!(v == v)) return fallback;
    const float r = roundf(v);
    if (r <= static_cast<float>(lo)) return lo;
    if (r >= static_cast<float>(hi)) return hi;
    return static_cast<int32_t>(r);
}

uint16_t millivolts(float voltage_v) {
    return static_cast<uint16_t>(rounded(voltage_v * 1000.0f, 0, 0xFFFE, 0xFFFF));
}

uint32_t percent_of(float value, float rated) {
    if (!(rated > 0.0f)) return 0;
    return static_cast<uint32_t>(rounded(100.0f * value / rated, 0, 99999, 0));
}

// "1.05 Ah (68" and "34 mOhm (168": an estimate and its share of the rated value, as the
// warning and its withdrawal both say it (the caller closes the bracket).
void append_capacity(TextBuffer& t, const core::MonitorStatus& status, float rated_capacity_ah) {
    t.append_fixed(rounded(status.capacity_ah * 100.0f, 0, 999999, 0), 2);
    t.append(" Ah (");
    t.append_uint(percent_of(status.capacity_ah, rated_capacity_ah));
}
void append_resistance(TextBuffer& t, const core::MonitorStatus& status, float rated_resistance_ohm) {
    t.append_uint(static_cast<uint32_t>(rounded(status.resistance_ohm * 1000.0f, 0, 999999, 0)));
    t.append(" mOhm (");
    t.append_uint(percent_of(status.resistance_ohm, rated_resistance_ohm));
}

// The verdict's shortfall, % of a healthy pack's flight; false when the flight is not short
// by a whole percent. A total of 0 (no flight left from the take-off charge) is 100 %.
bool shortfall_percent(const core::MonitorStatus& status, uint32_t& percent) {
    if (!(status.expected_time_s > 0.0f && status.total_time_s >= 0.0f && status.total_time_s < status.expected_time_s))
        return false;
    percent = percent_of(status.expected_time_s - status.total_time_s, status.expected_time_s);
    return percent > 0;
}

}  // namespace

uint16_t mavlink_crc(const uint8_t* data, size_t length, uint16_t crc) {
    for (size_t i = 0; i < length; ++i) {
        uint8_t t = static_cast<uint8_t>(data[i] ^ (crc & 0xFFu));
        t = static_cast<uint8_t>(t ^ (t << 4));
        crc = static_cast<uint16_t>((crc >> 8) ^ (static_cast<uint16_t>(t) << 8) ^ (static_cast<uint16_t>(t) << 3) ^ (t >> 4));
    }
    return crc;
}

void MavlinkFramer::configure(uint8_t system_id, uint8_t component_id) {
    system_id_ = system_id;
    component_id_ = component_id;
    sequence_ = 0;
}

size_t MavlinkFramer::frame(uint32_t message_id, uint8_t crc_extra, const uint8_t* payload, size_t length, uint8_t* out) {
    if (length > kMaxPayloadBytes) length = kMaxPayloadBytes;
    // MAVLink 2 drops trailing zero bytes; the receiver fills them back. One byte stays.
    while (length > 1 && payload[length - 1] == 0) --length;
    out[0] = 0xFD;
    out[1] = static_cast<uint8_t>(length);
    out[2] = 0;  // incompatibility flags: unsigned
    out[3] = 0;  // compatibility flags
    out[4] = sequence_++;
    out[5] = system_id_;
    out[6] = component_id_;
    out[7] = static_cast<uint8_t>(message_id);
    out[8] = static_cast<uint8_t>(message_id >> 8);
    out[9] = static_cast<uint8_t>(message_id >> 16);
    memcpy(out + 10, payload, length);
    uint16_t crc = mavlink_crc(out + 1, 9 + length);
    crc = mavlink_crc(&crc_extra, 1, crc);
    put_u16(out + 10 + length, crc);
    return length + kFrameOverheadBytes;
}

void pack_battery_status(const BatteryStatusFields& f, uint8_t* p) {
    memset(p, 0, kBatteryStatusLength);
    put_u32(p + 0, static_cast<uint32_t>(f.current_consumed_mah));
    put_u32(p + 4, static_cast<uint32_t>(f.energy_consumed_hj));
    put_u16(p + 8, static_cast<uint16_t>(f.temperature_cdegc));
    for (int i = 0; i < 10; ++i) put_u16(p + 10 + 2 * i, f.voltages_mv[i]);
    put_u16(p + 30, static_cast<uint16_t>(f.current_ca));
    p[32] = f.id;
    p[33] = f.battery_function;
    p[34] = f.type;
    p[35] = static_cast<uint8_t>(f.remaining_pct);
    // Extensions, in their declared order.
    put_u32(p + 36, static_cast<uint32_t>(f.time_remaining_s));
    p[40] = f.charge_state;
    for (int i = 0; i < 4; ++i) put_u16(p + 41 + 2 * i, f.voltages_ext_mv[i]);
    p[49] = f.mode;
    put_u32(p + 50, f.fault_bitmask);
}

BatteryStatusFields battery_status_fields(const TelemetryConfig& config, const core::Sample& sample,
                                          const core::MonitorStatus& status) {
    BatteryStatusFields f;
    f.id = config.battery_id;
    if (sample.cell_count > 0 && status.cells_valid) {
        for (int c = 0; c < sample.cell_count && c < core::kMaxCells; ++c) {
            const uint16_t mv = millivolts(sample.cell_voltage_v[c]);
            if (c < 10) {
                f.voltages_mv[c] = mv;
            } else {
                f.voltages_ext_mv[c - 10] = mv == 0 ? 1 : mv;  // 0 means "no cell" here
            }
        }
    } else {
        // No cells (or cells kept out): the pack in cell 0, split across cells 0 and 1
        // above 65.534 V as the message asks.
        const int32_t mv = rounded(sample.voltage_v * 1000.0f, 0, 2 * 0xFFFE, 0);
        f.voltages_mv[0] = static_cast<uint16_t>(mv > 0xFFFE ? 0xFFFE : mv);
        if (mv > 0xFFFE) f.voltages_mv[1] = static_cast<uint16_t>(mv - 0xFFFE);
    }
    f.current_ca = static_cast<int16_t>(rounded(sample.current_a * 100.0f, -32767, 32767, -1));
    if (sample.has_temperature) f.temperature_cdegc = static_cast<int16_t>(rounded(sample.temperature_c * 100.0f, -32767, 32766, 0x7FFF));
    if (status.initialised) {
        f.current_consumed_mah = rounded(status.consumed_mah, -2147483647, 2147483647, -1);
        f.energy_consumed_hj = rounded(status.consumed_mwh * 0.036f, -2147483647, 2147483647, -1);  // 1 mWh = 3.6 J
        f.remaining_pct = static_cast<int8_t>(rounded(status.soc * 100.0f, 0, 100, -1));
    }
    if (status.time_valid) f.time_remaining_s = rounded(status.remaining_time_s, 1, 2147483647, 0);  // ≥ 1: 0 says "none"
    constexpr uint8_t kHealth = (1u << core::kWarnLowCapacity) | (1u << core::kWarnHighResistance) |
                                (1u << core::kWarnCellOutlier) | (1u << core::kWarnShortFlight);
    if (!status.initialised) {
        f.charge_state = kChargeUndefined;
    } else if (status.time_valid && status.remaining_time_s < config.critical_time_s) {
        f.charge_state = kChargeCritical;
    } else if (status.time_valid && status.remaining_time_s < config.low_time_s) {
        f.charge_state = kChargeLow;
    } else if (!status.flying && (status.warnings & kHealth)) {
        // On the ground only: an autopilot may act on UNHEALTHY, which in flight would
        // abort for a verdict the pilot should weigh (the STATUSTEXT says it in flight).
        f.charge_state = kChargeUnhealthy;
    } else {
        f.charge_state = kChargeOk;
    }
    if (status.warnings & (1u << core::kWarnCellOutlier)) f.fault_bitmask |= kFaultCellFail;
    return f;
}

size_t warning_text(core::Warning w, float rated_capacity_ah, float rated_resistance_ohm,
                    const core::MonitorStatus& status, char* out) {
    // Integer formatting only: printf's float support costs flash on the ESP8266. What does
    // not fit the message's 50 characters is cut off.
    TextBuffer t(out, kStatusTextChars + 1);
    uint32_t percent = 0;
    t.append("battsim: ");
    switch (w) {
        case core::kWarnShortFlight:
            t.append("flight ");
            if (shortfall_percent(status, percent)) {
                t.append_uint(percent);
                t.append("% ");
            }
            t.append("short");
            if (status.short_flight_cause & core::JointEstimator::kCauseCapacity) {
                t.append(", capacity ");
                t.append_uint(percent_of(status.capacity_ah, rated_capacity_ah));
                t.append("%");
            }
            if (status.short_flight_cause & core::JointEstimator::kCauseResistance) {
                t.append(", R ");
                t.append_uint(percent_of(status.resistance_ohm, rated_resistance_ohm));
                t.append("%");
            }
            break;
        case core::kWarnLowCapacity:
            t.append("low capacity ");
            append_capacity(t, status, rated_capacity_ah);
            t.append("% of rated)");
            break;
        case core::kWarnHighResistance:
            t.append("high resistance ");
            append_resistance(t, status, rated_resistance_ohm);
            t.append("%)");
            break;
        case core::kWarnCellOutlier:
            t.append("cell ");
            t.append_uint(static_cast<uint32_t>(status.outlier_cell >= 0 ? status.outlier_cell + 1 : 0));
            if (status.cell_finding == core::CellAnalyzer::kLowCapacity) {
                t.append(" weak: low capacity");
            } else if (status.cell_finding == core::CellAnalyzer::kHighResistance) {
                t.append(" weak: high resistance");
            } else {
                t.append(" differs from the others");
            }
            break;
        case core::kWarnSensorFault:
            // The first cause that holds: a pilot can reseat a connector, recalibrate a
            // sensor or ignore a log hiccup, and needs to know which.
            t.append("sensor fault");
            if (status.sensor_fault_cause & core::kFaultReading) {
                t.append(": reading out of range");
            } else if (status.sensor_fault_cause & core::kFaultCells) {
                t.append(": cell reading out of range");
            } else if (status.sensor_fault_cause & core::kFaultCurrentOffset) {
                t.append(": current offset ");
                t.append_fixed(rounded(status.current_offset_a * 100.0f, -99999, 99999, 0), 2);
                t.append(" A");
            } else if (status.sensor_fault_cause & core::kFaultSampleGap) {
                t.append(": no reading for ");
                t.append_fixed(rounded(status.dt_s * 10.0f, 0, 99999, 0), 1);
                t.append(" s");
            }
            break;
        default:
            break;
    }
    return t.size();
}

size_t withdrawal_text(core::Warning w, float rated_capacity_ah, float rated_resistance_ohm,
                       const core::MonitorStatus& status, char* out) {
    TextBuffer t(out, kStatusTextChars + 1);
    uint32_t percent = 0;
    t.append("battsim: ");
    switch (w) {
        case core::kWarnShortFlight:
            // What the verdict reads now: the pilot weighs "12% short" differently from none.
            t.append("short flight cleared, ");
            if (shortfall_percent(status, percent)) {
                t.append_uint(percent);
                t.append("% short now");
            } else {
                t.append("not short now");
            }
            break;
        case core::kWarnLowCapacity:
            t.append("low capacity cleared, ");
            append_capacity(t, status, rated_capacity_ah);
            t.append("%)");
            break;
        case core::kWarnHighResistance:
            t.append("high resistance cleared, ");
            append_resistance(t, status, rated_resistance_ohm);
            t.append("%)");
            break;
        default:
            break;
    }
    return t.size();
}

void MavlinkTelemetry::configure(const TelemetryConfig& config, const core::MonitorConfig& monitor) {
    config_ = config;
    rated_capacity_ah_ = monitor.battery.capacity_ah;
    rated_resistance_ohm_ = monitor.battery.internal_resistance_ohm;
    framer_.configure(config.system_id, config.component_id);
    const float interval_us = config.interval_s > 0.0f ? config.interval_s * 1.0e6f : 1.0e6f;
    interval_us_ = static_cast<uint64_t>(interval_us);
    schedule_.configure(config.text_repeat_s, config.clear_hold_s, monitor);
    reversed_.configure(monitor.flying.min_flying_current_a);
    next_us_ = 0;
    started_ = false;
}

size_t MavlinkTelemetry::update(const core::Sample& sample, const core::MonitorStatus& status, uint8_t* out) {
    size_t n = 0;
    uint8_t payload[kMaxPayloadBytes];
    if (!started_ || status.time_us >= next_us_) {
        // From the samples' own time, so a replay sends what the device sent.
        next_us_ = started_ ? next_us_ + interval_us_ : status.time_us + interval_us_;
        if (next_us_ <= status.time_us) next_us_ = status.time_us + interval_us_;  // after a gap: no burst
        started_ = true;
        memset(payload, 0, kHeartbeatLength);
        // custom_mode 0; type, autopilot, base_mode 0, system_status, mavlink_version 3
        payload[4] = kMavTypeBattery;
        payload[5] = kMavAutopilotInvalid;
        payload[7] = status.flying ? kMavStateActive : kMavStateStandby;
        payload[8] = 3;
        n += framer_.frame(kHeartbeatId, kHeartbeatCrcExtra, payload, kHeartbeatLength, out + n);
        pack_battery_status(battery_status_fields(config_, sample, status), payload);
        n += framer_.frame(kBatteryStatusId, kBatteryStatusCrcExtra, payload, kBatteryStatusLength, out + n);
    }
    const uint8_t due = schedule_.due(status);
    for (int w = 0; w < core::kWarnCount; ++w) {
        if (!(due & (1u << w))) continue;
        schedule_.told(w, status.time_us);
        memset(payload, 0, kStatusTextLength);
        payload[0] = kMavSeverityWarning;
        warning_text(static_cast<core::Warning>(w), rated_capacity_ah_, rated_resistance_ohm_, status,
                     reinterpret_cast<char*>(payload + 1));
        // text is char[50], NUL-terminated only when shorter; id 0 and chunk_seq 0: one chunk
        n += framer_.frame(kStatusTextId, kStatusTextCrcExtra, payload, kStatusTextLength, out + n);
    }
    if (!reversed_.reversed() && reversed_.update(sample.time_us, sample.current_a)) {
        memset(payload, 0, kStatusTextLength);
        payload[0] = kMavSeverityWarning;
        TextBuffer t(reinterpret_cast<char*>(payload + 1), kStatusTextChars + 1);
        t.append(kReversedText);
        n += framer_.frame(kStatusTextId, kStatusTextCrcExtra, payload, kStatusTextLength, out + n);
    }
    const uint8_t withdrawn = schedule_.withdrawn();
    for (int w = 0; w < core::kWarnCount; ++w) {
        if (!(withdrawn & (1u << w))) continue;
        memset(payload, 0, kStatusTextLength);
        payload[0] = kMavSeverityNotice;
        withdrawal_text(static_cast<core::Warning>(w), rated_capacity_ah_, rated_resistance_ohm_, status,
                        reinterpret_cast<char*>(payload + 1));
        n += framer_.frame(kStatusTextId, kStatusTextCrcExtra, payload, kStatusTextLength, out + n);
    }
    return n;
}

}  // namespace telemetry
}  // namespace battsim
