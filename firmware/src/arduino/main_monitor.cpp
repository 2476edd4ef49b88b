// The monitor program on the NodeMCU: setup() wires the real drivers to the app, loop()
// runs one step. Everything else is in src/app, the same code the host tests run.
#include <Arduino.h>

#include "app/monitor_app.h"
#include "arduino/config_header.h"
#include "arduino/drivers.h"

namespace {

battsim::fw::WireBus g_bus;
battsim::fw::InaSensors g_sensors(g_bus);
battsim::fw::ArduinoClock g_clock;
battsim::fw::SdStorage g_storage;
battsim::fw::OledDisplay g_display;
battsim::fw::UartPort g_serial;
battsim::fw::TelemetryUartPort g_telemetry;
battsim::fw::GpioBuzzer g_buzzer;
// Static, not on the stack: the app holds the whole core::Monitor (6,496 B on the target).
battsim::fw::MonitorApp g_app(g_sensors, g_clock, g_storage, g_display, g_serial);

}  // namespace

void setup() {
    Serial.begin(BATTSIM_BAUD);
    Serial1.begin(BATTSIM_MAVLINK_BAUD);
    battsim::fw::radio_off();
    g_bus.begin();
    battsim::fw::MonitorAppConfig config;
    config.monitor = battsim_generated::monitor_config();
    config.outputs.uart = BATTSIM_UART_OUT != 0;
    config.outputs.sd = BATTSIM_SD_OUT != 0;
    config.outputs.display = BATTSIM_OLED_OUT != 0;
    config.outputs.mavlink = BATTSIM_MAVLINK_OUT != 0;
    config.outputs.buzzer = BATTSIM_BUZZER_OUT != 0;
    config.telemetry = battsim_generated::telemetry_config();
    g_app.attach_telemetry(g_telemetry);
    g_buzzer.begin();
    g_app.attach_buzzer(g_buzzer);
    g_app.begin(config);
}

void loop() { g_app.step(); }
