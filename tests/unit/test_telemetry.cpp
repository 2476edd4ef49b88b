// The MAVLink telemetry (src/telemetry): checksum against a published frame, frames by
// hand, BATTERY_STATUS fields from a status, when frames go out, and the warnings' texts.
// The stream is read back with tests/support/mavlink_decode.h, written apart from the encoder.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "core/cells/cell_analyzer.h"
#include "core/estimate/joint_estimator.h"
#include "mavlink_decode.h"
#include "telemetry/mavlink.h"

using namespace battsim;

namespace {

std::string run(telemetry::MavlinkTelemetry& t, const core::Sample& s, const core::MonitorStatus& st) {
    uint8_t out[telemetry::MavlinkTelemetry::kMaxBytesPerUpdate];
    const size_t n = t.update(s, st, out);
    return std::string(reinterpret_cast<const char*>(out), n);
}

core::MonitorConfig rated_4s() {
    core::MonitorConfig m;
    m.battery.capacity_ah = 1.55f;
    m.battery.internal_resistance_ohm = 0.02f;
    return m;
}

}  // namespace

TEST_CASE("Telemetry: the checksum reproduces a published heartbeat frame's", "[telemetry]") {
    // A MAVLink 1 heartbeat as printed in a public walk-through of the protocol:
    // FE 09 4E 01 01 00 | 00 00 00 00 02 03 51 04 03 | 1C 7F. The checksum covers every
    // byte after the start byte and then HEARTBEAT's CRC_EXTRA, 50; it is sent low byte first.
    const uint8_t covered[] = {0x09, 0x4E, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x03, 0x51, 0x04, 0x03};
    uint16_t crc = telemetry::mavlink_crc(covered, sizeof covered);
    const uint8_t extra = 50;
    crc = telemetry::mavlink_crc(&extra, 1, crc);
    CHECK(crc == 0x7F1C);
    // The tests' own decoder (bitwise, reflected polynomial) agrees.
    CHECK(mavtest::crc_bitwise(&extra, 1, mavtest::crc_bitwise(covered, sizeof covered)) == 0x7F1C);
}

TEST_CASE("Telemetry: the first sample sends a heartbeat and a battery status, byte for byte", "[telemetry]") {
    telemetry::MavlinkTelemetry t;
    t.configure(telemetry::TelemetryConfig{}, rated_4s());
    core::Sample s;
    s.voltage_v = 16.0f;
    core::MonitorStatus st;  // not initialised yet: everything unknown but the readings
    const std::string bytes = run(t, s, st);
    // HEARTBEAT from system 1, component 180 (MAV_COMP_ID_BATTERY), sequence 0: custom_mode 0,
    // MAV_TYPE_BATTERY (36), MAV_AUTOPILOT_INVALID (8), base_mode 0, MAV_STATE_STANDBY (3),
    // MAVLink version 3; checksum worked out by hand from the spec's accumulate.
    const uint8_t heartbeat[] = {0xFD, 0x09, 0x00, 0x00, 0x00, 0x01, 0xB4, 0x00, 0x00, 0x00, 0x00,
                                 0x00, 0x00, 0x00, 0x24, 0x08, 0x00, 0x03, 0x03, 0xDC, 0xF9};
    REQUIRE(bytes.size() > sizeof heartbeat);
    CHECK(bytes.substr(0, sizeof heartbeat) == std::string(reinterpret_cast<const char*>(heartbeat), sizeof heartbeat));

    const mavtest::Stream m = mavtest::decode(bytes, false);
    REQUIRE(m.error.empty());
    REQUIRE(m.frames.size() == 2);
    CHECK(m.frames[1].msgid == 147);
    CHECK(m.frames[1].seq == 1);
    const mavtest::Battery b = mavtest::battery(m.frames[1]);
    CHECK(b.voltages_mv[0] == 16000);  // no cells: the pack in cell 0, the others "none"
    CHECK(b.voltages_mv[1] == 0xFFFF);
    CHECK(b.current_consumed_mah == -1);
    CHECK(b.energy_consumed_hj == -1);
    CHECK(b.remaining_pct == -1);
    CHECK(b.time_remaining_s == 0);
    CHECK(b.temperature_cdegc == 0x7FFF);
    CHECK(b.charge_state == telemetry::kChargeUndefined);
    CHECK(b.function == 1);
    CHECK(b.type == 1);
    // Trailing zero bytes are not sent: charge_state (offset 40) is the last non-zero
    // field that could be, and here it is 0 too, so the payload ends at remaining_pct.
    CHECK(m.frames[1].wire_length == 36);
}

