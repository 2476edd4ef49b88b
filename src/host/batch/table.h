// The batch table (schema battsim.batch): one row per log in the columns of the
// dissertation's appendix, plus per-pack and per-monitor tables. The JSON form is what `batch --format
// json` writes and `merge` reads; Markdown and CSV are rendered from it, so a merged
// table and a single run's table come out of the same code byte for byte.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/batch/inputs.h"

namespace battsim {
namespace host {

constexpr const char* kBatchSchema = "battsim.batch";
// 2: a row's notes are their text, no longer a count. 3: a row's status may be
// "no_valid_samples"; the version is also written as "schema_version", as in the summaries.
constexpr int kBatchVersion = 3;

// A row's status: replayed; failed before or during the replay (error: why); replayed, but
// the config's sensor limits kept every sample out (error: how many, by which limit). Any
// status but "ok" is a failed log (exit 1, "failed" in the pack and monitor tables).
constexpr const char* kRowOk = "ok";
constexpr const char* kRowError = "error";
constexpr const char* kRowNoValidSamples = "no_valid_samples";

enum class TableFormat { Markdown, Csv, Json };
// "md", "csv", "json"; throws std::invalid_argument.
TableFormat parse_table_format(const std::string& name);

// The table document. `rows` are this run's rows (a shard's only, when sharded) in
// index order; `inputs`/`digest` describe the full list. Unsharded tables also carry
// the per-pack and per-monitor tables.
nlohmann::json make_table(std::vector<nlohmann::json> rows, std::size_t inputs, const std::string& digest,
                          const ShardSpec& shard);

// Per pack, in order of the pack's first row: flights (rows), failed, mean capacity
// and resistance over the pack's flights, and their trend: the least-squares slope
// against the flight's number within the pack (1, 2, … in input order), per flight.
std::vector<nlohmann::json> pack_rows(const std::vector<nlohmann::json>& rows);

// Per monitor (the manifest's `monitor`), in order of its first row: flights, failed, how
// many flights were checked against the charger and flagged, and the gain the checks that
// suggest one ask for, pooled as their median (with their spread, the gain in use, the
// count over the charger's at that gain, and a fault beyond `tolerance`).
std::vector<nlohmann::json> monitor_rows(const std::vector<nlohmann::json>& rows, double tolerance);

// Least-squares slope of y over x; NaN with fewer than two distinct x.
double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y);

// The log table (Markdown: followed by the pack table when there is one).
std::string render_table(const nlohmann::json& table, TableFormat format);
// The pack table alone.
std::string render_packs(const nlohmann::json& table, TableFormat format);
// The monitor table alone.
std::string render_monitors(const nlohmann::json& table, TableFormat format);

std::size_t failed_rows(const nlohmann::json& table);
// A failed row as one line, "log: why": the log named unless its reader's message already
// starts with it.
std::string failed_row_text(const nlohmann::json& row);

// Reads and checks a table written by `batch --format json`. Throws InputError.
nlohmann::json read_table_file(const std::string& path);
// Joins shard tables (in any order) into the table one unsharded run would have
// written. Every shard must come from the same input list (same digest and count), and
// together they must hold each input exactly once. Throws InputError naming the file.
nlohmann::json merge_tables(const std::vector<nlohmann::json>& tables, const std::vector<std::string>& origins);

}  // namespace host
}  // namespace battsim
