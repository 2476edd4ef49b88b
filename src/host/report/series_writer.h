// Per-sample series CSV: one row per sample the monitor accepted, fixed column set,
// fixed number formatting (byte-identical output for the same input).
#pragma once
#include <memory>
#include <string>

#include "core/monitor.h"
#include "core/sample.h"
#include "host/io/atomic_file.h"

namespace battsim {
namespace host {

class SeriesWriter {
public:
    SeriesWriter(const std::string& path, int cells);
    void add(const core::Sample& sample, const core::MonitorStatus& s);
    void commit();

private:
    std::unique_ptr<AtomicFile> file_;
    int cells_;
    std::string line_;
};

// The header line (without newline), for documentation and tests.
std::string series_header(int cells);

}  // namespace host
}  // namespace battsim
