// Shared by the firmware tests: temp dirs, files, running the programs, and the exact
// comparison of two monitor statuses.
#pragma once
#include <cstring>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "core/monitor.h"
#include "core/sample.h"
#include "test_files.h"

namespace fwtest {

using testsupport::read_file;
using testsupport::write_file;
using Run = testsupport::RunResult;

// A fresh directory, removed when the test program exits.
inline std::string temp_dir(const char* tag) { return testsupport::scratch_dir(tag); }

inline std::string q(const std::string& s) { return testsupport::shell_quoted(s); }

// Runs `program args` through the shell; stderr is captured through a file.
inline Run run(const std::string& program, const std::string& args) { return testsupport::run_program(program, args); }

inline std::string flight_path(int n) {
    return std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/" + std::to_string(n) + ".csv";
}

inline std::string reference_config_path() { return std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json"; }

// Bitwise float equality (so −0 ≠ +0 and NaN == NaN with the same bits): "exactly".
inline bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The first field of two statuses that differs, "" if none. Every field of MonitorStatus
// that the reference estimator path fills is compared; `with_cells` = false leaves out
// the fields that depend on per-cell voltages.
inline std::string status_difference(const battsim::core::MonitorStatus& a, const battsim::core::MonitorStatus& b,
                                     bool with_cells) {
    std::ostringstream d;
#define FW_CMP_F(field) \
    if (!same_bits(a.field, b.field)) d << #field " " << a.field << " vs " << b.field << "; ";
#define FW_CMP(field) \
    if (a.field != b.field) d << #field " " << +a.field << " vs " << +b.field << "; ";
    FW_CMP(time_us) FW_CMP_F(dt_s) FW_CMP_F(voltage_v) FW_CMP_F(current_a) FW_CMP_F(filtered_current_a)
    FW_CMP(sample_valid) FW_CMP(initialised) FW_CMP(initial_forced) FW_CMP(flying)
    FW_CMP_F(consumed_mah) FW_CMP_F(consumed_mwh) FW_CMP_F(model_voltage_v) FW_CMP_F(adapted_model_voltage_v)
    FW_CMP_F(soc) FW_CMP_F(capacity_ah) FW_CMP_F(resistance_ohm) FW_CMP_F(usable_capacity_ah)
    FW_CMP_F(remaining_time_s) FW_CMP_F(total_time_s) FW_CMP(time_valid) FW_CMP_F(avg_current_a)
    FW_CMP_F(avg_power_w) FW_CMP_F(long_avg_power_w) FW_CMP_F(expected_time_s) FW_CMP_F(remaining_energy_wh)
    FW_CMP(short_flight_cause)
    if (with_cells) {
        FW_CMP(cells_valid) FW_CMP(cell_count) FW_CMP(outlier_cell) FW_CMP(warnings) FW_CMP(warnings_raised)
        FW_CMP(sensor_fault_samples)
        for (int c = 0; c < battsim::core::kMaxCells; ++c) {
            FW_CMP_F(cell_score[c])
        }
        for (int w = 0; w < battsim::core::kWarnCount; ++w) {
            FW_CMP(warning_time_us[w])
        }
    } else {
        // Bits that do not depend on cells: capacity, resistance, short flight.
        const unsigned mask = (1u << battsim::core::kWarnLowCapacity) | (1u << battsim::core::kWarnHighResistance) |
                              (1u << battsim::core::kWarnShortFlight);
        if ((a.warnings & mask) != (b.warnings & mask)) d << "warnings (capacity/resistance bits); ";
    }
#undef FW_CMP_F
#undef FW_CMP
    return d.str();
}

}  // namespace fwtest