TEST_CASE("Telemetry: BATTERY_STATUS fields from a monitor status", "[telemetry]") {
    telemetry::TelemetryConfig cfg;
    cfg.battery_id = 2;
    core::Sample s;
    s.voltage_v = 15.2f;
    s.current_a = 23.456f;
    s.cell_count = 4;
    const float cells[] = {3.8004f, 3.7996f, 3.8f, 3.8012f};
    for (int c = 0; c < 4; ++c) s.cell_voltage_v[c] = cells[c];
    s.has_temperature = true;
    s.temperature_c = 21.5f;
    core::MonitorStatus st;
    st.initialised = true;
    st.cells_valid = true;
    st.flying = true;
    st.consumed_mah = 812.4f;
    st.consumed_mwh = 12000.0f;  // 12 Wh = 43.2 kJ = 432 hJ
    st.soc = 0.4761f;
    st.time_valid = true;
    st.remaining_time_s = 143.4f;

    telemetry::BatteryStatusFields f = telemetry::battery_status_fields(cfg, s, st);
    CHECK(f.id == 2);
    CHECK(f.voltages_mv[0] == 3800);
    CHECK(f.voltages_mv[1] == 3800);  // to the nearest millivolt
    CHECK(f.voltages_mv[2] == 3800);
    CHECK(f.voltages_mv[3] == 3801);
    CHECK(f.voltages_mv[4] == 0xFFFF);
    CHECK(f.current_ca == 2346);
    CHECK(f.temperature_cdegc == 2150);
    CHECK(f.current_consumed_mah == 812);
    CHECK(f.energy_consumed_hj == 432);
    CHECK(f.remaining_pct == 48);
    CHECK(f.time_remaining_s == 143);
    CHECK(f.charge_state == telemetry::kChargeOk);
    CHECK(f.fault_bitmask == 0);

    SECTION("charge state from the remaining flight time") {
        st.remaining_time_s = 59.0f;
        CHECK(telemetry::battery_status_fields(cfg, s, st).charge_state == telemetry::kChargeLow);
        st.remaining_time_s = 19.0f;
        CHECK(telemetry::battery_status_fields(cfg, s, st).charge_state == telemetry::kChargeCritical);
        st.remaining_time_s = 0.2f;  // an estimate of "none left" is not MAVLink's 0 = "no estimate"
        CHECK(telemetry::battery_status_fields(cfg, s, st).time_remaining_s == 1);
    }
    SECTION("a health verdict is UNHEALTHY on the ground only; a weak cell is CELL_FAIL") {
        st.warnings = 1u << core::kWarnShortFlight;
        CHECK(telemetry::battery_status_fields(cfg, s, st).charge_state == telemetry::kChargeOk);
        st.flying = false;
        CHECK(telemetry::battery_status_fields(cfg, s, st).charge_state == telemetry::kChargeUnhealthy);
        st.warnings = 1u << core::kWarnSensorFault;  // not the pack's health
        CHECK(telemetry::battery_status_fields(cfg, s, st).charge_state == telemetry::kChargeOk);
        st.warnings = 1u << core::kWarnCellOutlier;
        CHECK(telemetry::battery_status_fields(cfg, s, st).fault_bitmask == telemetry::kFaultCellFail);
    }
    SECTION("cells kept out, a pack above 65.534 V, and cells 11 and 12") {
        st.cells_valid = false;
        CHECK(telemetry::battery_status_fields(cfg, s, st).voltages_mv[0] == 15200);
        CHECK(telemetry::battery_status_fields(cfg, s, st).voltages_mv[1] == 0xFFFF);
        s.voltage_v = 70.0f;
        f = telemetry::battery_status_fields(cfg, s, st);
        CHECK(f.voltages_mv[0] == 65534);
        CHECK(f.voltages_mv[1] == 70000 - 65534);
        st.cells_valid = true;
        s.cell_count = 12;
        for (int c = 0; c < 12; ++c) s.cell_voltage_v[c] = 3.5f + 0.01f * static_cast<float>(c);
        f = telemetry::battery_status_fields(cfg, s, st);
        CHECK(f.voltages_mv[9] == 3590);
        CHECK(f.voltages_ext_mv[0] == 3600);
        CHECK(f.voltages_ext_mv[1] == 3610);
        CHECK(f.voltages_ext_mv[2] == 0);
    }
    SECTION("the wire layout, read back by the separate decoder") {
        uint8_t payload[telemetry::kBatteryStatusLength];
        f.fault_bitmask = 0x01020304u;
        f.voltages_ext_mv[3] = 4321;
        telemetry::pack_battery_status(f, payload);
        telemetry::MavlinkFramer framer;
        framer.configure(9, 181);
        uint8_t frame[telemetry::kMaxFrameBytes];
        const size_t n = framer.frame(telemetry::kBatteryStatusId, telemetry::kBatteryStatusCrcExtra, payload,
                                      telemetry::kBatteryStatusLength, frame);
        CHECK(n == telemetry::kMaxFrameBytes);  // nothing trailing to drop
        const mavtest::Stream m = mavtest::decode(std::string(reinterpret_cast<const char*>(frame), n), false);
        REQUIRE(m.error.empty());
        REQUIRE(m.frames.size() == 1);
        CHECK(m.frames[0].sysid == 9);
        CHECK(m.frames[0].compid == 181);
        const mavtest::Battery b = mavtest::battery(m.frames[0]);
        CHECK(b.current_consumed_mah == 812);
        CHECK(b.energy_consumed_hj == 432);
        CHECK(b.temperature_cdegc == 2150);
        CHECK(b.voltages_mv[3] == 3801);
        CHECK(b.current_ca == 2346);
        CHECK(b.id == 2);
        CHECK(b.remaining_pct == 48);
        CHECK(b.time_remaining_s == 143);
        CHECK(b.charge_state == telemetry::kChargeOk);
        CHECK(b.voltages_ext_mv[3] == 4321);
        CHECK(b.fault_bitmask == 0x01020304u);
    }
}

