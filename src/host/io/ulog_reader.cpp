#include "host/io/ulog_reader.h"
// Placeholder until the ULog reader lands (issue 6).
namespace battsim {
namespace host {
std::unique_ptr<SampleReader> open_ulog(const std::string& path, const ReaderOptions&) {
    throw InputError(path, 0, 0, "ULog files are not supported yet");
}
}  // namespace host
}  // namespace battsim
