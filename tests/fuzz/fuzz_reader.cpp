// libFuzzer harness: any bytes, any format detection, every reader. The only acceptable
// outcomes are samples or an InputError; a crash, a sanitizer report, a hang or another
// exception type is a bug (and becomes a regression test under tests/fuzz/regressions).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "host/io/sample_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = "/tmp/battsim-fuzz-reader-" + std::to_string(::getpid());
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    if (size) std::fwrite(data, 1, size, f);
    std::fclose(f);
    // The first byte picks the forced format too, so every reader sees every input.
    const auto& formats = battsim::host::log_formats();  // Auto first: the empty input detects
    battsim::host::ReaderOptions opt;
    opt.format = formats[size ? data[0] % formats.size() : 0].format;
    // The second byte switches the averaging reader on for one input in four.
    if (size > 1 && data[1] % 4 == 0) opt.average_us = 1000u * (1u + data[1] % 64u);
    try {
        auto reader = battsim::host::open_reader(path, opt);
        battsim::core::Sample s;
        long n = 0;
        while (reader->next(s) && n < 1000000) ++n;
    } catch (const battsim::host::InputError&) {
    }
    std::remove(path.c_str());  // nothing left in /tmp when the fuzzer stops
    return 0;
}
