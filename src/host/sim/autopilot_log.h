// Simulated flights written as an autopilot's binary log, so the suites can be flown through
// the DataFlash and ULog readers as an ArduPilot or PX4 user's logs are:
//  * ArduPilot DataFlash (.bin): each battery update as a BAT message (TimeUS, Instance, Volt,
//    VoltR, Curr, CurrTot, EnrgTot, Temp in centi-degrees, Res) followed by a BCL message with
//    the same TimeUS (Volt, V1..V12 in mV, 0 for no cell), in ArduPilot's own order and
//    layout, each defined by an FMT message first;
//  * PX4 ULog (.ulg): battery_status (timestamp, voltage_v, current_a, discharged_mah,
//    temperature, cell_count, voltage_cell_v[14]) after the header, flag bits, format and
//    subscription messages of the ULog specification.
// The values are the simulated sensors' readings, as the CSV log holds them; the autopilot's
// own logging rate is the caller's thinning (autopilot_log_interval_s).
#pragma once

#include "core/sample.h"

#include <cstdint>
#include <string>

namespace battsim {
namespace host {
namespace sim {

enum class AutopilotLog { DataFlash, ULog };

// The autopilots' default battery logging intervals: ArduPilot's battery monitor updates
// and logs BAT at 10 Hz; PX4's logger records battery_status every 200 ms.
double autopilot_log_interval_s(AutopilotLog kind);

class AutopilotLogWriter {
public:
    AutopilotLogWriter(AutopilotLog kind, int cells);
    // The definitions that open the log.
    std::string header() const;
    // One battery update; cell_v holds `cells` voltages.
    void append(std::string& out, int64_t time_us, double voltage_v, double current_a, const double* cell_v,
                double temperature_c);

private:
    AutopilotLog kind_;
    int cells_;
    double consumed_mah_ = 0;
    double consumed_wh_ = 0;
    int64_t last_time_us_ = -1;
};

}  // namespace sim
}  // namespace host
}  // namespace battsim
