// PX4 ULog (.ulg): topic battery_status through a small reader of our own.
#pragma once
#include <memory>
#include <string>

#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

std::unique_ptr<SampleReader> open_ulog(const std::string& path, const ReaderOptions& options);

}  // namespace host
}  // namespace battsim
