// The discharge logger on the NodeMCU: raw readings and a coulomb count over the UART,
// for `battsim log` on the host (docs/firmware.md, discharge test).
#include <Arduino.h>

#include "app/logger_app.h"
#include "arduino/config_header.h"
#include "arduino/drivers.h"

namespace {

battsim::fw::WireBus g_bus;
battsim::fw::InaSensors g_sensors(g_bus);
battsim::fw::ArduinoClock g_clock;
battsim::fw::OledDisplay g_display;
battsim::fw::UartPort g_serial;
battsim::fw::LoggerApp g_app(g_sensors, g_clock, g_display, g_serial);

}  // namespace

void setup() {
    Serial.begin(BATTSIM_BAUD);
    battsim::fw::radio_off();
    g_bus.begin();
    // Shunt calibration and cell count come from the same exported config as the monitor
    // (the two fields as constants: the whole MonitorConfig is 940 B of stack).
    constexpr int kCells = battsim_generated::monitor_config().cells_in_series;
    constexpr battsim::core::ShuntCalibration kShunt = battsim_generated::monitor_config().shunt;
    battsim::fw::LoggerAppConfig config;
    config.cells_in_series = kCells;
    config.shunt = kShunt;
    config.display = BATTSIM_OLED_OUT != 0;
    g_app.begin(config);
}

void loop() { g_app.step(); }
