// What the monitor knows, sent as MAVLink 2 so that it reaches the pilot in flight: a ground
// station shows BATTERY_STATUS in its battery panel and speaks STATUSTEXT, and an
// autopilot with a MAVLink battery backend can take BATTERY_STATUS as its battery.
// Embedded-clean like src/core (no heap, no exceptions, fixed buffers), and shared by the
// firmware (its telemetry UART) and `battsim replay --mavlink/--tlog`, so the device and the
// host send the same bytes for the same log.
//
// Written from the MAVLink 2 serialisation spec and the common.xml message definitions:
// frame = 0xFD, len, incompat flags, compat flags, seq, sysid, compid, msgid (24-bit LE),
// payload (fields by size, extensions last; trailing zero bytes dropped), CRC-16/MCRF4XX
// over everything after 0xFD plus the message's CRC_EXTRA byte.
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "core/config.h"
#include "core/monitor.h"
#include "core/sample.h"
#include "telemetry/warning_schedule.h"
#include "telemetry/wiring_check.h"

namespace battsim {
namespace telemetry {

// The messages sent: id and CRC_EXTRA (common.xml), and the full payload length.
constexpr uint32_t kHeartbeatId = 0;
constexpr uint8_t kHeartbeatCrcExtra = 50;
constexpr size_t kHeartbeatLength = 9;
constexpr uint32_t kBatteryStatusId = 147;
constexpr uint8_t kBatteryStatusCrcExtra = 154;
constexpr size_t kBatteryStatusLength = 54;
constexpr uint32_t kStatusTextId = 253;
constexpr uint8_t kStatusTextCrcExtra = 83;
constexpr size_t kStatusTextLength = 54;
constexpr size_t kStatusTextChars = 50;

constexpr size_t kMaxPayloadBytes = 54;
constexpr size_t kFrameOverheadBytes = 12;  // 10 header + 2 checksum (unsigned frames)
constexpr size_t kMaxFrameBytes = kMaxPayloadBytes + kFrameOverheadBytes;

// Enum values used (common.xml).
constexpr uint8_t kMavTypeBattery = 36;
constexpr uint8_t kMavAutopilotInvalid = 8;
constexpr uint8_t kMavStateStandby = 3;
constexpr uint8_t kMavStateActive = 4;
constexpr uint8_t kMavCompIdBattery = 180;
constexpr uint8_t kMavSeverityWarning = 4;
constexpr uint8_t kMavSeverityNotice = 5;
constexpr uint8_t kBatteryFunctionAll = 1;
constexpr uint8_t kBatteryTypeLipo = 1;
enum ChargeState : uint8_t {
    kChargeUndefined = 0,
    kChargeOk = 1,
    kChargeLow = 2,
    kChargeCritical = 3,
    kChargeUnhealthy = 6,
};
constexpr uint32_t kFaultCellFail = 4;  // MAV_BATTERY_FAULT_CELL_FAIL

// MAVLink's checksum (CRC-16/MCRF4XX, the spec's "X.25" accumulate), continued from `crc`.
uint16_t mavlink_crc(const uint8_t* data, size_t length, uint16_t crc = 0xFFFFu);

// Frames payloads as MAVLink 2 (unsigned) and counts the sequence.
class MavlinkFramer {
public:
    void configure(uint8_t system_id, uint8_t component_id);
    // Writes the frame of `payload` (`length` ≤ kMaxPayloadBytes, the message's full length)
    // into `out` (room for kMaxFrameBytes); returns its length.
    size_t frame(uint32_t message_id, uint8_t crc_extra, const uint8_t* payload, size_t length, uint8_t* out);

private:
    uint8_t system_id_ = 1;
    uint8_t component_id_ = kMavCompIdBattery;
    uint8_t sequence_ = 0;
};

// BATTERY_STATUS in MAVLink's own units; the defaults are its "unknown" values.
struct BatteryStatusFields {
    int32_t current_consumed_mah = -1;
    int32_t energy_consumed_hj = -1;   // hectojoules
    int16_t temperature_cdegc = 0x7FFF;  // INT16_MAX: unknown
    uint16_t voltages_mv[10] = {0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF};
    int16_t current_ca = -1;           // centiamperes
    uint8_t id = 0;
    uint8_t battery_function = kBatteryFunctionAll;
    uint8_t type = kBatteryTypeLipo;
    int8_t remaining_pct = -1;
    int32_t time_remaining_s = 0;      // 0: no estimate
    uint8_t charge_state = kChargeUndefined;
    uint16_t voltages_ext_mv[4] = {};  // cells 11–14; 0: none
    uint8_t mode = 0;
    uint32_t fault_bitmask = 0;
};
// Wire layout of the full payload (kBatteryStatusLength bytes).
void pack_battery_status(const BatteryStatusFields& f, uint8_t* payload);

struct TelemetryConfig {
    uint8_t system_id = 1;                     // the vehicle's, so a ground station files the battery under it
    uint8_t component_id = kMavCompIdBattery;  // MAV_COMP_ID_BATTERY
    uint8_t battery_id = 0;                    // BATTERY_STATUS.id: 1 if the autopilot reports its own battery 0
    float interval_s = 1.0f;                   // HEARTBEAT and BATTERY_STATUS period
    float low_time_s = 60.0f;                  // charge_state LOW below this remaining flight time
    float critical_time_s = 20.0f;             // CRITICAL below this
    float text_repeat_s = 30.0f;               // in flight, a warning still active is texted again after this (0: once)
    float clear_hold_s = 5.0f;                 // in flight, a told verdict off this long is withdrawn (0: never)
};

constexpr const char* kReversedText = "battsim: current reversed, swap shunt sense wires";

// The monitor's status in BATTERY_STATUS terms (docs/telemetry.md gives each field's source).
BatteryStatusFields battery_status_fields(const TelemetryConfig& config, const core::Sample& sample,
                                          const core::MonitorStatus& status);

// The sentence a ground station shows and speaks when warning `w` is raised, written to
// `text` (room for kStatusTextChars + 1: at most that many characters and a NUL); returns
// its length.
// The rated capacity and resistance are the config's (`battery`), against which the
// monitor judged the pack.
size_t warning_text(core::Warning w, float rated_capacity_ah, float rated_resistance_ohm,
                    const core::MonitorStatus& status, char* text);

// The sentence that withdraws warning `w` (WarningSchedule's withdrawable ones) once its
// verdict no longer holds in flight, with the estimate now; as warning_text.
size_t withdrawal_text(core::Warning w, float rated_capacity_ah, float rated_resistance_ohm,
                       const core::MonitorStatus& status, char* text);

// What goes out after each monitor update: HEARTBEAT and BATTERY_STATUS every interval
// of the samples' own time (the first sample sends at once), and a STATUSTEXT at severity
// WARNING when WarningSchedule says a warning is due (raised; repeated in flight), and one at
// NOTICE when it withdraws a verdict. A warning is told or withdrawn, never both at once.
// Once a boot, at WARNING, kReversedText when the current reads reversed (wiring_check.h):
// the monitor then sees no flight, and no verdict would ever come.
class MavlinkTelemetry {
public:
    // HEARTBEAT, BATTERY_STATUS, a text per warning and the wiring's text.
    static constexpr size_t kMaxBytesPerUpdate = (3 + core::kWarnCount) * kMaxFrameBytes;

    void configure(const TelemetryConfig& config, const core::MonitorConfig& monitor);
    // Writes the frames due at this sample into `out` (room for kMaxBytesPerUpdate);
    // returns the bytes written (0 when nothing is due).
    size_t update(const core::Sample& sample, const core::MonitorStatus& status, uint8_t* out);

private:
    TelemetryConfig config_;
    float rated_capacity_ah_ = 0.0f;
    float rated_resistance_ohm_ = 0.0f;
    MavlinkFramer framer_;
    uint64_t interval_us_ = 1000000u;
    uint64_t next_us_ = 0;
    bool started_ = false;
    WarningSchedule schedule_;
    ReversedCurrentCheck reversed_;
};

}  // namespace telemetry
}  // namespace battsim
