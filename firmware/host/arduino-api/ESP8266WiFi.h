// Compile-check declarations of the ESP8266 core's Wi-Fi switch (README.md here).
#pragma once
#include <stdint.h>

enum WiFiMode_t { WIFI_OFF = 0, WIFI_STA = 1, WIFI_AP = 2, WIFI_AP_STA = 3 };

class ESP8266WiFiClass {
public:
    bool mode(WiFiMode_t mode);
    bool forceSleepBegin(uint32_t sleep_us = 0);
};
extern ESP8266WiFiClass WiFi;
