#include "app/display_pages.h"

#include "telemetry/text_buffer.h"

namespace battsim {
namespace fw {

namespace {

using Row = telemetry::FixedText<kDisplayColumns + 1>;

// "m:ss", or "--:--" when unknown.
void append_minutes(Row& r, bool valid, float seconds) {
    if (!valid || !(seconds >= 0.0f) || seconds > 359999.0f) {
        r.append("--:--");
        return;
    }
    const uint32_t s = static_cast<uint32_t>(seconds + 0.5f);
    r.appendf("%2u:%02u", static_cast<unsigned>(s / 60u), static_cast<unsigned>(s % 60u));
}

void append_counters_row(Row& r, const ReadingCounters& c) {
    if (c.ready_timeouts > 0) r.appendf(" INA?%u", static_cast<unsigned>(c.ready_timeouts));
    if (c.missed > 0) r.appendf(" miss%u", static_cast<unsigned>(c.missed));
}

}  // namespace

void draw_monitor_page(Display& d, const MonitorPage& page) {
    const core::MonitorStatus& s = *page.status;
    const core::Sample& x = *page.sample;
    d.clear();
    Row r;
    r.appendf("%5.2fV %6.1fA %s", static_cast<double>(x.voltage_v), static_cast<double>(x.current_a),
              s.flying ? "FLY" : "GND");
    d.text(0, 0, r.c_str());

    r.clear();
    if (s.initialised) {
        r.appendf("SoC %3d%% %6.0fmAh", static_cast<int>(s.soc * 100.0f + 0.5f), static_cast<double>(s.consumed_mah));
    } else {
        r.append("SoC  --  resting...");
    }
    d.text(0, 1, r.c_str());

    r.clear();
    r.appendf("Cap %4.2fAh ", static_cast<double>(s.capacity_ah));
    // No estimate yet reads "--": "R  0mOhm" looked measured, and so did the joint
    // estimator's configured prior before the pack's own current steps measured one.
    if (s.resistance_measured) {
        r.appendf("R%3.0fmOhm", static_cast<double>(s.resistance_ohm * 1000.0f));
    } else {
        r.append("R --mOhm");
    }
    d.text(0, 2, r.c_str());

    r.clear();
    r.append("Left ");
    append_minutes(r, s.time_valid, s.remaining_time_s);
    r.append(" of ");
    append_minutes(r, s.time_valid, s.total_time_s);
    d.text(0, 3, r.c_str());

    r.clear();
    for (int c = 0; c < x.cell_count && c < 4; ++c) {
        // Four columns each, so four cells always fit the 21: a reading out of 0-9.99 V (a
        // loose tap) had widened its value and pushed the fourth cell off the row unseen.
        const float v = x.cell_voltage_v[c];
        if (c > 0) r.append(" ");
        if (v >= 0.0f && v <= 9.99f) {
            r.appendf("%.2f", static_cast<double>(v));
        } else {
            r.append("----");
        }
    }
    if (x.cell_count == 0) r.append("no cell taps");
    d.text(0, 4, r.c_str());

    r.clear();
    // Before everything: with the current reversed no estimate means anything.
    if (page.current_reversed) r.append("SIGN ");
    if (s.warnings == 0 && !page.current_reversed) r.append("ok");
    // The verdict first: the row is cut at 21 columns when everything is raised at once.
    if (s.warnings & (1u << core::kWarnShortFlight)) r.append("SHORT ");
    if (s.warnings & (1u << core::kWarnLowCapacity)) r.append("CAP ");
    if (s.warnings & (1u << core::kWarnHighResistance)) r.append("RES ");
    if (s.warnings & (1u << core::kWarnCellOutlier)) r.appendf("CELL%d ", s.outlier_cell + 1);
    // A sensor fault by its cause, in the same width: what to check differs.
    if (s.warnings & (1u << core::kWarnSensorFault)) {
        r.append(s.sensor_fault_cause & core::kFaultReading         ? "SENS "
                 : s.sensor_fault_cause & core::kFaultCells         ? "TAP "
                 : s.sensor_fault_cause & core::kFaultCurrentOffset ? "OFS "
                 : s.sensor_fault_cause & core::kFaultSampleGap     ? "GAP "
                                                                    : "SENS ");
    }
    if (!page.sd_ok) r.append(" SD!");
    append_counters_row(r, page.counters);
    d.text(0, 5, r.c_str());
    d.show();
}

void draw_logger_page(Display& d, const LoggerPage& page) {
    d.clear();
    Row r;
    r.append("discharge logger");
    d.text(0, 0, r.c_str());
    r.clear();
    r.appendf("%6.3f V", static_cast<double>(page.voltage_v));
    d.text(0, 1, r.c_str());
    r.clear();
    r.appendf("%7.2f A", static_cast<double>(page.current_a));
    d.text(0, 2, r.c_str());
    r.clear();
    r.appendf("%8.1f mAh", static_cast<double>(page.consumed_mah));
    d.text(0, 3, r.c_str());
    r.clear();
    if (page.connected) {
        r.appendf("sent %lu", static_cast<unsigned long>(page.lines_sent));
    } else {
        r.append("waiting for host");
    }
    d.text(0, 4, r.c_str());
    r.clear();
    // Why lines are missing from the record: readings without cells are not sent.
    if (page.taps_missing) r.append("no taps");
    if (page.counters.tap_errors > 0) r.appendf("tap%u", static_cast<unsigned>(page.counters.tap_errors));
    append_counters_row(r, page.counters);
    d.text(0, 5, r.c_str());
    d.show();
}

}  // namespace fw
}  // namespace battsim
