// `battsim batch`: replay many logs in parallel through replay_log and collect one
// table row per log. Planning (which logs, with which settings) is separate from
// running, so shards, merge and the benchmarks all see the same list.
#pragma once
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/batch/inputs.h"
#include "host/batch/manifest.h"
#include "host/replay.h"
#include "host/report/json_compare.h"

namespace battsim {
namespace host {

struct BatchItem {
    std::size_t index = 0;   // place in the full, unsharded list
    std::string path;        // log path as given or resolved from the manifest
    std::string stem;        // file stem: the row's default label
    // Names the --out summary and the golden (summary_stem()): the stem, unless other logs of
    // the list share it (ArduPilot's 00000001.BIN on every drone's card): then the log's path
    // below those logs' common directory, '/' written "__" (see assign_summary_names).
    std::string summary_name;
    std::string test;        // row label (default: the stem)
    std::string pack;        // empty = none
    std::string monitor;     // empty = none
    double charged_mah = 0;  // the charger's count after this log (0 = none): `charger_check`
    std::string error;       // non-empty: failed before replay (a pattern that matched nothing)
    std::string config_path; // the config file read (empty = the built-in one), an input of the run
    ReplayOptions replay;    // reader settings and the loaded config
    // <summary_stem()>.json is the log's --out summary and its golden; an item made by hand
    // without a summary_name uses its stem.
    const std::string& summary_stem() const { return summary_name.empty() ? stem : summary_name; }
};

struct BatchPlanRequest {
    std::vector<std::string> paths;  // files, directories, patterns; empty with a manifest = all its logs
    std::string manifest;            // empty = none
    LogSettings command_line;        // options given on the command line; they win over the manifest
    std::vector<std::string> outputs;  // files the command writes: left out of directories and patterns
};

// The full ordered list. With a manifest and no paths: the manifest's logs in its order
// (directories and patterns in entries expanded in place). With paths: the expanded
// paths, each taking the settings of the manifest entry naming the same file (or the
// manifest's defaults). Throws InputError (manifest; a log it lists twice, by any name,
// included), ConfigError (a config file) or std::invalid_argument (a log the paths name twice).
std::vector<BatchItem> plan_batch(const BatchPlanRequest& request);

// Identifies the full list (paths, labels, packs, configs) so merge can tell shards of
// one run from shards of another. 16 hex digits (FNV-1a 64).
std::string inputs_digest(const std::vector<BatchItem>& items);

// Sets each item's summary_name: its stem where no other item has that stem; otherwise, for
// every item of a shared stem, its path (made absolute, lexically normal) relative to the
// deepest directory holding all the items of that stem, with '/' written "__":
// d1/00000001.BIN and d2/00000001.BIN are "d1__00000001.BIN" and "d2__00000001.BIN";
// a/x.csv and a/x.bin "x.csv" and "x.bin". Depends only on the set of paths, so it is the same
// for any input order, --jobs and shard (plan_batch calls it on the full list).
void assign_summary_names(std::vector<BatchItem>& items);

// Summary names still shared by more than one item after assign_summary_names ("30: a/30.csv,
// a/30.csv"; only paths that spell one file alike, or "__" in a directory's name, get there),
// which would overwrite each other's summaries in --out and match the same golden file.
std::vector<std::string> duplicate_summary_names(const std::vector<BatchItem>& items);

// Items whose summary is not named by their stem alone ("d1/00000001.BIN: d1__00000001.BIN.json"),
// in item order: said on stderr, so the operator knows where to look.
std::vector<std::string> renamed_summaries(const std::vector<BatchItem>& items);

// A note config_notes makes of a config alone (what it makes unreliable), "config NAME: note",
// and how many of the run's logs are replayed with that config.
struct CountedNote {
    std::string note;
    std::size_t logs = 0;
};
// Said once per config, not per row (every row's notes repeat it): a fleet replayed with the
// joint estimator and no OCV table reads plausible nonsense. Items that failed before replay
// (error) are left out; in the order of the note's text.
std::vector<CountedNote> count_config_notes(const std::vector<BatchItem>& items);
// "note (3 logs), config NAME: note" ("1 log").
std::string counted_note_text(const CountedNote& n);

struct BatchRunOptions {
    unsigned jobs = 1;
    std::string out_dir;          // non-empty: write <summary_stem()>.json there as each log completes
    bool keep_summaries = false;  // return the summaries (for --compare)
    // After each log: logs done, total, failed so far. Called with a lock held, in
    // completion order (which varies with --jobs; nothing written to the table depends on it).
    std::function<void(std::size_t, std::size_t, std::size_t)> progress;
};

struct BatchResult {
    std::vector<nlohmann::json> rows;       // in item order
    std::vector<nlohmann::json> summaries;  // in item order (null for failed); empty unless kept
    std::size_t failed = 0;
    std::uint64_t samples = 0;              // replayed, over all logs
    // --out summaries that could not be written, in item order ("log: why"); their rows keep
    // the numbers computed.
    std::vector<std::string> unwritten;
    // What the reader said of a log (its summary's input.notes) and what its config_notes say of
    // that log beyond what its config alone makes unreliable (a config for another pack than
    // the log's, a count past the capacity), "log: note", in item order.
    std::vector<std::string> log_notes;
    // Earlier runs' --out summaries of logs that failed this run, removed (so they cannot read
    // as this run's): "log: what", in item order. Said, since an operator rerunning a fleet
    // had lost a flight's only summary without a word.
    std::vector<std::string> removed;
};

// Replays `items` on a pool of `jobs` threads. A log that fails becomes an error row
// with the reason; the others go on. Never throws for a bad log; throws
// std::runtime_error only if --out cannot be created.
BatchResult run_batch(const std::vector<BatchItem>& items, const BatchRunOptions& options);

// A one-line progress bar ("[#####.....]  12/140 logs, 1 failed"), `width` cells wide.
std::string progress_line(std::size_t done, std::size_t total, std::size_t failed, int width = 30);

// The table row for a replayed log, and for one that failed.
nlohmann::json make_row(const BatchItem& item, const nlohmann::json& summary);
nlohmann::json make_error_row(const BatchItem& item, const std::string& reason);

// --compare: each replayed summary against GOLDEN_DIR/<summary_stem()>.json.
struct GoldenComparison {
    std::vector<std::string> lines;  // one per difference or problem, in item order
    std::size_t compared = 0;        // summaries that had a golden
    std::size_t changed = 0;         // of those, summaries with a difference
    std::size_t missing = 0;         // summaries without a golden file
    std::size_t failed = 0;          // items that produced no summary
    bool ok() const { return changed == 0 && missing == 0 && failed == 0; }
};
// Fields always ignored: /input/path (where the log sat on the machine that made the
// golden) and /battsim_version (a release alone is not a regression).
CompareOptions golden_compare_options(double relative_tolerance, double absolute_tolerance = 1e-9);
GoldenComparison compare_to_goldens(const std::vector<BatchItem>& items, const std::vector<nlohmann::json>& summaries,
                                    const std::string& golden_dir, const CompareOptions& options);

}  // namespace host
}  // namespace battsim
