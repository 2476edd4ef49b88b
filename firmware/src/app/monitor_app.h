// The monitor program: every INA226 reading goes through core::Monitor, and its status
// goes to the UART (series lines after a host's hello), to a series CSV on the SD card
// to the OLED, as MAVLink to a second (telemetry) UART and as beeps to a buzzer, each switchable. Landing saves the long-term current and power
// averages to the card; the next boot starts its rolling averages from them.
#pragma once
#include <stdint.h>

#include "app/beeper.h"
#include "app/hardware.h"
#include "app/line_link.h"
#include "app/reading_loop.h"
#include "app/series_line.h"
#include "telemetry/text_buffer.h"
#include "core/config.h"
#include "core/estimate/rolling_average.h"
#include "core/monitor.h"
#include "telemetry/mavlink.h"
#include "telemetry/wiring_check.h"

namespace battsim {
namespace fw {

struct Outputs {
    bool uart = true;
    bool sd = true;
    bool display = true;
    bool mavlink = true;  // only with a telemetry port attached
    bool buzzer = true;   // only with a buzzer attached
};

struct MonitorAppConfig {
    core::MonitorConfig monitor;  // from the generated battsim_config.h
    telemetry::TelemetryConfig telemetry;  // the MAVLink output's and the buzzer's, from the same header
    Outputs outputs;
    bool remember_averages = true;       // read/write kAveragesPath
    uint32_t sd_sync_interval_ms = 5000; // card writes stall the loop; batch them
    uint32_t display_interval_ms = 500;  // a full OLED frame takes ~25 ms over I²C
    uint32_t poll_us = 1000;             // conversion-ready polling interval
};

struct MonitorAppState {
    bool sensors_ok = false;
    bool sd_ok = false;      // card present and log file open
    bool display_ok = false;
    bool averages_loaded = false;
    char log_path[24] = {};  // "battsim/log0001.csv"
    uint32_t sd_errors = 0;
    uint32_t flights = 0;    // take-offs seen, including those of earlier boots
    uint32_t samples = 0;
    uint32_t averages_saved = 0;
    // The current held below minus the take-off current for 2 s (telemetry::ReversedCurrentCheck):
    // the shunt's sense wires are the wrong way round (or its offset is far off). Kept for the boot.
    bool current_reversed = false;
    Outputs outputs;
};

class MonitorApp {
public:
    enum class Step { Sample, Timeout, SensorError };

    MonitorApp(Sensors& sensors, Clock& clock, Storage& storage, Display& display, SerialPort& serial)
        : sensors_(sensors), clock_(clock), storage_(storage), display_(display), link_(serial),
          readings_(sensors, clock) {}

    // The UART the MAVLink telemetry goes to (to an autopilot's or a telemetry radio's
    // serial port); before begin(). Without it there is no MAVLink output.
    void attach_telemetry(SerialPort& port) { telemetry_port_ = &port; }
    // The buzzer (app/beeper.h; thresholds from `telemetry` above); before begin().
    void attach_buzzer(Buzzer& buzzer) { buzzer_ = &buzzer; }
    void begin(const MonitorAppConfig& config);
    // One pass of the loop: serial input, wait for a conversion, estimate, outputs.
    Step step();

    const core::MonitorStatus& status() const { return monitor_.status(); }
    const core::Sample& last_sample() const { return sample_; }
    const MonitorAppState& state() const { return state_; }
    ReadingCounters counters() const { return readings_.counters(); }
    // The monitor's configuration as used (initial averages from the card included).
    const core::MonitorConfig& monitor_config() const { return monitor_.config(); }
    // Long-term average current; the core keeps it privately, so the app runs a twin
    // fed exactly as the monitor feeds its own (checked against avg_current_a in tests).
    const core::RollingAverage::Status& current_average() const { return current_average_.status(); }

    // Saves the averages now (also done on every landing).
    bool save_averages();
    // Pushes buffered SD data to the card.
    void sync_storage();

private:
    void handle_serial();
    void handle_command(const char* cmd);
    void open_sd_log();
    void write_outputs();
    void draw_display();
    void send_status_note();
    void silence_buzzer();

    Sensors& sensors_;
    Clock& clock_;
    Storage& storage_;
    Display& display_;
    LineLink link_;
    SerialPort* telemetry_port_ = nullptr;
    Buzzer* buzzer_ = nullptr;
    Beeper beeper_;
    bool buzzing_ = false;
    ReadingLoop readings_;
    MonitorAppConfig config_;
    MonitorAppState state_;
    core::Monitor monitor_;
    core::RollingAverage current_average_;
    telemetry::MavlinkTelemetry telemetry_;
    core::Sample sample_;
    Reading reading_;
    int series_cells_ = -1;  // fixed by the first sample, as in battsim replay
    bool card_ok_ = false;
    bool log_opened_ = false;  // one log file per boot, opened once
    bool was_flying_ = false;
    telemetry::ReversedCurrentCheck reversed_check_;
    uint32_t last_sync_ms_ = 0;
    uint32_t last_display_ms_ = 0;
    bool displayed_ = false;
    uint32_t last_sensor_retry_ms_ = 0;
    telemetry::FixedText<kSeriesLineCapacity> line_;
    telemetry::FixedText<kSeriesLineCapacity> header_;
};

}  // namespace fw
}  // namespace battsim
