// Turning batch arguments (files, directories, glob patterns) into one ordered list of
// logs, and picking a deterministic shard of that list. The order is a function of the
// arguments and the file names only, so every run, shard and machine sees the same list.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace battsim {
namespace host {

struct ExpandedPath {
    std::string path;
    std::string argument;  // what it came from (a file, directory or pattern)
    std::string error;     // non-empty: the argument yielded no file (then path == argument)
};

// In argument order; a directory gives its regular, non-hidden files (not recursive), a
// pattern (*, ?, [ and no such file) its matches; both sorted by natural_less. A directory
// or a pattern leaves out battsim's own outputs: .json and .md files (summaries, tables,
// truth), which no log format is, and the files in `outputs` (the command's -o, --packs,
// --monitors), so a nightly run writing into its log directory reads the same logs the
// second night. An argument that yields nothing gives one entry with `error` set, so it
// shows up as a failed row instead of vanishing. A file met twice, by any name
// (log_file_key), throws std::invalid_argument naming both: listed twice, a log would
// count twice in the per-pack and per-monitor tables.
std::vector<ExpandedPath> expand_inputs(const std::vector<std::string>& arguments,
                                        const std::vector<std::string>& outputs = {});

// Equal for two names of one file: an existing file by device and inode (symlinks and hard
// links included), another by its path made canonical (std::filesystem::weakly_canonical).
std::string log_file_key(const std::string& path);

// Why `again` is refused: it names the same log as `first` (listed `where`, e.g. "on line 2",
// or "" to say nothing more); each named as given, with the argument it came from.
std::string listed_twice(const ExpandedPath& again, const ExpandedPath& first, const std::string& where = "");

// Digit runs compare as numbers ("9.csv" < "10.csv"), everything else by bytes; no
// locale. Ties such as "01"/"1" fall back to byte order, so the order is total.
bool natural_less(const std::string& a, const std::string& b);

// Whether `s` holds glob metacharacters.
bool is_glob_pattern(const std::string& s);

// `--shard K/N`: K in 1..N. count == 0 = no sharding.
struct ShardSpec {
    std::size_t index = 0;
    std::size_t count = 0;
    bool active() const { return count > 0; }
    // Input i (0-based, in the full list's order) belongs to shard K when i mod N == K − 1:
    // shards are interleaved, so long and short logs spread evenly, and the choice needs
    // only the list itself.
    bool contains(std::size_t i) const { return count == 0 || i % count == index - 1; }
};
// Throws std::invalid_argument with a message naming what was expected.
ShardSpec parse_shard(const std::string& text);
std::string to_string(const ShardSpec& s);  // "K/N", or "" when inactive

// File name without its last extension ("a/b/30.csv" → "30"): names per-log summaries
// and golden files.
std::string path_stem(const std::string& path);

// Replaces ${NAME} and ${NAME:-default} with the environment's value (the default when
// NAME is unset or empty). A relative value leading the text is made absolute against the
// working directory. Throws std::invalid_argument for an unset variable without a default
// or an unclosed ${.
std::string expand_variables(const std::string& text);

}  // namespace host
}  // namespace battsim
