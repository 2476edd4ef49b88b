#include "host/batch/bench.h"

#include <sys/resource.h>
#include <time.h>

#include <chrono>
#include <filesystem>
#include <memory>

#include "core/monitor.h"
#include "host/batch/table.h"

namespace battsim {
namespace host {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::uint64_t file_bytes(const std::string& path) {
    std::error_code ec;
    const auto n = std::filesystem::file_size(path, ec);
    return ec ? 0 : static_cast<std::uint64_t>(n);
}

}  // namespace

MonitorBench bench_monitor(const std::string& log, const ReplayOptions& options, std::uint64_t passes,
                           double min_seconds) {
    ReaderOptions ro = options.reader;
    ro.shunt = options.config.monitor.shunt;  // as replay_log does
    std::vector<core::Sample> samples;
    {
        std::unique_ptr<SampleReader> reader = open_reader(log, ro);
        core::Sample s;
        while (reader->next(s)) samples.push_back(s);
    }
    if (samples.empty()) throw InputError(log, 0, 0, "the log holds no samples");

    MonitorBench r;
    r.samples = samples.size();
    auto monitor = std::make_unique<core::Monitor>();
    volatile float sink = 0.0f;  // keeps the updates from being optimised away
    while (true) {
        monitor->configure(options.config.monitor);  // not timed: once per flight on the drone
        const double c0 = process_cpu_seconds();
        const Clock::time_point t0 = Clock::now();
        float acc = 0.0f;
        for (const core::Sample& s : samples) acc += monitor->update(s).capacity_ah;
        r.seconds += seconds_since(t0);
        r.cpu_seconds += process_cpu_seconds() - c0;
        sink = sink + acc;
        ++r.passes;
        if (passes > 0 ? r.passes >= passes : r.seconds >= min_seconds) break;
    }
    r.ns_per_update = r.seconds * 1e9 / static_cast<double>(r.samples * r.passes);
    r.cpu_ns_per_update = r.cpu_seconds * 1e9 / static_cast<double>(r.samples * r.passes);
    return r;
}

ThroughputBench bench_replay(const std::string& log, const ReplayOptions& options, double min_seconds,
                             std::uint64_t min_runs) {
    ThroughputBench r;
    const std::uint64_t bytes = file_bytes(log);
    const double c0 = process_cpu_seconds();
    const Clock::time_point t0 = Clock::now();
    while (r.runs < min_runs || seconds_since(t0) < min_seconds) {
        const nlohmann::json summary = replay_log(log, options);
        r.samples += summary["samples"]["total"].get<std::uint64_t>();
        r.bytes += bytes;
        ++r.runs;
    }
    r.seconds = seconds_since(t0);
    r.cpu_seconds = process_cpu_seconds() - c0;
    r.logs = 1;
    return r;
}

ThroughputBench bench_batch(const std::vector<BatchItem>& items, unsigned jobs, double min_seconds,
                            std::uint64_t min_runs) {
    ThroughputBench r;
    std::uint64_t bytes = 0;
    for (const BatchItem& it : items) bytes += file_bytes(it.path);
    BatchRunOptions opt;
    opt.jobs = jobs;
    r.jobs = jobs;
    const double c0 = process_cpu_seconds();
    const Clock::time_point t0 = Clock::now();
    while (r.runs < min_runs || seconds_since(t0) < min_seconds) {
        const BatchResult res = run_batch(items, opt);
        if (r.runs == 0) {
            for (const nlohmann::json& row : res.rows) {
                if (row.value("status", std::string()) == "ok") continue;
                r.failure = failed_row_text(row);
                return r;
            }
        }
        r.samples += res.samples;
        r.bytes += bytes;
        r.logs += items.size();
        ++r.runs;
    }
    r.seconds = seconds_since(t0);
    r.cpu_seconds = process_cpu_seconds() - c0;
    return r;
}

double process_cpu_seconds() {
    struct timespec ts {};
    if (::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return 0;
    return static_cast<double>(ts.tv_sec) + ts.tv_nsec * 1e-9;
}

long peak_rss_kib() {
    struct rusage u {};
    if (::getrusage(RUSAGE_SELF, &u) != 0) return -1;
    return u.ru_maxrss;  // KiB on Linux
}

}  // namespace host
}  // namespace battsim
