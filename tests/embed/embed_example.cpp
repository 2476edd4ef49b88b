// battsim's core in your own firmware, in one file (docs/embedding.md walks through it).
//
// Everything an integration needs is here: the config exported from a JSON, one statically
// allocated monitor, one Sample per sensor reading, and what to read off the status. Only
// read_reading() stands in for your drivers: it takes the readings from a predictive-bms raw
// log (time_ms,bus_v,cell1_v..cell4_v,current_ma,shunt_mv), so that the tests can feed this
// program the same log as `battsim replay` and check that it prints the same numbers
// (tests/cli/test_embed_example_cli.cpp). The C library alone (stdio for the stand-in and
// the printout); no battsim host code.
//
// Built by CMake (tests/embed/CMakeLists.txt) against the core sources with the core's
// rules (-fno-exceptions -fno-rtti) and -Wconversion -Wdouble-promotion -Werror; by hand:
//   build/battsim export-config --firmware configs/sim-4s.json --estimator joint -o battsim_config.h
//   g++ -std=c++17 -O2 -ffp-contract=off -fno-exceptions -fno-rtti -Isrc -I.
//       tests/embed/embed_example.cpp $(find src/core -name '*.cpp') -o embed_example
//   ./embed_example logs/example-4s.csv
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "battsim_config.h"  // battsim export-config --firmware PACK.json --estimator joint
#include "core/monitor.h"

