// The discharge logger on the NodeMCU: raw readings and a coulomb count over the UART,
// for `battsim log` on the host (docs/firmware.md, discharge test).
#include <Arduino.h>

#include "app/logger_app.h"
#include "arduino/config_header.h"
#include "arduino/drivers.h"

namespace {

battsim::fw::InaSensors g_sensors;
battsim::fw::ArduinoClock g_clock;
battsim::fw::OledDisplay g_display;
battsim::fw::UartPort g_serial;
battsim::fw::LoggerApp g_app(g_sensors, g_clock, g_display, g_serial);

}  // namespace

void setup() {
    Serial.begin(BATTSIM_BAUD);
    battsim::fw::radio_off();
    // Shunt calibration and cell count come from the same exported config as the monitor.
    constexpr battsim::core::MonitorConfig kConfig = battsim_generated::monitor_config();
    battsim::fw::LoggerAppConfig config;
    config.cells_in_series = kConfig.cells_in_series;
    config.shunt = kConfig.shunt;
    config.display = BATTSIM_OLED_OUT != 0;
    g_app.begin(config);
}

void loop() { g_app.step(); }
