// Benchmarks behind `battsim bench`: the monitor's cost per sample, end-to-end replay
// throughput of one log, batch throughput over many, and peak memory. Wall time is
// read here and only here; nothing measured feeds back into any estimate.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "host/batch/batch.h"
#include "host/replay.h"

namespace battsim {
namespace host {

struct MonitorBench {
    std::uint64_t samples = 0;  // per pass
    std::uint64_t passes = 0;
    double seconds = 0;         // wall time in Monitor::update only
    double cpu_seconds = 0;     // CPU time of the process over the same loops
    double ns_per_update = 0;   // wall
    double cpu_ns_per_update = 0;
};
// Reads the log's samples into memory once (the benchmark's own copy; replay streams),
// then runs a freshly configured Monitor over them `passes` times, or until
// `min_seconds` when passes == 0. Throws InputError for a bad log.
MonitorBench bench_monitor(const std::string& log, const ReplayOptions& options, std::uint64_t passes,
                           double min_seconds);

struct ThroughputBench {
    std::uint64_t runs = 0;     // replays of the log (1 for a batch)
    std::uint64_t logs = 0;
    std::uint64_t samples = 0;  // over all runs
    std::uint64_t bytes = 0;    // log bytes read, over all runs
    unsigned jobs = 1;
    double seconds = 0;         // wall time
    // CPU time of the whole process (all threads): on a shared machine the wall time
    // includes waiting for a core, the CPU time does not.
    double cpu_seconds = 0;
    // The first log that failed in the first run ("path: why"); empty when all replayed. A
    // throughput over logs that never opened measures nothing.
    std::string failure;
    double samples_per_second() const { return seconds > 0 ? samples / seconds : 0; }
    double megabytes_per_second() const { return seconds > 0 ? bytes / seconds / 1e6 : 0; }
    double megabytes_per_cpu_second() const { return cpu_seconds > 0 ? bytes / cpu_seconds / 1e6 : 0; }
};
// replay_log end to end (open, parse, monitor, summary), repeated until `min_seconds`
// have passed and at least `min_runs` runs were made.
ThroughputBench bench_replay(const std::string& log, const ReplayOptions& options, double min_seconds,
                             std::uint64_t min_runs);
// run_batch over `items` with `jobs` threads, no outputs written, repeated like
// bench_replay (runs counts whole batches; logs, samples and bytes are per batch × runs).
ThroughputBench bench_batch(const std::vector<BatchItem>& items, unsigned jobs, double min_seconds,
                            std::uint64_t min_runs);

// CPU time used by this process so far (all threads), seconds.
double process_cpu_seconds();

// Peak resident set of this process so far (getrusage ru_maxrss), KiB.
long peak_rss_kib();

}  // namespace host
}  // namespace battsim
