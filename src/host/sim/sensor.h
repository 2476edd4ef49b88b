// The sensor layer of the reference hardware (ESP8266 + INA226 + INA3221 + SD card):
// what the logger would have written given the plant's true values.
//
// Timing: the INA226 converts continuously (nominally 2.116 ms × 2 channels × 16 averages
// = 67.7 ms; the reference logs show 66.87 ms, its oscillator runs fast) and each value is
// the average over its conversion window. The loop reads each new conversion about a
// millisecond after it is ready and stamps it with millis(). Now and then a read is late
// (tens of ms), and SD-card writes stall the loop for 0.1–0.35 s, sometimes for several
// reads in a row, so conversions are missed. The INA3221 (balance-lead taps) converts on
// its own cycle; the logger takes its latest value.
//
// Quantisation: INA226 bus 1.25 mV, shunt 2.5 µV; INA3221 8 mV. Cells are computed as the
// real logger does: cell1 = ch1, cellk = chk − ch(k−1), last cell = INA226 bus − last tap,
// so the last cell absorbs any mismatch between the two chips.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/sensor.h"
#include "host/sim/plant.h"
#include "host/sim/rng.h"

namespace battsim {
namespace host {
namespace sim {

// The hardware unit's own small errors (datasheet-sized), drawn from the seed unless given.
struct SensorUnit {
    double bus_gain_error = 0.0;                // INA226 bus voltage, fraction
    double tap_gain_error[kMaxCells] = {};      // INA3221 tap k (cells 1..k+1), fraction
    double tap_offset_v[kMaxCells] = {};
};

struct SensorFaults {
    double current_offset_a = 0.0;     // the current reads this much high
    double current_gain_error = 0.0;   // ... and this fraction high
    int loose_tap = 0;                 // 1..cells−1: that balance-lead tap loses contact
    double loose_contact_mean_s = 6.0; // mean time in contact while flying (vibration)
    double loose_ground_factor = 6.0;  // contact lasts this many times longer on the ground
    double loose_open_mean_s = 0.3;    // mean time open; an open tap floats near 0 V
    double missed_probability = 0.0;   // each row lost independently
    double missed_burst_rate_per_min = 0.0;  // longer dropouts (I2C lock-ups)
    double missed_burst_min_s = 0.5;
    double missed_burst_max_s = 3.0;
    bool any() const {
        return current_offset_a != 0.0 || current_gain_error != 0.0 || loose_tap != 0 || missed_probability > 0.0 ||
               missed_burst_rate_per_min > 0.0;
    }
};

// The core::SensorFaultCause bits a monitor should name for these faults: an offset, a
// loose balance tap (its cell readings), dropouts of a second or more (gaps). A gain error
// is none of them: no flight shows it (a charger's count does), and single missed rows
// are no gap.
uint8_t nameable_fault_causes(const SensorFaults& faults);

struct SensorParams {
    double period_ms = 66.87;
    // The INA3221's cycle: 3 channels × shunt and bus × 1.1 ms × 16 averages. The
    // dissertation's logger reads its last cell at 2.32 × the others' short-lag resistance,
    // which this gives and a bus-only 52.8 ms (the default until the fifty-second session) does not.
    double tap_period_ms = 105.6;
    double first_read_ms = 600.0;     // boot time before the first read (plus up to a period)
    double latency_max_ms = 1.2;
    double late_read_rate_per_s = 1.0 / 120.0;
    double late_read_min_ms = 30.0;
    double late_read_max_ms = 45.0;
    double stall_rate_per_s = 1.0 / 90.0;
    double stall_first_min_s = 0.10;
    double stall_first_max_s = 0.35;
    int stall_more_max = 4;           // further slow reads after the first, 0..this many
    double stall_more_min_s = 0.215;
    double stall_more_max_s = 0.235;
    double bus_noise_v = 0.0012;
    double shunt_noise_mv = 0.0015;
    double tap_noise_v = 0.004;
    double temperature_noise_c = 0.1;
    double bus_gain_sd = 0.0005;
    double tap_gain_sd = 0.001;
    double tap_offset_sd_v = 0.004;
    // Wiring, not a fault: resistance of the main current's return path between the pack's
    // negative (balance pin 0) and the monitor's ground, as when the monitor is also
    // grounded through the drone (a BEC). Every reading against that ground (the bus and
    // each tap) is low by I·R, so cell 1 and the pack read that much more resistance.
    double ground_lead_ohm = 0.0;
    // ... and of the positive main lead between the pack's positive (the last balance pin)
    // and where the bus voltage is taken: the bus reads I·R low and no tap does, so the last
    // cell (bus − last tap) carries it. The reference logger's flights show about as much
    // again as a cell's own resistance there (cell-resistance-fifths.py).
    double bus_lead_ohm = 0.0;
    bool unit_given = false;  // true: use `unit` as is; false: draw it from the seed
    SensorUnit unit;
    core::ShuntCalibration shunt;
    SensorFaults faults;
};

// One logged row in ADC counts, so formatting is exact integer arithmetic.
struct LogRecord {
    int64_t time_ms = 0;
    int32_t bus_count = 0;                 // × 1.25 mV
    int32_t shunt_count = 0;               // × 2.5 µV
    int32_t tap_count[kMaxCells] = {};     // × 8 mV, taps 1..cells−1
    int32_t temperature_dc = 0;            // × 0.1 °C
    double read_time_s = 0.0;
};

// What the pack really did during one plant step, as the sensors see it.
struct TrueValues {
    double voltage_v = 0.0;
    double current_a = 0.0;
    double cell_v[kMaxCells] = {};
    double temperature_c = 0.0;
};

struct SensorStats {
    long reads = 0;
    long dropped = 0;         // rows lost to the missed-samples fault
    long stalls = 0;          // SD-card stall episodes
    long late_reads = 0;
    double loose_open_s = 0;  // time the loose tap spent open
    long loose_episodes = 0;
    long current_clipped = 0;  // reads with the shunt register at its end (about ±215 A): the log is wrong there
};

class SensorChain {
public:
    void configure(const SensorParams& params, int cells, uint64_t seed);
    // The true values held over [t_s, t_s + dt_s); appends the rows read in that interval.
    void feed(double t_s, double dt_s, const TrueValues& v, bool airborne, std::vector<LogRecord>& out);
    const SensorUnit& unit() const { return unit_; }
    const SensorStats& stats() const { return stats_; }
    int cells() const { return cells_; }

private:
    // Readings integrated over a conversion (V·s, mV·s) and the time they cover, so a
    // conversion reads the mean of what it saw.
    struct Accumulator {
        double bus_v_s = 0, shunt_mv_s = 0, taps_v_s[kMaxCells] = {}, span_s = 0;
    };
    void finish_ina226();
    void finish_ina3221();
    void emit(double read_time_s, std::vector<LogRecord>& out);
    void schedule_after(double read_time_s);

