// battsim batch PATHS…: replay many logs in parallel and write the appendix table,
// per-log summaries, shards of the work and a regression check against goldens.
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <mutex>
#include <thread>

#include "command.h"
#include "common_options.h"
#include "host/batch/batch.h"
#include "host/batch/table.h"
#include "host/config_json.h"
#include "host/io/atomic_file.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace cli {
namespace {

namespace fs = std::filesystem;

struct BatchArgs {
    std::vector<std::string> paths;
    std::string manifest;
    std::string format = "md";
    std::string output = "-";
    bool output_given = false;
    std::string packs;
    std::string monitors;
    std::string out_dir;
    std::string shard;
    std::string compare;
    double tolerance = 1e-6;
    unsigned jobs = 0;
    bool no_progress = false;
    InputArgs input;
};

int run(const BatchArgs& a) {
    const char* me = "battsim batch: ";
    host::TableFormat format;
    host::ShardSpec shard;
    host::BatchPlanRequest plan;
    try {
        format = host::parse_table_format(a.format);
        if (!a.shard.empty()) shard = host::parse_shard(a.shard);
        plan.command_line = host::settings_from_strings(setting_strings(a.input));
    } catch (const std::invalid_argument& e) {
        std::cerr << me << e.what() << "\n";
        return kExitUsage;
    }
    if (a.paths.empty() && a.manifest.empty()) {
        std::cerr << me << "expected logs (files, directories or patterns) or --manifest FILE\n";
        return kExitUsage;
    }
    if (!(a.tolerance >= 0)) {
        std::cerr << me << "--tolerance: expected a relative tolerance >= 0\n";
        return kExitUsage;
    }
    plan.paths = a.paths;
    plan.manifest = a.manifest;
    plan.outputs = {a.output_given ? a.output : std::string(), a.packs, a.monitors};

    std::vector<host::BatchItem> all;
    try {
        all = host::plan_batch(plan);
    } catch (const host::InputError& e) {
        std::cerr << me << e.what() << "\n";
        return kExitInputError;
    } catch (const host::ConfigError& e) {
        std::cerr << me << "config: " << e.what() << "\n";
        return kExitConfigError;
    } catch (const std::invalid_argument& e) {  // a log the command line names twice
        std::cerr << me << e.what() << "\n";
        return kExitUsage;
    }
    // A missing golden directory is one mistake, not one "no golden" per log.
    std::error_code dir_ec;
    if (!a.compare.empty() && !fs::is_directory(a.compare, dir_ec)) {
        std::cerr << me << "--compare: " << a.compare << " is not a directory of golden summaries\n";
        return kExitUsage;
    }
    if (!a.out_dir.empty() || !a.compare.empty()) {
        // Logs of one stem (ArduPilot's 00000001.BIN on every card) are named by their paths
        // (plan_batch); only names that still clash, which no rule can part, are refused.
        const std::vector<std::string> dups = host::duplicate_summary_names(all);
        if (!dups.empty()) {
            // Only the options given: "--compare" had been named in a run without it.
            const std::string given = !a.out_dir.empty() && !a.compare.empty() ? "--out and --compare name"
                                      : !a.out_dir.empty()                      ? "--out names"
                                                                                : "--compare names";
            std::cerr << me << given
                      << " summaries <log stem>.json (logs of one stem: <path below their common directory, / as __>.json), "
                         "but these logs would share one:\n";
            for (const std::string& d : dups) std::cerr << "  " << d << "\n";
            // A log given twice by two spellings was refused before (plan_batch): these are two logs.
            std::cerr << me << "rename one of the files (or its directory)\n";
            return kExitUsage;
        }
        // Said, the first few, so the operator finds each log's summary (and names its golden).
        const std::vector<std::string> renamed = host::renamed_summaries(all);
        constexpr size_t kRenamedShown = 5;
        for (size_t k = 0; k < renamed.size() && k < kRenamedShown; ++k)
            std::cerr << me << "note: stem shared, summary named by its path: " << renamed[k] << "\n";
        if (renamed.size() > kRenamedShown)
            std::cerr << me << "note: " << renamed.size() - kRenamedShown << " more summaries named by their paths\n";
    }
    const std::string digest = host::inputs_digest(all);
    std::vector<host::BatchItem> items;
    for (const host::BatchItem& it : all)
        if (shard.contains(it.index)) items.push_back(it);

    // Every log listed and every config read is an input, the goldens too (a summary
    // written over its golden would compare equal); every summary --out writes is an output.
    std::vector<host::NamedPath> inputs{{"-m/--manifest", a.manifest}};
    for (const host::BatchItem& it : all) {
        inputs.push_back({"a log", it.path});
        inputs.push_back({"the config of " + it.path, it.config_path});
    }
    std::vector<host::NamedPath> outputs{
        text_output(a.output_given ? "-o/--output" : "the table (standard output without -o)", a.output),
        text_output("--packs", a.packs),
        text_output("--monitors", a.monitors),
        {"--out", a.out_dir, false, host::Dash::Refused, true}};
    for (const host::BatchItem& it : items) {
        if (!a.compare.empty())
            inputs.push_back({"--compare's " + it.summary_stem() + ".json",
                              (fs::path(a.compare) / (it.summary_stem() + ".json")).string()});
        if (!a.out_dir.empty())
            outputs.push_back({"--out's " + it.summary_stem() + ".json", (fs::path(a.out_dir) / (it.summary_stem() + ".json")).string()});
    }
    if (int rc = check_outputs("battsim batch", inputs, outputs)) return rc;
    // What each config makes unreliable, once per config.
    for (const host::CountedNote& n : host::count_config_notes(items)) std::cerr << me << host::counted_note_text(n) << "\n";

    host::BatchRunOptions opt;
    opt.jobs = a.jobs > 0 ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
    opt.out_dir = a.out_dir;
    opt.keep_summaries = !a.compare.empty();
    const bool bar = !a.no_progress && ::isatty(STDERR_FILENO);
    if (bar) {
        opt.progress = [](size_t done, size_t total, size_t failed) {
            std::cerr << "\r" << host::progress_line(done, total, failed) << std::flush;
        };
    }
    host::BatchResult result;
    try {
        result = host::run_batch(items, opt);
    } catch (const std::runtime_error& e) {
        std::cerr << me << e.what() << "\n";
        return kExitOutputError;
    }
    if (bar) std::cerr << "\r\033[K" << std::flush;  // the table replaces the bar

    const size_t failed = result.failed;
    const nlohmann::json table = host::make_table(std::move(result.rows), all.size(), digest, shard);
    for (const nlohmann::json& r : table["rows"])
        if (r["status"] != "ok") std::cerr << me << "failed: " << host::failed_row_text(r) << "\n";
    // Said before the outputs are written: a write that fails is then the last thing said.
    if (failed > 0) std::cerr << me << failed << " of " << items.size() << " logs failed\n";
    for (const std::string& r : result.removed) std::cerr << me << r << "\n";
    // What replay would say of each log (a truncated file, a config for another pack than the
    // log's: every row "ok" all the same), the first few in full: a 4S config on a 6S fleet
    // says it of every log.
    constexpr size_t kLogNotesShown = 5;
    for (size_t k = 0; k < result.log_notes.size() && k < kLogNotesShown; ++k)
        std::cerr << me << "note: " << result.log_notes[k] << "\n";
    if (result.log_notes.size() > kLogNotesShown)
        std::cerr << me << "note: " << result.log_notes.size() - kLogNotesShown
                  << " more such notes (the notes column of the CSV and JSON tables, and each log's summary, --out DIR)\n";
    for (const std::string& u : result.unwritten) std::cerr << me << u << "\n";
    // Each output on its own: one that fails (a full disk) does not take the others with it.
    bool unwritten = false;
    const auto write = [&](const std::string& path, const std::function<std::string()>& render) {
        if (path.empty()) return;
        try {
            host::write_file_atomic(path, render());
        } catch (const std::runtime_error& e) {
            std::cerr << me << e.what() << "\n";
            unwritten = true;
        }
    };
    write(a.output, [&] { return host::render_table(table, format); });
    write(a.packs, [&] { return host::render_packs(table, format); });
    write(a.monitors, [&] { return host::render_monitors(table, format); });

    bool regressed = false;
    if (!a.compare.empty()) {
        const host::GoldenComparison c = host::compare_to_goldens(
            items, result.summaries, a.compare, host::golden_compare_options(a.tolerance));
        for (const std::string& line : c.lines) std::cerr << "compare: " << line << "\n";
        std::cerr << "compare: " << c.compared << " compared, " << c.changed << " changed, " << c.missing
                  << " without golden, " << c.failed << " not replayed (tolerance " << a.tolerance << " relative)\n";
        regressed = !c.ok();
    }
    if (!result.unwritten.empty() || unwritten) return kExitOutputError;
    return failed > 0 || regressed ? kExitFailure : kExitOk;
}

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<BatchArgs>();
    sub.add_option("PATHS", a->paths, "Logs: files, directories (their files, not recursive) and glob patterns");
    sub.add_option("-m,--manifest", a->manifest, "Manifest (JSON or CSV) mapping logs to packs, configs and columns");
    sub.add_option("-j,--jobs", a->jobs, "Parallel replays (default or 0: the machine's cores)")->check(CLI::Range(0, 1024));

