// ArduPilot DataFlash logs (text .log and binary .bin), driven by their FMT messages.
#pragma once
#include <memory>
#include <string>

#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

std::unique_ptr<SampleReader> open_dataflash_text(const std::string& path, const ReaderOptions& options);
std::unique_ptr<SampleReader> open_dataflash_binary(const std::string& path, const ReaderOptions& options);

}  // namespace host
}  // namespace battsim