TEST_CASE("Telemetry: one heartbeat and battery status per interval of the samples' time", "[telemetry]") {
    telemetry::MavlinkTelemetry t;
    t.configure(telemetry::TelemetryConfig{}, rated_4s());
    core::Sample s;
    s.voltage_v = 16.0f;
    core::MonitorStatus st;
    std::string all;
    // 10 Hz for 3.05 s: sends at 0, 1, 2 and 3 s.
    for (int k = 0; k <= 30; ++k) {
        st.time_us = 5000000u + 100000u * static_cast<uint64_t>(k) + 500u;
        all += run(t, s, st);
    }
    // A 10 s gap: one pair, not ten.
    st.time_us += 10000000u;
    all += run(t, s, st);
    st.time_us += 100000u;
    all += run(t, s, st);
    const mavtest::Stream m = mavtest::decode(all, false);
    REQUIRE(m.error.empty());
    REQUIRE(m.frames.size() == 10);
    for (size_t i = 0; i < m.frames.size(); ++i) {
        CHECK(m.frames[i].seq == i);
        CHECK(m.frames[i].msgid == (i % 2 == 0 ? 0u : 147u));
    }
}

TEST_CASE("Telemetry: a warning is texted when raised and again while active, the short flight with its cause", "[telemetry]") {
    telemetry::MavlinkTelemetry t;
    telemetry::TelemetryConfig cfg;
    cfg.interval_s = 1000.0f;  // no battery status in the way after the first
    t.configure(cfg, rated_4s());
    core::Sample s;
    core::MonitorStatus st;
    st.time_us = 1;
    run(t, s, st);  // the first pair
    st.time_us = 2;
    CHECK(run(t, s, st).empty());

    // The joint estimator raises short flight and its cause in the same update.
    st.warnings_raised = st.warnings = (1u << core::kWarnShortFlight) | (1u << core::kWarnLowCapacity);
    st.short_flight_cause = core::JointEstimator::kCauseCapacity;
    st.expected_time_s = 300.0f;
    st.total_time_s = 222.0f;  // 26 % short
    st.capacity_ah = 1.05f;    // 67.7 % of 1.55 Ah
    st.resistance_ohm = 0.041f;
    mavtest::Stream m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.error.empty());
    REQUIRE(m.frames.size() == 1);
    uint8_t severity = 0;
    CHECK(mavtest::text(m.frames[0], &severity) == "battsim: flight 26% short, capacity 68%");
    CHECK(severity == telemetry::kMavSeverityWarning);
    CHECK(run(t, s, st).empty());  // not again at once

    // Later the resistance joins the cause, and a cell is named: their own texts.
    st.warnings_raised |= (1u << core::kWarnHighResistance) | (1u << core::kWarnCellOutlier);
    st.outlier_cell = 2;
    st.cell_finding = core::CellAnalyzer::kHighResistance;
    st.time_us = 3;
    m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.frames.size() == 2);
    CHECK(mavtest::text(m.frames[0]) == "battsim: high resistance 41 mOhm (205%)");
    CHECK(mavtest::text(m.frames[1]) == "battsim: cell 3 weak: high resistance");

    // 30 s after its first text the short flight is said again, now with both causes,
    // which have no repeat of their own; the cell 30 s after its own first text.
    st.warnings = st.warnings_raised;
    st.flying = true;
    st.short_flight_cause = core::JointEstimator::kCauseCapacity | core::JointEstimator::kCauseResistance;
    st.time_us = 2 + 30000000u - 1;
    CHECK(run(t, s, st).empty());
    st.time_us = 2 + 30000000u;
    m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.frames.size() == 1);
    CHECK(mavtest::text(m.frames[0]) == "battsim: flight 26% short, capacity 68%, R 205%");
    st.time_us = 3 + 30000000u;
    m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.frames.size() == 1);
    CHECK(mavtest::text(m.frames[0]) == "battsim: cell 3 weak: high resistance");
    // A warning no longer active is not repeated.
    st.warnings = 1u << core::kWarnCellOutlier;
    st.time_us = 3 + 60000000u;
    m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.frames.size() == 1);
    CHECK(mavtest::text(m.frames[0]) == "battsim: cell 3 weak: high resistance");
    // Landed: the charge state says it from now on, the text is not repeated.
    st.flying = false;
    st.time_us = 3 + 90000000u;
    CHECK(run(t, s, st).empty());
}

