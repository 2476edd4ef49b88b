#include "host/batch/batch.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <new>
#include <optional>
#include <thread>

#include "host/batch/table.h"
#include "host/config_json.h"
#include "host/io/atomic_file.h"
#include "host/io/json_text.h"
#include "host/report/charger_check.h"

namespace battsim {
namespace host {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Key under which a manifest entry and a command-line path are recognised as the same
// file, whichever way each spells it.
std::string file_key(const std::string& path) {
    std::error_code ec;
    const fs::path c = fs::weakly_canonical(path, ec);
    return ec ? fs::path(path).lexically_normal().string() : c.string();
}

struct Planned {
    ExpandedPath input;
    LogSettings settings;
    std::string config_named_at;  // "m.csv:2" where the manifest row names its config; "" otherwise
};

}  // namespace

std::vector<BatchItem> plan_batch(const BatchPlanRequest& request) {
    std::optional<Manifest> manifest;
    if (!request.manifest.empty()) manifest = load_manifest(request.manifest);

    // Each manifest entry expanded (directories, patterns) with its layered settings.
    std::vector<Planned> from_manifest;
    if (manifest) {
        // Where each file was first listed: a log listed twice would count twice in its
        // pack's and its monitor's rows, and which entry's settings hold would be a guess.
        std::map<std::string, std::pair<const ManifestEntry*, ExpandedPath>> listed;
        const auto place = [](const ManifestEntry& e) {
            return "line " + std::to_string(e.line) + (e.column > 0 ? ", column " + std::to_string(e.column) : "");
        };
        for (const ManifestEntry& e : manifest->logs) {
            std::vector<ExpandedPath> files;
            try {
                files = expand_inputs({e.path}, request.outputs);
            } catch (const std::invalid_argument& why) {
                throw InputError(manifest->path, e.line, e.column, why.what());
            }
            for (const ExpandedPath& f : files) {
                if (!f.error.empty()) continue;
                const auto [it, fresh] = listed.emplace(log_file_key(f.path), std::make_pair(&e, f));
                if (!fresh)
                    throw InputError(manifest->path, e.line, e.column,
                                     listed_twice(f, it->second.second, "on " + place(*it->second.first)));
            }
            if (e.settings.charged_mah && files.size() != 1) {
                throw InputError(manifest->path, e.line, e.column,
                                 "\"charged_mah\" is the charger's count after one log, but \"" + e.path + "\" names " +
                                     std::to_string(files.size()) + " files; list the file");
            }
            if (e.settings.test && files.size() > 1) {
                throw InputError(manifest->path, e.line, e.column,
                                 "\"test\" labels one log, but \"" + e.path + "\" names " + std::to_string(files.size()) +
                                     " files; drop the label (each row is then named after its file) or list the files");
            }
            LogSettings s = manifest->defaults;
            s.overlay(e.settings);
            // A config that cannot be read fails its rows: each says which manifest row named it.
            const std::string named_at = e.settings.config ? manifest->path + ":" + std::to_string(e.line) +
                                                                  (e.column > 0 ? ":" + std::to_string(e.column) : std::string())
                                                : std::string();
            for (ExpandedPath f : files) {
                // "pattern matches no file" alone did not say which of the manifest's lines.
                if (!f.error.empty())
                    f.error += " (" + manifest->path + ":" + std::to_string(e.line) +
                               (e.column > 0 ? ":" + std::to_string(e.column) : std::string()) + ")";
                from_manifest.push_back({f, s, named_at});
            }
        }
    }

    std::vector<Planned> planned;
    if (manifest && request.paths.empty()) {
        planned = from_manifest;
    } else {
        std::map<std::string, const Planned*> by_file;
        for (const Planned& p : from_manifest) {
            if (p.input.error.empty()) by_file.emplace(file_key(p.input.path), &p);
        }
        for (const ExpandedPath& f : expand_inputs(request.paths, request.outputs)) {
            Planned p{f, manifest ? manifest->defaults : LogSettings(), std::string()};
            auto it = by_file.find(file_key(f.path));
            if (it != by_file.end()) {
                p.settings = it->second->settings;
                p.config_named_at = it->second->config_named_at;
            }
            planned.push_back(p);
        }
    }

    std::map<std::string, LoadedConfig> configs;  // each config file read once
    std::map<std::string, std::string> bad_configs;  // and each that failed, with why
    std::vector<BatchItem> items;
    items.reserve(planned.size());
    std::vector<bool> labelled;  // the row's label given, not the stem
    for (Planned& p : planned) {
        p.settings.overlay(request.command_line);
        BatchItem item;
        item.index = items.size();
        item.path = p.input.path;
        item.stem = path_stem(p.input.path);
        item.error = p.input.error;
        item.test = p.settings.test ? *p.settings.test : (item.error.empty() ? item.stem : p.input.path);
        item.pack = p.settings.pack ? *p.settings.pack : std::string();
        item.monitor = p.settings.monitor ? *p.settings.monitor : std::string();
        item.charged_mah = p.settings.charged_mah ? *p.settings.charged_mah : 0.0;
        item.replay.reader = p.settings.reader_options();
        item.config_path = p.settings.config ? *p.settings.config : std::string();
        if (p.settings.config) {
            const std::string& path = *p.settings.config;
            auto it = configs.find(path);
            if (it == configs.end() && !bad_configs.count(path)) {
                try {
                    it = configs.emplace(path, load_config_file(path)).first;
                } catch (const ConfigError& e) {
                    // The command line's config is one mistake for the whole run; a manifest's
                    // is its logs' rows' failure, and the rest of the fleet still runs.
                    if (request.command_line.config) throw;
                    bad_configs.emplace(path, std::string("config: ") + e.what());
                }
            }
            if (it != configs.end()) {
                item.replay.config = it->second;
            } else {
                item.replay.config = default_config();
                item.replay.config.name = path;  // the row names the config it could not read
                if (item.error.empty())
                    item.error = bad_configs[path] + (p.config_named_at.empty() || request.command_line.config
                                                          ? std::string()
                                                          : " (named on " + p.config_named_at + ")");
            }
        } else {
            item.replay.config = builtin_config();  // as replay with no -c
        }
        if (p.settings.estimator) item.replay.config.monitor.estimator = *p.settings.estimator;
        labelled.push_back(p.settings.test.has_value());
        items.push_back(std::move(item));
    }
    assign_summary_names(items);
    // Logs of one stem (every card's 00000001.BIN) are labelled as their summaries are named:
    // two rows had both read "00000001" in the Markdown table.
    for (size_t k = 0; k < items.size(); ++k)
        if (!labelled[k] && items[k].error.empty() && items[k].summary_stem() != items[k].stem)
            items[k].test = items[k].summary_stem();
    return items;
}

void assign_summary_names(std::vector<BatchItem>& items) {
    std::map<std::string, std::vector<size_t>> by_stem;
    for (size_t k = 0; k < items.size(); ++k) by_stem[items[k].stem].push_back(k);
    for (const auto& group : by_stem) {
        if (group.second.size() < 2) {
            items[group.second[0]].summary_name = items[group.second[0]].stem;
            continue;
        }
        // Absolute and lexically normal, symlinks not followed: the names read as the paths were
        // given, and a fleet copied elsewhere keeps them (only what lies below the common part counts).
        std::vector<fs::path> paths;
        for (size_t k : group.second) {
            std::error_code ec;
            const fs::path abs = fs::absolute(items[k].path, ec);
            paths.push_back((ec ? fs::path(items[k].path) : abs).lexically_normal());
        }
        fs::path common = paths[0].parent_path();
        for (const fs::path& p : paths) {
            fs::path shared;
            const fs::path dir = p.parent_path();
            for (auto a = common.begin(), b = dir.begin(); a != common.end() && b != dir.end() && *a == *b; ++a, ++b)
                shared /= *a;
            common = shared;
        }
        for (size_t i = 0; i < group.second.size(); ++i) {
            std::string rel = paths[i].lexically_relative(common).generic_string();
            if (rel.empty() || rel == ".") rel = paths[i].filename().string();
            std::string name;
            for (char c : rel) name += c == '/' ? std::string("__") : std::string(1, c);
            items[group.second[i]].summary_name = name;
        }
    }
}

std::string inputs_digest(const std::vector<BatchItem>& items) {
    uint64_t h = 1469598103934665603ull;
    auto mix = [&h](const std::string& s) {
        for (unsigned char c : s) {
            h ^= c;
            h *= 1099511628211ull;
        }
        h ^= 0xff;  // field separator that no text contains
        h *= 1099511628211ull;
    };
    mix(std::to_string(items.size()));
    for (const BatchItem& it : items) {
        // The path as given or resolved from the manifest as given: shards on nodes that
        // mount the fleet elsewhere agree when run with the same relative paths (no form of
        // the path serves every case: an absolute one differs between nodes, one relative
        // to the manifest differs with the mount of data outside it).
        mix(it.path);
        mix(it.test);
        mix(it.pack);
        mix(it.replay.config.name);
        mix(to_string(it.replay.config.monitor.estimator));
        if (it.charged_mah > 0) mix("charged " + std::to_string(it.charged_mah));  // lists without it keep their digest
        if (!it.monitor.empty()) mix("monitor " + it.monitor);                       // likewise
        // What the log was read and replayed with: a shard rerun after a config was edited
        // under the same name (replay --config-out writes a gain into it), or with another
        // --average-ms, gives other numbers and must not merge with the rest.
        mix(json_text(config_to_json(it.replay.config), -1));
        const ReaderOptions& r = it.replay.reader;
        const ColumnMapping& c = r.columns;
        char numbers[160];
        std::snprintf(numbers, sizeof numbers, "%d %d %.17g %.17g %d %llu", static_cast<int>(r.format),
                      static_cast<int>(r.current_source), c.time_scale_to_s, c.current_scale_to_a,
                      c.current_negative_is_discharge ? 1 : 0, static_cast<unsigned long long>(r.average_us));
        mix(numbers);
        mix(c.time);
        mix(c.voltage);
        mix(c.current);
        mix(c.temperature);
        mix(std::to_string(c.cells.size()));
        for (const std::string& cell : c.cells) mix(cell);
        if (r.ignore_temperature) mix("no temperature");  // lists without it keep their digest
    }
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

std::vector<std::string> duplicate_summary_names(const std::vector<BatchItem>& items) {
    // Every item, failed ones too: a failed log's run removes an earlier run's summary of that name.
    std::map<std::string, std::vector<std::string>> by_name;
    std::vector<std::string> order;
    for (const BatchItem& it : items) {
        auto& v = by_name[it.summary_stem()];
        if (v.empty()) order.push_back(it.summary_stem());
        v.push_back(it.path);
    }
    std::vector<std::string> out;
    for (const std::string& name : order) {
        const auto& v = by_name[name];
        if (v.size() < 2) continue;
        std::string line = name + ":";
        for (size_t i = 0; i < v.size(); ++i) line += (i ? ", " : " ") + v[i];
        out.push_back(line);
    }
    return out;
}

std::vector<CountedNote> count_config_notes(const std::vector<BatchItem>& items) {
    std::map<std::string, std::size_t> noted;
    for (const BatchItem& it : items) {
        if (!it.error.empty()) continue;
        for (const std::string& note : config_notes(it.replay.config.monitor))
            ++noted["config " + it.replay.config.name + ": " + note];
    }
    std::vector<CountedNote> counted;
    for (const auto& [note, logs] : noted) counted.push_back({note, logs});
    return counted;
}

std::string counted_note_text(const CountedNote& n) {
    return "note (" + std::to_string(n.logs) + (n.logs == 1 ? " log" : " logs") + "), " + n.note;
}

std::vector<std::string> renamed_summaries(const std::vector<BatchItem>& items) {
    std::vector<std::string> out;
    for (const BatchItem& it : items)
        if (it.summary_stem() != it.stem) out.push_back(it.path + ": " + it.summary_stem() + ".json");
    return out;
}

std::string progress_line(size_t done, size_t total, size_t failed, int width) {
    const size_t filled = total ? done * static_cast<size_t>(width) / total : static_cast<size_t>(width);
    std::string bar = "[" + std::string(filled, '#') + std::string(static_cast<size_t>(width) - filled, '.') + "] ";
    bar += std::to_string(done) + "/" + std::to_string(total) + " logs";
    if (failed) bar += ", " + std::to_string(failed) + " failed";
    return bar;
}

// What a row says of its log whether it replayed or not: which log, pack, monitor, config
// and estimator.
static json row_of(const BatchItem& item) {
    json row;
    row["index"] = item.index;
    row["test"] = item.test;
    row["log"] = item.path;
    row["pack"] = item.pack.empty() ? json(nullptr) : json(item.pack);
    row["monitor"] = item.monitor.empty() ? json(nullptr) : json(item.monitor);
    row["config"] = item.replay.config.name;
    row["estimator"] = to_string(item.replay.config.monitor.estimator);
    return row;
}

json make_row(const BatchItem& item, const json& summary) {
    json row = row_of(item);
    // The summary's own say, where it has one.
    row["config"] = summary.value("config", row["config"].get<std::string>());
    row["estimator"] = summary.value("estimator", row["estimator"].get<std::string>());
    // A log the config kept wholly out replays without an error and reads null everywhere: its
    // row fails (with the reason) and keeps what the summary says, so a pipeline need not
    // compare sensor_fault_samples with samples itself.
    const std::string no_valid = no_valid_samples_text(summary);
    row["status"] = no_valid.empty() ? kRowOk : kRowNoValidSamples;
    row["error"] = no_valid.empty() ? json(nullptr) : json(no_valid);
    // Missing members give null rather than an exception: a summary without a flight
    // (or from an older schema) still makes a row.
    auto pick = [&summary](const char* pointer) -> json {
        const json::json_pointer p(pointer);
        return summary.contains(p) ? summary.at(p) : json(nullptr);
    };
    const bool flew = pick("/flight").is_object();
    row["flight"] = flew;
    row["flight_duration_s"] = pick("/flight/duration_s");
    row["capacity_mean_ah"] = pick("/flight/capacity_ah/mean");
    row["capacity_first20_ah"] = pick("/flight/capacity_ah/first20_mean");
    row["capacity_final_ah"] = pick("/flight/capacity_ah/final");
    row["capacity_final_sigma_ah"] = pick("/flight/capacity_ah/final_sigma");
    row["capacity_after_rest_ah"] = pick("/flight/capacity_ah/after_rest");
    row["charger_ratio"] = pick("/charger_check/ratio");
    row["charger_fault"] = pick("/charger_check/fault");
    row["charger_current_gain"] = pick("/charger_check/current_gain");
    row["charger_suggested_gain"] = pick("/charger_check/suggested_current_gain");
    row["error_mean_v"] = pick("/flight/voltage_error_v/model/mean");
    row["abs_error_mean_v"] = pick("/flight/voltage_error_v/model/mean_abs");
    row["resistance_mean_ohm"] = pick("/flight/resistance_ohm/mean");
    row["resistance_first20_ohm"] = pick("/flight/resistance_ohm/first20_mean");
    row["resistance_final_ohm"] = pick("/flight/resistance_ohm/final");
    const json scores = pick("/flight/cell_scores");
    row["cell_scores"] = scores.is_array() ? scores : json::array();
    row["remaining_at20_s"] = pick("/flight/remaining_time_s/at20");
    json warnings = json::array();
    json fault_cause = json::array();
    const json raised = pick("/warnings");
    json outlier_cell;  // 1-based, null without a cell warning
    if (raised.is_array()) {
        for (const json& w : raised) {
            warnings.push_back(w.is_object() ? w.value("name", std::string("?")) : std::string("?"));
            if (w.is_object() && w.value("name", std::string()) == "cell_outlier") outlier_cell = w.value("cell", json());
            if (w.is_object() && w.value("name", std::string()) == "sensor_fault") fault_cause = w.value("cause", json::array());
        }
    }
    row["warnings"] = warnings;
    row["outlier_cell"] = outlier_cell;
    row["sensor_fault_cause"] = fault_cause;
    const json total = pick("/samples/total");
    row["samples"] = total.is_number_unsigned() ? total.get<uint64_t>() : 0;
    const json faults = pick("/sensor_fault_samples");
    row["sensor_fault_samples"] = faults.is_number_unsigned() ? faults.get<uint64_t>() : 0;
    // The notes themselves, the reader's then the config's: a count had told a truncated log
    // from a config without an OCV table only through --out's summaries.
    json notes = json::array();
    // Then the charger check's: a typo'd charged_mah (1.5 for 1500) had been said only in --out's summary.
    for (const char* pointer : {"/input/notes", "/config_notes", "/charger_check/notes"}) {
        const json list = pick(pointer);
        if (list.is_array())
            for (const json& note : list)
                if (note.is_string())
                    notes.push_back(std::string(pointer) == "/charger_check/notes" ? "charger check: " + note.get<std::string>()
                                                                                 : note.get<std::string>());
    }
    row["notes"] = notes;
    return row;
}

json make_error_row(const BatchItem& item, const std::string& reason) {
    json row = row_of(item);
    row["status"] = kRowError;
    row["error"] = reason;
    row["flight"] = false;
    for (const char* k : {"flight_duration_s", "capacity_mean_ah", "capacity_first20_ah", "capacity_final_ah",
                          "capacity_final_sigma_ah", "capacity_after_rest_ah", "charger_ratio", "charger_fault", "charger_current_gain",
                          "charger_suggested_gain", "error_mean_v",
                          "abs_error_mean_v", "resistance_mean_ohm", "resistance_first20_ohm", "resistance_final_ohm",
                          "remaining_at20_s"})
        row[k] = nullptr;
    row["cell_scores"] = json::array();
    row["warnings"] = json::array();
    row["samples"] = 0;
    row["sensor_fault_samples"] = 0;
    row["sensor_fault_cause"] = json::array();
    row["notes"] = json::array();
    row["outlier_cell"] = nullptr;
    return row;
}

BatchResult run_batch(const std::vector<BatchItem>& items, const BatchRunOptions& options) {
    const size_t n = items.size();
    BatchResult result;
    result.rows.assign(n, json());
    if (options.keep_summaries) result.summaries.assign(n, json());
    if (!options.out_dir.empty()) {
        std::error_code ec;
        fs::create_directories(options.out_dir, ec);
        if (ec || !fs::is_directory(options.out_dir))
            throw std::runtime_error(options.out_dir + ": cannot create the summary directory (" + ec.message() + ")");
    }

    std::vector<std::string> unwritten(n);
    std::vector<std::vector<std::string>> log_notes(n);
    std::vector<std::string> removed(n);
    std::atomic<size_t> next{0};
    std::mutex lock;
    size_t done = 0;
    // A log with no summary this run: an earlier run's summary of it would read as this run's.
    auto forget_old_summary = [&](size_t k) {
        const fs::path old_summary = fs::path(options.out_dir) / (items[k].summary_stem() + ".json");
        std::error_code ec;
        if (fs::remove(old_summary, ec))
            removed[k] = items[k].path + ": an earlier run's summary " + old_summary.string() +
                         " was removed: the log failed this run, and that summary would read as this run's";
        else if (ec && ec != std::errc::no_such_file_or_directory)
            unwritten[k] = items[k].path + ": an earlier run's summary " + old_summary.string() + " could not be removed (" +
                           ec.message() + "); it is not this run's";
    };
    auto work = [&]() {
        for (size_t k = next++; k < n; k = next++) {
            const BatchItem& item = items[k];
            json row, summary;
            uint64_t samples = 0;
            if (!item.error.empty()) {
                row = make_error_row(item, item.error);
                if (!options.out_dir.empty()) forget_old_summary(k);
            } else {
                try {
                    summary = replay_log(item.path, item.replay);
                    std::string check_error;
                    // Without a valid sample there is no charge to check: the row says why.
                    if (item.charged_mah > 0 && no_valid_samples_text(summary).empty()) {
                        try {
                            add_charger_check(summary, item.charged_mah, ChargerCheckOptions().tolerance,
                                              item.replay.config.monitor);
                        } catch (const std::invalid_argument& e) {
                            check_error = std::string("charger check: ") + e.what();
                        }
                    }
                    // A check that cannot be made fails the row; the replay's summary is kept.
                    row = check_error.empty() ? make_row(item, summary) : make_error_row(item, check_error);
                    samples = check_error.empty() ? row["samples"].get<uint64_t>() : 0;
                    // The notes the log gave rise to, as replay says them: the reader's, then the
                    // config's of this log (those of the config alone are said once per config).
                    const std::vector<std::string> config_wide = config_notes(item.replay.config.monitor);
                    for (const json& note : summary["input"].value("notes", json::array()))
                        log_notes[k].push_back(item.path + ": " + note.get<std::string>());
                    for (const json& note : summary.value("config_notes", json::array()))
                        if (std::find(config_wide.begin(), config_wide.end(), note.get<std::string>()) == config_wide.end())
                            log_notes[k].push_back(item.path + ": " + note.get<std::string>());
                    if (summary.contains("charger_check"))
                        for (const json& note : summary["charger_check"].value("notes", json::array()))
                            log_notes[k].push_back(item.path + ": charger check: " + note.get<std::string>());
                } catch (const std::bad_alloc&) {
                    // This log alone; the others may still fit (its what() says only "std::bad_alloc").
                    row = make_error_row(item, "out of memory replaying this log");
                    summary = json();
                } catch (const std::exception& e) {
                    // InputError carries file:line:column; anything else is reported as is.
                    row = make_error_row(item, e.what());
                    summary = json();
                }
                if (summary.is_null() && !options.out_dir.empty()) {
                    forget_old_summary(k);
                } else if (!options.out_dir.empty()) {
                    // Written now, not at the end: a crash later loses nothing done so far.
                    try {
                        write_file_atomic((fs::path(options.out_dir) / (item.summary_stem() + ".json")).string(),
                                          json_text(summary, 2) + "\n");
                    } catch (const std::exception& e) {
                        // The replay's numbers stand; only the file is missing (exit 5).
                        unwritten[k] = item.path + ": summary not written: " + e.what();
                    }
                }
            }
            const bool failed = row["status"] != "ok";
            std::lock_guard<std::mutex> g(lock);
            result.rows[k] = std::move(row);
            result.samples += samples;
            if (options.keep_summaries) result.summaries[k] = std::move(summary);
            if (failed) ++result.failed;
            ++done;
            if (options.progress) options.progress(done, n, result.failed);
        }
    };
    const size_t jobs = std::max<size_t>(1, std::min<size_t>(options.jobs, n));
    if (jobs <= 1) {
        work();
    } else {
        std::vector<std::thread> pool;
        pool.reserve(jobs);
        for (size_t t = 0; t < jobs; ++t) pool.emplace_back(work);
        for (std::thread& t : pool) t.join();
    }
    for (std::string& u : unwritten)
        if (!u.empty()) result.unwritten.push_back(std::move(u));
    for (auto& notes : log_notes)
        for (std::string& note : notes) result.log_notes.push_back(std::move(note));
    for (std::string& r : removed)
        if (!r.empty()) result.removed.push_back(std::move(r));
    return result;
}

CompareOptions golden_compare_options(double relative_tolerance, double absolute_tolerance) {
    CompareOptions o;
    o.relative_tolerance = relative_tolerance;
    o.absolute_tolerance = absolute_tolerance;
    o.ignore = {"/input/path", "/battsim_version"};
    return o;
}

GoldenComparison compare_to_goldens(const std::vector<BatchItem>& items, const std::vector<json>& summaries,
                                    const std::string& golden_dir, const CompareOptions& options) {
    GoldenComparison c;
    for (size_t k = 0; k < items.size(); ++k) {
        const BatchItem& item = items[k];
        const std::string golden = (fs::path(golden_dir) / (item.summary_stem() + ".json")).string();
        if (k >= summaries.size() || summaries[k].is_null()) {
            ++c.failed;
            c.lines.push_back(item.path + ": not compared, the replay failed");
            continue;
        }
        std::error_code ec;
        if (!fs::is_regular_file(golden, ec)) {
            ++c.missing;
            c.lines.push_back(item.path + ": no golden summary " + golden);
            continue;
        }
        // An unreadable golden counts as compared and changed, so "changed" never exceeds
        // "compared".
        ++c.compared;
        json expected;
        try {
            std::ifstream in(golden, std::ios::binary);
            expected = json::parse(in);
        } catch (const std::exception& e) {
            ++c.changed;
            c.lines.push_back(golden + ": not valid JSON (" + std::string(e.what()) + ")");
            continue;
        }
        const std::vector<JsonDifference> diffs = compare_json(expected, summaries[k], options);
        if (diffs.empty()) continue;
        ++c.changed;
        for (const JsonDifference& d : diffs)
            c.lines.push_back(golden + ": " + d.path + ": golden " + d.expected + ", now " + d.actual);
    }
    return c;
}

}  // namespace host
}  // namespace battsim
