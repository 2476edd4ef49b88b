// battsim bench monitor|replay|batch: the figures in docs/benchmarks.md (scripts/bench.sh
// runs them all, and the callgrind count of instructions per monitor update).
#include <functional>
#include <iostream>
#include <thread>

#include "command.h"
#include "common_options.h"
#include "host/batch/bench.h"
#include "host/config_json.h"
#include "host/report/summary.h"

namespace battsim {
namespace cli {
namespace {

struct BenchArgs {
    std::vector<std::string> paths;
    std::string manifest;
    std::uint64_t passes = 0;
    double min_time = 1.0;
    std::uint64_t min_runs = 3;
    unsigned jobs = 0;
    bool json = false;
    InputArgs input;
};

// The logs with their settings, exactly as `battsim batch` would plan them.
int plan(const BenchArgs& a, std::vector<host::BatchItem>& items) {
    host::BatchPlanRequest req;
    req.paths = a.paths;
    req.manifest = a.manifest;
    try {
        req.command_line = host::settings_from_strings(setting_strings(a.input));
        items = host::plan_batch(req);
    } catch (const std::invalid_argument& e) {
        std::cerr << "battsim bench: " << e.what() << "\n";
        return kExitUsage;
    } catch (const host::InputError& e) {
        std::cerr << "battsim bench: " << e.what() << "\n";
        return kExitInputError;
    } catch (const host::ConfigError& e) {
        std::cerr << "battsim bench: config: " << e.what() << "\n";
        return kExitConfigError;
    }
    if (items.empty()) {
        std::cerr << "battsim bench: no logs\n";
        return kExitUsage;
    }
    for (const host::BatchItem& it : items) {
        if (!it.error.empty()) {
            std::cerr << "battsim bench: " << it.path << ": " << it.error << "\n";
            return kExitInputError;
        }
    }
    return kExitOk;
}

// The figures to six significant digits (seconds had printed as 9.133000000000578e-06), and
// as JSON with the schema fields every other report carries.
void print(const std::string& benchmark, nlohmann::json j, bool as_json) {
    for (auto it = j.begin(); it != j.end(); ++it)
        if (it.value().is_number_float()) it.value() = host::round_sig(it.value().get<double>());
    if (as_json) {
        nlohmann::json out = {{"schema", "battsim.bench"}, {"schema_version", 1}, {"battsim_version", BATTSIM_VERSION},
                              {"benchmark", benchmark}};
        for (auto it = j.begin(); it != j.end(); ++it) out[it.key()] = it.value();
        std::cout << host::json_text(out, 2) << "\n";
        return;
    }
    for (auto it = j.begin(); it != j.end(); ++it) std::cout << it.key() << ": " << host::json_text(it.value()) << "\n";
}

// Times the first planned log with `bench`, which returns the figures to print.
int bench_first_log(const BenchArgs& a, const std::string& benchmark,
                    const std::function<nlohmann::json(const host::BatchItem&)>& bench) {
    std::vector<host::BatchItem> items;
    if (int rc = plan(a, items)) return rc;
    try {
        print(benchmark, bench(items.front()), a.json);
    } catch (const host::InputError& e) {
        std::cerr << "battsim bench: " << e.what() << "\n";
        return kExitInputError;
    }
    return kExitOk;
}

int run_monitor(const BenchArgs& a) {
    return bench_first_log(a, "monitor", [&a](const host::BatchItem& it) -> nlohmann::json {
        const host::MonitorBench r = host::bench_monitor(it.path, it.replay, a.passes, a.min_time);
        return {{"log", it.path},
                {"samples_per_pass", r.samples},
                {"passes", r.passes},
                {"updates", r.samples * r.passes},
                {"seconds", r.seconds},
                {"cpu_seconds", r.cpu_seconds},
                {"ns_per_update", r.ns_per_update},
                {"cpu_ns_per_update", r.cpu_ns_per_update},
                {"peak_rss_kib", host::peak_rss_kib()}};
    });
}

int run_replay(const BenchArgs& a) {
    return bench_first_log(a, "replay", [&a](const host::BatchItem& it) -> nlohmann::json {
        const host::ThroughputBench r = host::bench_replay(it.path, it.replay, a.min_time, a.min_runs);
        return {{"log", it.path},
                {"runs", r.runs},
                {"samples", r.samples},
                {"bytes", r.bytes},
                {"seconds", r.seconds},
                {"cpu_seconds", r.cpu_seconds},
                {"samples_per_s", r.samples_per_second()},
                {"mb_per_s", r.megabytes_per_second()},
                {"mb_per_cpu_s", r.megabytes_per_cpu_second()},
                {"ns_per_sample", r.samples ? r.seconds * 1e9 / r.samples : 0.0},
                {"cpu_ns_per_sample", r.samples ? r.cpu_seconds * 1e9 / r.samples : 0.0},
                {"peak_rss_kib", host::peak_rss_kib()}};
    });
}

int run_batch(const BenchArgs& a) {
    std::vector<host::BatchItem> items;
    if (int rc = plan(a, items)) return rc;
    const unsigned jobs = a.jobs > 0 ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
    const host::ThroughputBench r = host::bench_batch(items, jobs, a.min_time, a.min_runs);
    if (!r.failure.empty()) {
        std::cerr << "battsim bench: " << r.failure << "\n";
        return kExitInputError;
    }
    print("batch", {{"runs", r.runs},
           {"logs", r.logs},
           {"jobs", r.jobs},
           {"samples", r.samples},
           {"bytes", r.bytes},
           {"seconds", r.seconds},
           {"cpu_seconds", r.cpu_seconds},
           {"mb_per_cpu_s", r.megabytes_per_cpu_second()},
           {"logs_per_s", r.seconds > 0 ? r.logs / r.seconds : 0.0},
           {"samples_per_s", r.samples_per_second()},
           {"mb_per_s", r.megabytes_per_second()},
           {"peak_rss_kib", host::peak_rss_kib()}},
          a.json);
    return kExitOk;
}

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<BenchArgs>();
    sub.require_subcommand(1);
    CLI::App* mon = sub.add_subcommand("monitor", "ns per core::Monitor::update over a log's samples held in memory");
    CLI::App* rep = sub.add_subcommand("replay", "End-to-end replay throughput of one log (samples/s, MB/s)");
    CLI::App* bat = sub.add_subcommand("batch", "Batch throughput over many logs with --jobs threads");
    for (CLI::App* s : {mon, rep, bat}) {
        s->add_option("-m,--manifest", a->manifest, "Manifest giving the logs' settings (as for batch)");
        s->add_flag("--json", a->json, "Print the figures as JSON");
        add_input_options(*s, a->input);
    }
    mon->add_option("LOG", a->paths, "Log to replay")->required()->expected(1);
    // Read as unsigned, -1 had wrapped to 2^64 - 1 passes and hung.
    mon->add_option("--passes", a->passes, "Passes over the log (default: until --min-time)")->check(CLI::Range(1, 100000000));
    mon->add_option("--min-time", a->min_time, "Seconds of updates to time at least")->check(number_in(0.0, 3600.0))->capture_default_str();
    rep->add_option("LOG", a->paths, "Log to replay")->required()->expected(1);
    rep->add_option("--min-time", a->min_time, "Seconds to keep replaying")->check(number_in(0.0, 3600.0))->capture_default_str();
    rep->add_option("--min-runs", a->min_runs, "Replays at least")->check(CLI::Range(1, 100000000))->capture_default_str();
    bat->add_option("PATHS", a->paths, "Logs: files, directories, patterns (or --manifest alone)");
    bat->add_option("-j,--jobs", a->jobs, "Threads (default or 0: the machine's cores)")->check(CLI::Range(0, 1024));
    bat->add_option("--min-time", a->min_time, "Seconds to keep repeating the batch")->check(number_in(0.0, 3600.0))->capture_default_str();
    bat->add_option("--min-runs", a->min_runs, "Batches at least")->check(CLI::Range(1, 100000000))->capture_default_str();
    return [a, mon, rep]() -> int {
        if (mon->parsed()) return run_monitor(*a);
        if (rep->parsed()) return run_replay(*a);
        return run_batch(*a);
    };
}

const RegisterCommand reg{{"bench", "Benchmarks: monitor update cost, replay and batch throughput, memory", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