TEST_CASE("Telemetry: text_repeat_s 0 texts each warning once", "[telemetry]") {
    telemetry::MavlinkTelemetry t;
    telemetry::TelemetryConfig cfg;
    cfg.interval_s = 1000.0f;
    cfg.text_repeat_s = 0.0f;
    t.configure(cfg, rated_4s());
    core::Sample s;
    core::MonitorStatus st;
    run(t, s, st);
    st.warnings_raised = st.warnings = 1u << core::kWarnSensorFault;
    st.flying = true;
    int texts = 0;
    for (int k = 1; k <= 400; ++k) {
        st.time_us = 1000000u * static_cast<uint64_t>(k);
        texts += static_cast<int>(mavtest::decode(run(t, s, st), false).frames.size());
    }
    CHECK(texts == 1);
}

TEST_CASE("Telemetry: the warnings' sentences, by hand", "[telemetry]") {
    char text[telemetry::kStatusTextChars + 1];
    core::MonitorStatus st;
    st.capacity_ah = 1.05f;
    st.resistance_ohm = 0.0336f;
    CHECK(std::string(text, telemetry::warning_text(core::kWarnLowCapacity, 1.55f, 0.02f, st, text)) ==
          "battsim: low capacity 1.05 Ah (68% of rated)");
    CHECK(std::string(text) == "battsim: low capacity 1.05 Ah (68% of rated)");
    st.capacity_ah = 0.999f;  // 1.00 Ah: the hundredths carried
    telemetry::warning_text(core::kWarnLowCapacity, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: low capacity 1.00 Ah (64% of rated)");
    telemetry::warning_text(core::kWarnHighResistance, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: high resistance 34 mOhm (168%)");
    // A sensor fault says its first cause: the pack reading, a cell reading, the current
    // sensor's offset (with its sign), or a gap in the samples (its length).
    st.sensor_fault_cause = core::kFaultReading | core::kFaultSampleGap;
    telemetry::warning_text(core::kWarnSensorFault, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: sensor fault: reading out of range");
    st.sensor_fault_cause = core::kFaultCells;
    telemetry::warning_text(core::kWarnSensorFault, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: sensor fault: cell reading out of range");
    st.sensor_fault_cause = core::kFaultCurrentOffset | core::kFaultSampleGap;
    st.current_offset_a = -0.826f;
    telemetry::warning_text(core::kWarnSensorFault, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: sensor fault: current offset -0.83 A");
    st.sensor_fault_cause = core::kFaultSampleGap;
    st.dt_s = 2.101f;
    telemetry::warning_text(core::kWarnSensorFault, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: sensor fault: no reading for 2.1 s");
    st.sensor_fault_cause = 0;  // not raised by a known cause: the bare warning
    telemetry::warning_text(core::kWarnSensorFault, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: sensor fault");
    st.outlier_cell = 0;
    st.cell_finding = core::CellAnalyzer::kNone;  // the reference estimator's Piao score
    telemetry::warning_text(core::kWarnCellOutlier, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: cell 1 differs from the others");
    st.short_flight_cause = core::JointEstimator::kCauseCapacity | core::JointEstimator::kCauseResistance;
    st.expected_time_s = 300.0f;
    st.total_time_s = 100.0f;
    st.capacity_ah = 100.0f;  // absurd on purpose: the sentence stays within 50 characters
    st.resistance_ohm = 10.0f;
    const size_t n = telemetry::warning_text(core::kWarnShortFlight, 1.55f, 0.02f, st, text);
    CHECK(n == telemetry::kStatusTextChars);
    CHECK(std::string(text) == std::string("battsim: flight 67% short, capacity 6452%, R 50000").substr(0, 50));
}

TEST_CASE("Telemetry: a short flight that clears in flight is withdrawn after clear_hold_s, and told afresh if it returns", "[telemetry]") {
    telemetry::MavlinkTelemetry t;
    telemetry::TelemetryConfig cfg;
    cfg.interval_s = 1000.0f;  // no battery status in the way after the first
    cfg.clear_hold_s = 5.0f;
    core::MonitorConfig joint = rated_4s();
    joint.estimator = core::EstimatorKind::Joint;
    t.configure(cfg, joint);
    core::Sample s;
    core::MonitorStatus st;
    st.time_us = 1;
    st.flying = true;
    run(t, s, st);  // the first pair
    const uint64_t t0 = 10000000u;
    const auto at = [&](double after_s) { st.time_us = t0 + static_cast<uint64_t>(after_s * 1e6); };

    const uint8_t verdict = (1u << core::kWarnShortFlight) | (1u << core::kWarnHighResistance);
    st.warnings_raised = st.warnings = verdict;
    st.short_flight_cause = core::JointEstimator::kCauseResistance;
    st.expected_time_s = 300.0f;
    st.total_time_s = 222.0f;
    st.resistance_ohm = 0.031f;
    at(0);
    mavtest::Stream m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.frames.size() == 1);
    CHECK(mavtest::text(m.frames[0]) == "battsim: flight 26% short, R 155%");

    // Off for less than the hold, then on again: a flicker, nothing said either way.
    st.warnings = 0;
    st.total_time_s = 250.0f;
    at(1);
    CHECK(run(t, s, st).empty());
    at(5.9);
    CHECK(run(t, s, st).empty());
    st.warnings = verdict;
    at(6);
    CHECK(run(t, s, st).empty());

    // Off while its reading is within 5 points of the bar (250 s of 300 s: 17 % short; a
    // verdict hovering at the bar would be withdrawn and warned in turn): not withdrawn
    // however long.
    st.warnings = 0;
    st.total_time_s = 250.0f;
    for (double k = 6.5; k < 20; k += 0.1) {
        at(k);
        CHECK(run(t, s, st).empty());
    }
    // Not short from 20 s: withdrawn at 25 s, once, at NOTICE, with the verdict's reading
    // now (264 s of a healthy 300 s: 12 % short), and its cause with it.
    st.total_time_s = 264.0f;
    at(20);
    CHECK(run(t, s, st).empty());
    at(24.999);
    CHECK(run(t, s, st).empty());
    at(25);
    m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.error.empty());
    REQUIRE(m.frames.size() == 1);
    uint8_t severity = 0;
    CHECK(mavtest::text(m.frames[0], &severity) == "battsim: short flight cleared, 12% short now");
    CHECK(severity == telemetry::kMavSeverityNotice);
    for (int k = 26; k < 100; ++k) {
        at(k);
        CHECK(run(t, s, st).empty());
    }

    // Back after its withdrawal: news again at once, not at the next 30 s repeat.
    st.warnings = verdict;
    st.total_time_s = 222.0f;
    at(100);
    m = mavtest::decode(run(t, s, st), false);
    REQUIRE(m.frames.size() == 1);
    CHECK(mavtest::text(m.frames[0], &severity) == "battsim: flight 26% short, R 155%");
    CHECK(severity == telemetry::kMavSeverityWarning);

    // Cleared after the landing: the charge state says it on the ground, no text.
    st.warnings = 0;
    st.flying = false;
    for (int k = 101; k < 200; ++k) {
        at(k);
        CHECK(run(t, s, st).empty());
    }
}

TEST_CASE("Telemetry: the joint estimator's cause giving way to another is no withdrawal; the reference's low capacity is withdrawn", "[telemetry]") {
    telemetry::TelemetryConfig cfg;
    cfg.interval_s = 1000.0f;
    core::Sample s;
    constexpr uint8_t kShort = 1u << core::kWarnShortFlight, kCap = 1u << core::kWarnLowCapacity,
                      kRes = 1u << core::kWarnHighResistance;
    // Joint: short for resistance, then capacity joins (told on its own), then resistance
    // leaves while the flight stays short: nothing is withdrawn.
    core::MonitorConfig joint = rated_4s();
    joint.estimator = core::EstimatorKind::Joint;
    telemetry::MavlinkTelemetry t;
    t.configure(cfg, joint);
    core::MonitorStatus st;
    st.flying = true;
    st.expected_time_s = 300.0f;
    st.total_time_s = 200.0f;
    st.time_us = 1;
    run(t, s, st);
    st.warnings_raised = st.warnings = kShort | kRes;
    st.time_us = 1000000u;
    CHECK(mavtest::decode(run(t, s, st), false).frames.size() == 1);
    st.warnings_raised = st.warnings = kShort | kRes | kCap;
    st.time_us = 2000000u;
    CHECK(mavtest::decode(run(t, s, st), false).frames.size() == 1);  // the capacity, on its own
    st.warnings = kShort | kCap;
    for (int k = 3; k < 29; ++k) {
        st.time_us = 1000000u * static_cast<uint64_t>(k);
        CHECK(run(t, s, st).empty());
    }
    // Reference: low capacity told, then off for the hold: withdrawn.
    telemetry::MavlinkTelemetry r;
    r.configure(cfg, rated_4s());
    core::MonitorStatus rs;
    rs.flying = true;
    rs.capacity_ah = 1.4f;
    rs.time_us = 1;
    run(r, s, rs);
    rs.warnings_raised = rs.warnings = kCap;
    rs.time_us = 1000000u;
    CHECK(mavtest::decode(run(r, s, rs), false).frames.size() == 1);
    rs.warnings = 0;
    rs.time_us = 2000000u;
    CHECK(run(r, s, rs).empty());
    rs.time_us = 7000000u;
    const mavtest::Stream m = mavtest::decode(run(r, s, rs), false);
    REQUIRE(m.frames.size() == 1);
    CHECK(mavtest::text(m.frames[0]) == "battsim: low capacity cleared, 1.40 Ah (90%)");
}

TEST_CASE("Telemetry: clear_hold_s 0 never withdraws; a cell or sensor warning is never withdrawn", "[telemetry]") {
    for (const float hold_s : {0.0f, 5.0f}) {
        telemetry::MavlinkTelemetry t;
        telemetry::TelemetryConfig cfg;
        cfg.interval_s = 1000.0f;
        cfg.clear_hold_s = hold_s;
        core::MonitorConfig joint = rated_4s();
        joint.estimator = core::EstimatorKind::Joint;
        t.configure(cfg, joint);
        core::Sample s;
        core::MonitorStatus st;
        st.flying = true;
        st.time_us = 1;
        run(t, s, st);
        st.warnings_raised = st.warnings = hold_s > 0.0f
                                               ? (1u << core::kWarnCellOutlier) | (1u << core::kWarnSensorFault)
                                               : (1u << core::kWarnShortFlight);
        st.time_us = 1000000u;
        CHECK(!run(t, s, st).empty());
        st.warnings = 0;
        for (int k = 2; k < 60; ++k) {
            st.time_us = 1000000u * static_cast<uint64_t>(k);
            CHECK(run(t, s, st).empty());
        }
    }
}

TEST_CASE("Telemetry: the withdrawals' sentences, by hand", "[telemetry]") {
    char text[telemetry::kStatusTextChars + 1];
    core::MonitorStatus st;
    st.expected_time_s = 300.0f;
    st.total_time_s = 300.0f;  // not short at all now
    CHECK(std::string(text, telemetry::withdrawal_text(core::kWarnShortFlight, 1.55f, 0.02f, st, text)) ==
          "battsim: short flight cleared, not short now");
    st.total_time_s = 255.0f;  // 15 % short: under the bar
    telemetry::withdrawal_text(core::kWarnShortFlight, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: short flight cleared, 15% short now");
    st.total_time_s = 299.0f;  // 0.3 % short: no "0% short now"
    telemetry::withdrawal_text(core::kWarnShortFlight, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: short flight cleared, not short now");
    // The worst a verdict reads, no flight left from the take-off charge: 100 %, not no number.
    st.total_time_s = 0.0f;
    st.short_flight_cause = core::JointEstimator::kCauseResistance;
    st.resistance_ohm = 0.0328f;
    telemetry::warning_text(core::kWarnShortFlight, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: flight 100% short, R 164%");
    // The reference estimator's own verdicts (it has no short flight).
    st.capacity_ah = 1.4f;
    st.resistance_ohm = 0.0226f;
    telemetry::withdrawal_text(core::kWarnLowCapacity, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: low capacity cleared, 1.40 Ah (90%)");
    telemetry::withdrawal_text(core::kWarnHighResistance, 1.55f, 0.02f, st, text);
    CHECK(std::string(text) == "battsim: high resistance cleared, 23 mOhm (113%)");
    st.resistance_ohm = 99.0f;  // absurd on purpose: within 50 characters
    CHECK(telemetry::withdrawal_text(core::kWarnHighResistance, 1.55f, 0.02f, st, text) <= telemetry::kStatusTextChars);
}

TEST_CASE("Telemetry: a current held reversed for 2 s is texted once, as swapped shunt sense wires", "[telemetry]") {
    // Swapped sense wires: the monitor sees no flight and would never warn; the text is the
    // pilot's only word of it. The firmware's OLED `SIGN` reads the same check.
    const auto texts_over = [](const std::vector<float>& currents_a) {
        telemetry::MavlinkTelemetry t;
        telemetry::TelemetryConfig cfg;
        cfg.interval_s = 1000.0f;  // the heartbeats out of the way
        core::MonitorConfig m = rated_4s();
        m.flying.min_flying_current_a = 1.0f;
        t.configure(cfg, m);
        std::vector<std::pair<double, std::string>> said;
        core::Sample s;
        core::MonitorStatus st;
        for (size_t k = 0; k < currents_a.size(); ++k) {
            s.time_us = st.time_us = 100000u * static_cast<uint64_t>(k);  // every 0.1 s
            s.current_a = currents_a[k];
            for (const mavtest::Frame& f : mavtest::decode(run(t, s, st), false).frames) {
                if (f.msgid != telemetry::kStatusTextId) continue;
                uint8_t severity = 0;
                said.emplace_back(s.time_us * 1e-6, mavtest::text(f, &severity));
                CHECK(severity == telemetry::kMavSeverityWarning);
            }
        }
        return said;
    };
    std::vector<float> currents(100, 0.5f);  // 10 s on the ground
    CHECK(texts_over(currents).empty());
    for (size_t k = 10; k < 100; ++k) currents[k] = -12.0f;  // reversed from 1.0 s on
    const auto reversed = texts_over(currents);
    REQUIRE(reversed.size() == 1);
    CHECK(reversed[0].first == Approx(3.0));  // held 2 s
    CHECK(reversed[0].second == "battsim: current reversed, swap shunt sense wires");
    CHECK(reversed[0].second.size() <= telemetry::kStatusTextChars);
    // A 1.8 s reversal (an ESC braking) and a 2 s one broken by one sample above minus the
    // take-off current do not count; exactly at minus the take-off current for 2 s does.
    std::vector<float> brief(100, 5.0f);
    for (size_t k = 10; k < 29; ++k) brief[k] = -8.0f;                    // 1.0 … 2.8 s
    for (size_t k = 40; k < 61; ++k) brief[k] = k == 50 ? -0.9f : -8.0f;  // 4.0 … 6.0 s
    CHECK(texts_over(brief).empty());
    for (size_t k = 65; k < 90; ++k) brief[k] = -1.0f;  // from 6.5 s
    const auto at_bar = texts_over(brief);
    REQUIRE(at_bar.size() == 1);
    CHECK(at_bar[0].first == Approx(8.5));
}