namespace {

using battsim::core::CellAnalyzer;
using battsim::core::Monitor;
using battsim::core::MonitorConfig;
using battsim::core::MonitorStatus;
using battsim::core::Sample;

// The config: a constant expression, so it can live in flash (on the ESP8266, .rodata is in
// RAM). Monitor::configure() copies it into the monitor.
constexpr MonitorConfig kConfig = battsim_generated::monitor_config();

// One monitor per pack, static (about 6.5 KB: too big for most task stacks). No global
// state besides the object itself: two packs are two monitors.
Monitor g_monitor;

// --- stand-in for your sensor drivers ------------------------------------------------------

// One reading into `s`: time in µs from a monotonic clock, pack voltage (V), current (A,
// positive = discharge), each cell's own voltage (V, cell 1 at the pack's negative end).
// Returns false at the end of the input.
bool read_reading(FILE* in, Sample& s) {
    char line[256];
    while (fgets(line, sizeof line, in) != nullptr) {
        double field[8];
        char* p = line;
        int n = 0;
        for (; n < 8; ++n) {
            char* end = nullptr;
            field[n] = strtod(p, &end);
            if (end == p) break;
            p = end;
            if (*p == ',') ++p;
        }
        if (n < 8) continue;  // not a reading (a blank line)
        s = Sample{};
        s.time_us = static_cast<uint64_t>(llround(field[0] * 1000.0));
        s.voltage_v = static_cast<float>(field[1]);
        s.current_a = static_cast<float>(field[6] / 1000.0);  // the log's current is in mA
        s.cell_count = 4;  // 0 when the sample has no cell voltages
        for (int c = 0; c < 4; ++c) s.cell_voltage_v[c] = static_cast<float>(field[2 + c]);
        // s.has_temperature / s.temperature_c (°C): only the model extensions read it.
        return true;
    }
    return false;
}

// --- what your firmware does with the status -------------------------------------------------

// The summary's names for the warning bits (core::Warning); the core carries no strings.
const char* const kWarningNames[battsim::core::kWarnCount] = {"low_capacity", "high_resistance", "cell_outlier",
                                                              "sensor_fault", "short_flight"};
static_assert(battsim::core::kWarnShortFlight == 4 && battsim::core::kWarnCount == 5, "kWarningNames follows core::Warning");
static_assert(battsim::core::JointEstimator::kCauseCapacity == 1 && battsim::core::JointEstimator::kCauseResistance == 2,
              "the short flight's causes below are bits 0 and 1");
static_assert(battsim::core::kFaultReading == 1 && battsim::core::kFaultCells == 2 &&
                  battsim::core::kFaultCurrentOffset == 4 && battsim::core::kFaultSampleGap == 8,
              "the sensor fault's causes below are bits 0 to 3");

double seconds(uint64_t time_us) { return static_cast<double>(time_us) * 1e-6; }

// " (a, b)": the names of the bits set in `bits`, bit 0 first.
void print_bits(const char* const* names, int count, uint8_t bits) {
    const char* sep = " (";
    for (int b = 0; b < count; ++b) {
        if (!(bits & (1u << b))) continue;
        fprintf(stderr, "%s%s", sep, names[b]);
        sep = ", ";
    }
    if (sep[0] == ',') fprintf(stderr, ")");
}

// The per-sample line: the columns of `battsim replay --series` of the same name, written
// as it writes them (empty while a value is not known yet).
void print_line(const Sample& s, const MonitorStatus& st) {
    printf("%.6f,", seconds(s.time_us));
    if (st.initialised) printf("%.5f", static_cast<double>(st.soc));  // no state of charge before the first rest
    printf(",%.5f,", static_cast<double>(st.capacity_ah));
    if (st.resistance_ohm > 0.0f) printf("%.6f", static_cast<double>(st.resistance_ohm));
    printf(",");
    if (st.time_valid) printf("%.2f", static_cast<double>(st.remaining_time_s));  // from the take-off on
    printf(",%d,%d,%u,%d\n", st.flying ? 1 : 0, st.sample_valid ? 1 : 0, static_cast<unsigned>(st.warnings),
           st.outlier_cell + 1);  // outlier_cell is 0-based, −1 = none; printed 1-based, 0 = none
}

// Warnings as they come on (a pilot's alert, a buzzer, a MAVLink STATUSTEXT: src/telemetry
// does that last one), and the landing's capacity.
void report_events(const Sample& s, const MonitorStatus& st, uint8_t& warnings_before, bool& flying_before) {
    const uint8_t raised = static_cast<uint8_t>(st.warnings & ~warnings_before);
    for (int w = 0; w < battsim::core::kWarnCount; ++w) {
        if (!(raised & (1u << w))) continue;
        fprintf(stderr, "warning %s raised at %.3f s", kWarningNames[w], seconds(s.time_us));
        if (w == battsim::core::kWarnCellOutlier && st.outlier_cell >= 0) {
            fprintf(stderr, " (cell %d, %s)", st.outlier_cell + 1,
                    st.cell_finding == CellAnalyzer::kLowCapacity ? "low capacity" : "high resistance");
        } else if (w == battsim::core::kWarnShortFlight) {
            const char* const causes[] = {"capacity", "resistance"};  // JointEstimator::Cause bits
            print_bits(causes, 2, st.short_flight_cause);
        } else if (w == battsim::core::kWarnSensorFault) {
            const char* const causes[] = {"pack reading", "cell reading", "current offset",
                                          "sample gap"};  // core::SensorFaultCause bits
            print_bits(causes, 4, st.sensor_fault_cause);
        }
        fprintf(stderr, "\n");
    }
    warnings_before = st.warnings;
    if (flying_before && !st.flying) {
        fprintf(stderr, "landed at %.3f s: capacity %.3f +/- %.3f Ah, resistance %.2f mOhm, %.0f mAh drawn\n",
                seconds(s.time_us), static_cast<double>(st.capacity_ah), static_cast<double>(st.capacity_sigma_ah),
                static_cast<double>(st.resistance_ohm * 1000.0f), static_cast<double>(st.consumed_mah));
    }
    flying_before = st.flying;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s RAW_LOG\n", argv[0]);
        return 2;
    }
    FILE* in = fopen(argv[1], "r");
    if (in == nullptr) {
        fprintf(stderr, "cannot open %s\n", argv[1]);
        return 2;
    }
    g_monitor.configure(kConfig);  // at boot, and again for a new pack (it starts afresh)
    printf("time_s,soc,capacity_ah,resistance_ohm,remaining_time_s,flying,sample_valid,warnings,outlier_cell\n");
    Sample sample;
    uint8_t warnings_before = 0;
    bool flying_before = false;
    while (read_reading(in, sample)) {
        const MonitorStatus& st = g_monitor.update(sample);  // one call per reading
        print_line(sample, st);
        report_events(sample, st, warnings_before, flying_before);
    }
    fclose(in);
    return 0;
}