    SensorParams p_;
    int cells_ = 4;
    SensorUnit unit_;
    // The taps' noise has a stream of its own: how often the INA3221 converts must not
    // change the noise on the bus and shunt readings (a comparison of tap periods was
    // confounded by it).
    Rng timing_rng_, noise_rng_, tap_noise_rng_, fault_rng_;
    Accumulator acc226_, acc3221_;
    double next_ready226_s_ = 0, next_ready3221_s_ = 0;
    double next_read_s_ = 0;
    int stall_left_ = 0;
    double next_stall_s_ = 0;
    // Latest completed conversions (counts).
    int32_t bus_count_ = 0, shunt_count_ = 0, tap_count_[kMaxCells] = {};
    bool have226_ = false, have3221_ = false;
    double temperature_c_ = 0;
    // Loose lead: open/closed with random durations.
    bool loose_open_ = false;
    double loose_switch_s_ = 0;
    // Missed-sample bursts.
    double burst_start_s_ = 0, burst_end_s_ = -1;
    SensorStats stats_;
};

// Text of the log. Raw: the dissertation logger's header-less 4-cell format
// `time_ms,bus_voltage_v,cell1_v..cell4_v,current_ma,shunt_mv,`. Csv: the headered format
// `time_s,voltage_v,current_a,cell1_v..cellN_v,temperature_c`.
// Raw: the reference logger's rows; Csv: battsim's CSV with cells and temperature;
// Radio: an EdgeTX radio's telemetry log (Date, Time, RxBt(V), Curr(A)): the pack voltage
// and current in the 0.1 V and 0.1 A steps of the Crossfire battery sensor, one row per
// log interval (the rows are thinned by the caller), no cells.
// DataFlash and ULog: an autopilot's binary log (autopilot_log.h), written by the caller.
enum class SimLogFormat { Raw, Csv, Radio, DataFlash, ULog };
// A format's name (as scenarios and `simulate --format` / `score --log-format` give it), its
// file extension and a few words for help texts.
struct SimLogFormatEntry {
    SimLogFormat format;
    const char* name;
    const char* extension;
    const char* description;  // empty: the name says enough
};
// Every SimLogFormat, in the order help texts and messages list them: the one list a new
// simulated format is added to. The names, the extension, the scenario reader's message and
// both commands' option checks and help read it.
const std::vector<SimLogFormatEntry>& sim_log_formats();
const char* sim_log_format_name(SimLogFormat f);
const char* sim_log_extension(SimLogFormat f);
// The format named `name`; false when no entry has that name.
bool parse_sim_log_format(const std::string& name, SimLogFormat& out);
// The names for an option's check, and "raw (…), csv, … or ulog (…)" for its help.
std::vector<std::string> sim_log_format_names();
std::string sim_log_format_help();
std::string format_header(SimLogFormat f, int cells);
void format_record(SimLogFormat f, int cells, const core::ShuntCalibration& shunt, const LogRecord& r,
                   std::string& out);

// A row's readings in volts, amperes and °C, as the CSV log gives them (the current in whole
// mA): what the binary autopilot logs carry.
struct RecordValues {
    double voltage_v = 0;
    double current_a = 0;
    double cell_v[kMaxCells] = {};
    double temperature_c = 0;
};
RecordValues record_values(int cells, const core::ShuntCalibration& shunt, const LogRecord& r);

// The current the firmware computes from a shunt count, in mA, in float exactly as the
// ESP8266 does.
float firmware_current_ma(int32_t shunt_count, const core::ShuntCalibration& shunt);

}  // namespace sim
}  // namespace host
}  // namespace battsim
