// The discharge logger: raw readings (INA226 bus and shunt voltage, INA3221 cumulative
// taps as cell voltages) with a coulomb count, streamed as CSV over the UART once a host
// has said hello (`battsim log`). Every number is written so that `battsim replay` of the
// recorded file sees the very floats the device computed:
//   time_us,voltage_v,current_a,shunt_mv,cell1_v..cellN_v,consumed_mah,missed_readings
// voltage, shunt and cells are exact decimals of the integer readings; current_a has 9
// significant digits (a float read back exactly). The mAh count starts at the handshake.
// Without a tap chip at the hello the header and lines carry no cell columns (and a note says
// so): the pack's curve is what a discharge test needs first.
#pragma once
#include <stdint.h>

#include "app/hardware.h"
#include "app/line_link.h"
#include "app/reading_loop.h"
#include "telemetry/text_buffer.h"
#include "core/estimate/coulomb_counter.h"
#include "core/sensor.h"

namespace battsim {
namespace fw {

struct LoggerAppConfig {
    int cells_in_series = 4;
    core::ShuntCalibration shunt;
    bool display = true;
    uint32_t display_interval_ms = 500;
    uint32_t poll_us = 1000;
};

class LoggerApp {
public:
    enum class Step { Reading, Timeout, SensorError };

    LoggerApp(Sensors& sensors, Clock& clock, Display& display, SerialPort& serial)
        : sensors_(sensors), clock_(clock), display_(display), link_(serial), readings_(sensors, clock) {}

    void begin(const LoggerAppConfig& config);
    Step step();

    uint32_t lines_sent() const { return lines_sent_; }
    bool connected() const { return link_.connected(); }
    ReadingCounters counters() const { return readings_.counters(); }
    float consumed_mah() const { return counter_.status().consumed_mah; }

private:
    void handle_serial();
    void send_header();
    void send_line(float current_a, const int32_t* cells_10uv);

    Sensors& sensors_;
    Clock& clock_;
    Display& display_;
    LineLink link_;
    ReadingLoop readings_;
    LoggerAppConfig config_;
    core::CoulombCounter counter_;
    bool sensors_ok_ = false;
    bool display_ok_ = false;
    bool counting_ = false;
    uint64_t last_time_us_ = 0;
    uint32_t lines_sent_ = 0;
    uint32_t last_display_ms_ = 0;
    bool displayed_ = false;
    uint32_t last_sensor_retry_ms_ = 0;
    int cells_ = 0;         // cells the config asks for (0: none measurable)
    int header_cells_ = 0;  // cells in the header last sent: none when no tap chip answered
    Reading reading_;
    telemetry::FixedText<256> line_;
};

}  // namespace fw
}  // namespace battsim
