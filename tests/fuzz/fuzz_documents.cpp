// libFuzzer harness: any bytes as each JSON document the host reads whole (monitor config,
// scenario, batch manifest, batch table). The only acceptable outcomes are a loaded
// document or the reader's own error type with a message; a crash, a sanitizer report, a
// hang (the position scanner once spun on a stray '}') or another exception type is a bug.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "host/batch/manifest.h"
#include "host/batch/table.h"
#include "host/config_json.h"
#include "host/io/sample_reader.h"
#include "host/sim/scenario.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = "/tmp/battsim-fuzz-documents-" + std::to_string(::getpid()) + ".json";
    if (size == 0) return 0;
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    // The first byte picks the reader; the rest is the document.
    std::fwrite(data + 1, 1, size - 1, f);
    std::fclose(f);
    namespace host = battsim::host;
    try {
        switch (data[0] % 4) {
            case 0: host::load_config_file(path); break;
            case 1: host::sim::load_scenario(path); break;
            case 2: host::load_manifest(path); break;
            default: host::read_table_file(path); break;
        }
    } catch (const host::ConfigError&) {
    } catch (const host::sim::ScenarioError&) {
    } catch (const host::InputError&) {
    }
    std::remove(path.c_str());  // nothing left in /tmp when the fuzzer stops
    return 0;
}
