// Positions in a JSON document parsed whole (configs, scenarios, manifests, tables):
// nlohmann::json keeps no source positions, so error messages that name a "$.a.b[3]"
// path get their line and column from a second, light walk over the text.
#pragma once
#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

namespace battsim {
namespace host {

// Where each value (and each member's key) of an already parsed JSON text starts, keyed
// by the "$.a.b[3]" paths the messages use.
class JsonLocator {
public:
    explicit JsonLocator(const std::string& text);
    // Byte offset of the value at `path`; its nearest located ancestor's when the path is
    // not in the text; 0 (the document's start) when nothing is.
    std::size_t offset(const std::string& path) const;
    // Byte offset of the key of member `path`; its value's offset when it has no key.
    std::size_t key_offset(const std::string& path) const;
    // 1-based line and column of offset() / key_offset().
    std::pair<long, long> location(const std::string& path) const;
    std::pair<long, long> key_location(const std::string& path) const;

    // The first member whose key its object already had ("$.a.b" of the second one), and
    // where that second key starts; empty when every key is unique. nlohmann::json keeps
    // the last value silently, so a pasted-twice key would change the numbers unseen.
    const std::string& duplicate_key() const { return duplicate_; }
    std::size_t duplicate_offset() const { return duplicate_at_; }

private:
    void skip_ws();
    std::string string_token();
    void value(const std::string& path, int depth);
    void skip_nested();

    static constexpr int kMaxDepth = 32;  // deeper values are located at their ancestor

    const std::string& t_;
    std::size_t p_ = 0;
    std::map<std::string, std::size_t> offsets_;
    std::map<std::string, std::size_t> keys_;
    std::string duplicate_;
    std::size_t duplicate_at_ = 0;
};

// A bad value in a JSON document: "origin[:line:column]: $.a.b: detail". Readers that
// see only the parsed value throw it with the path; whoever holds the text adds the line
// and column with located().
class JsonValueError : public std::runtime_error {
public:
    explicit JsonValueError(const std::string& message) : std::runtime_error(message) {}
    // `at_key`: the error is the member's name (an unknown key), so point at the key.
    JsonValueError(const std::string& origin, const std::string& where, const std::string& detail, bool at_key = false,
                   long line = 0, long column = 0);
    bool has_path() const { return !where_.empty(); }
    const std::string& origin() const { return origin_; }
    const std::string& where() const { return where_; }
    const std::string& detail() const { return detail_; }
    bool at_key() const { return at_key_; }
    long line() const { return line_; }
    long column() const { return column_; }

private:
    std::string origin_, where_, detail_;
    bool at_key_ = false;
    long line_ = 0, column_ = 0;
};

// `e` with the line and column of its path in the text `loc` walked; unchanged when it has
// no path or already has a position.
template <typename E>
E located(const E& e, const JsonLocator& loc) {
    if (!e.has_path() || e.line() > 0) return e;
    const std::pair<long, long> lc = e.at_key() ? loc.key_location(e.where()) : loc.location(e.where());
    return E(e.origin(), e.where(), e.detail(), e.at_key(), lc.first, lc.second);
}

// Reads and parses the JSON document at `path` into `text` and the returned value; a read
// error, an empty file or a syntax error (with its line and column) throws E(message).
// `kind` names the document ("config file"), `expected` what an empty one should hold.
template <typename E>
nlohmann::json load_json_document(const std::string& path, const std::string& kind, const std::string& expected,
                                  std::string& text);

// A syntax error's 1-based line and column in `text` and the parser's own words without
// its position, e.g. "syntax error while parsing object - unexpected '}'; expected string literal".
struct JsonSyntaxError {
    long line = 1;
    long column = 1;
    std::string what;
};
JsonSyntaxError json_syntax_error(const std::string& text, const nlohmann::json::parse_error& e);
// Parses a whole document. False, with where and what, when it is not valid JSON: a syntax
// error, or a number beyond a double ("1e999"), which the parser reports without a position
// (the first place the number's text occurs is given).
bool parse_json_text(const std::string& text, nlohmann::json& out, JsonSyntaxError& error);

// The text of a JSON value for output (indent < 0: one line). Bytes that are not UTF-8 (a
// Latin-1 file name from an old camera or a Windows share) are replaced with U+FFFD instead
// of throwing: a summary must not be lost for the name of its log.
std::string json_text(const nlohmann::json& j, int indent = -1);
// `text` with what is not UTF-8 replaced the same way (for a plot's title, which gnuplot
// writes into an SVG as UTF-8).
std::string valid_utf8(const std::string& text);
// A bad value as an error message quotes it: scalars as their text (cut at 60 characters),
// arrays and objects by their size only, so a value nested 100,000 deep is neither printed
// whole nor walked recursively (which overflowed the stack).
std::string json_brief(const nlohmann::json& j);

// Reads a document (config, scenario, manifest, table) whole. Capped, so that a path to a
// device or a runaway file gives a message instead of eating the memory.
enum class TextRead { Ok, Missing, Denied, NameTooLong, CannotOpen, IsDirectory, TooLarge };
constexpr std::size_t kMaxTextFileBytes = 64u * 1024u * 1024u;
TextRead read_text_file(const std::string& path, std::string& text, std::size_t max_bytes = kMaxTextFileBytes);
// "cannot open config file: no such file", "cannot open config file", "cannot open config
// file: it is a directory", "config file is larger than 64 MiB", for `what` = "config file".
std::string text_read_message(TextRead r, const std::string& what);

template <typename E>
nlohmann::json load_json_document(const std::string& path, const std::string& kind, const std::string& expected,
                                  std::string& text) {
    const TextRead r = read_text_file(path, text);
    if (r != TextRead::Ok) throw E(path + ": " + text_read_message(r, kind));
    if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw E(path + ": file is empty; expected " + expected);
    nlohmann::json j;
    JsonSyntaxError se;
    if (!parse_json_text(text, j, se))
        throw E(path + ":" + std::to_string(se.line) + ":" + std::to_string(se.column) + ": " +
                (se.what.rfind("$", 0) == 0 ? "" : "not valid JSON: ") + se.what);
    return j;
}

}  // namespace host
}  // namespace battsim
