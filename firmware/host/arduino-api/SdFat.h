// Compile-check declarations of greiman/SdFat 2.x (README.md here): the FAT/exFAT
// volume (SdFs), its files (FsFile) and the SPI card configuration.
#pragma once
#include <stddef.h>
#include <stdint.h>

typedef uint8_t oflag_t;
#define O_RDONLY 0x00
#define O_WRONLY 0x01
#define O_RDWR 0x02
#define O_APPEND 0x08
#define O_CREAT 0x10
#define O_TRUNC 0x20

const uint8_t SHARED_SPI = 0;
const uint8_t DEDICATED_SPI = 1;
#define SD_SCK_MHZ(mhz) (1000000UL * (mhz))

class SdSpiConfig {
public:
    SdSpiConfig(uint8_t chip_select_pin, uint8_t options, uint32_t max_sck_hz);
};

class FsFile {
public:
    bool open(const char* path, oflag_t flags = O_RDONLY);
    bool isOpen() const;
    bool close();
    int available();
    int read(void* buf, size_t count);  // -1 on error
    size_t write(const void* buf, size_t count);
    bool sync();
};

class SdFs {
public:
    bool begin(SdSpiConfig config);
    bool exists(const char* path);
    bool mkdir(const char* path, bool make_parents = true);
    bool remove(const char* path);
    bool rename(const char* old_path, const char* new_path);
};
