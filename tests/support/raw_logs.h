// Small synthetic logs in the dissertation logger's raw format, for the unit and CLI tests.
#pragma once
#include <cstdio>
#include <string>

namespace testsupport {

// A raw predictive-bms log: 10 s of rest, then a load whose voltage sags with the charge
// drawn. `amps` and `sag_v_per_s` make each log's numbers different.
inline std::string raw_flight(double amps, double sag_v_per_s, int load_rows = 400) {
    std::string s;
    long t = 630;
    char line[160];
    for (int k = 0; k < 150; ++k, t += 67) {
        std::snprintf(line, sizeof line, "%ld,16.50,4.12,4.13,4.12,4.13,250.00,1.32,\n", t);
        s += line;
    }
    for (int k = 0; k < load_rows; ++k, t += 67) {
        const double v = 16.2 - amps * 0.02 - sag_v_per_s * k * 0.067;
        const double c = v / 4;
        std::snprintf(line, sizeof line, "%ld,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,\n", t, v, c, c + 0.01, c, v - 3 * c - 0.01,
                      amps * 1000.0, amps * 0.378);
        s += line;
    }
    return s;
}

}  // namespace testsupport
