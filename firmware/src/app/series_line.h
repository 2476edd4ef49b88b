// The monitor's output line: the per-sample series CSV of `battsim replay --series`,
// byte for byte (same columns, same number formatting), written here without src/host
// so the firmware depends on the core only. A device SD log therefore diffs directly
// against a replay of the same readings; tests/unit/test_firmware_replay.cpp holds the
// two writers to that.
#pragma once
#include "telemetry/text_buffer.h"
#include "core/monitor.h"
#include "core/sample.h"

namespace battsim {
namespace fw {

// Longest line, the header: 23 fixed columns plus 5 × kMaxCells cell columns (about 920
// characters with 6 cells); a data line is shorter.
constexpr size_t kSeriesLineCapacity = 1024;

// The header line with its '\n'; `cells` = cell columns (the first sample's cell count).
void format_series_header(int cells, telemetry::TextBuffer& out);
// One row with its '\n'.
void format_series_line(const core::Sample& sample, const core::MonitorStatus& s, int cells, telemetry::TextBuffer& out);

}  // namespace fw
}  // namespace battsim
