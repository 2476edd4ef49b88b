// The compiled-in configuration and the build switches, with a clear message when the
// header has not been exported yet.
#pragma once

#if __has_include("battsim_config.h")
#include "battsim_config.h"
#else
#error "firmware/include/battsim_config.h is missing: run `battsim export-config --firmware CONFIG.json -o firmware/include/battsim_config.h` (docs/firmware.md)"
#endif

// Outputs on at boot (each can also be switched over the serial line: "out sd off").
#ifndef BATTSIM_UART_OUT
#define BATTSIM_UART_OUT 1
#endif
#ifndef BATTSIM_SD_OUT
#define BATTSIM_SD_OUT 1
#endif
#ifndef BATTSIM_OLED_OUT
#define BATTSIM_OLED_OUT 1
#endif
#ifndef BATTSIM_BUZZER_OUT
#define BATTSIM_BUZZER_OUT 1
#endif
#ifndef BATTSIM_MAVLINK_OUT
#define BATTSIM_MAVLINK_OUT 1
#endif
// The telemetry UART (D4): 57600 is the autopilots' default for a telemetry port.
#ifndef BATTSIM_MAVLINK_BAUD
#define BATTSIM_MAVLINK_BAUD 57600
#endif
#ifndef BATTSIM_BAUD
#define BATTSIM_BAUD 115200
#endif