    auto* output = sub.add_option("-o,--output", a->output, "Write the table here (atomically) instead of standard output");
    sub.add_option("--packs", a->packs, "Also write the per-pack table here, in --format (\"-\" = standard output)");
    sub.add_option("--monitors", a->monitors,
                   "Also write the per-monitor table (charger checks pooled per current sensor) here, in --format "
                   "(\"-\" = standard output)");
    sub.add_option("--out", a->out_dir,
                   "Write each log's summary JSON here as <log stem>.json, as it completes (logs of one stem: "
                   "<path below their common directory, / as __>.json)");
    sub.add_option("--shard", a->shard, "Replay only shard K of N (K/N, 1-based): inputs whose index mod N is K-1");
    auto* compare = sub.add_option("--compare", a->compare,
                   "Compare each summary with GOLDEN_DIR/<log stem>.json (named as --out names it); exit 1 on a change");
    // Finite, and only with --compare: inf had passed every comparison, and alone it did nothing.
    sub.add_option("--tolerance", a->tolerance, "--compare: relative tolerance (plus 1e-9 absolute)")
        ->capture_default_str()
        ->check(number_in(0.0, 1.0e6))
        ->needs(compare);
    sub.add_flag("--no-progress", a->no_progress, "No progress bar (it is shown only when stderr is a terminal)");
    add_input_options(sub, a->input);
    // Here --format is the table's format (as for merge); the logs' format moves to
    // --log-format, usually set per log in the manifest anyway.
    sub.remove_option(sub.get_option("--format"));
    sub.add_option("--log-format", a->input.format, host::log_format_help())
        ->capture_default_str();
    sub.add_option("--format", a->format, "Table format: md, csv or json (json is what merge reads)")->capture_default_str();
    return [a, output]() {
        a->output_given = output->count() > 0;
        return run(*a);
    };
}

const RegisterCommand reg{{"batch", "Replay many logs in parallel into one table (shards, goldens, packs)", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
