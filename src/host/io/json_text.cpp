#include "host/io/json_text.h"

#include <cerrno>
#include <filesystem>
#include <fstream>

#include "host/io/line_reader.h"

namespace battsim {
namespace host {

JsonLocator::JsonLocator(const std::string& text) : t_(text) {
    skip_ws();
    value("$", 0);
}

std::size_t JsonLocator::offset(const std::string& path) const {
    // A path not in the text (a missing member, or below kMaxDepth) is located at its
    // nearest ancestor that is.
    std::string p = path;
    while (!p.empty()) {
        auto it = offsets_.find(p);
        if (it != offsets_.end()) return it->second;
        const std::size_t cut = p.find_last_of(".[");
        if (cut == std::string::npos || cut == 0) break;
        p.erase(cut);
    }
    return 0;
}

std::size_t JsonLocator::key_offset(const std::string& path) const {
    auto it = keys_.find(path);
    return it == keys_.end() ? offset(path) : it->second;
}

std::pair<long, long> JsonLocator::location(const std::string& path) const { return line_column(t_, offset(path)); }

std::pair<long, long> JsonLocator::key_location(const std::string& path) const {
    return line_column(t_, key_offset(path));
}

void JsonLocator::skip_ws() {
    while (p_ < t_.size() && (t_[p_] == ' ' || t_[p_] == '\t' || t_[p_] == '\n' || t_[p_] == '\r')) ++p_;
}

std::string JsonLocator::string_token() {
    std::string s;
    if (p_ >= t_.size() || t_[p_] != '"') return s;
    ++p_;
    while (p_ < t_.size() && t_[p_] != '"') {
        // An escape is kept as written (an escaped n is not the letter n): keys compare as spelt.
        if (t_[p_] == '\\' && p_ + 1 < t_.size()) s += t_[p_++];
        s += t_[p_++];
    }
    ++p_;
    return s;
}

// Every step consumes at least one byte, so text that failed to parse cannot stall the
// walk; below kMaxDepth a value is skipped without recursion or paths, so a deeply nested
// file costs neither stack nor memory.
void JsonLocator::value(const std::string& path, int depth) {
    skip_ws();
    if (p_ >= t_.size()) return;
    offsets_[path] = p_;
    const char c = t_[p_];
    if (depth >= kMaxDepth && (c == '{' || c == '[')) {
        skip_nested();
        return;
    }
    if (c == '{' || c == '[') {
        const char close = c == '{' ? '}' : ']';
        ++p_;
        std::size_t index = 0;
        while (true) {
            skip_ws();
            if (p_ >= t_.size()) return;
            if (t_[p_] == close) {
                ++p_;
                return;
            }
            if (t_[p_] == ',') {
                ++p_;
                continue;
            }
            if (c == '{') {
                const std::size_t key_at = p_;
                const std::string key = string_token();
                // Every object is walked once under its own path, so a key seen again
                // under the same path is the same object's.
                if (!keys_.emplace(path + "." + key, key_at).second && duplicate_.empty()) {
                    duplicate_ = path + "." + key;
                    duplicate_at_ = key_at;
                }
                skip_ws();
                if (p_ < t_.size() && t_[p_] == ':') ++p_;
                value(path + "." + key, depth + 1);
            } else {
                value(path + "[" + std::to_string(index++) + "]", depth + 1);
            }
        }
    }
    if (c == '"') {
        string_token();
        return;
    }
    const std::size_t start = p_;
    while (p_ < t_.size() && std::string(",]} \t\r\n").find(t_[p_]) == std::string::npos) ++p_;
    if (p_ == start) ++p_;  // a stray '}' or ']' in text that does not parse: always move on
}

void JsonLocator::skip_nested() {
    long open = 0;
    while (p_ < t_.size()) {
        const char c = t_[p_];
        if (c == '"') {
            string_token();
            continue;
        }
        ++p_;
        if (c == '{' || c == '[') ++open;
        if ((c == '}' || c == ']') && --open <= 0) return;
    }
}

namespace {
std::string value_error_text(const std::string& origin, const std::string& where, const std::string& detail, long line,
                             long column) {
    std::string s = origin;
    if (line > 0) s += ":" + std::to_string(line) + ":" + std::to_string(column);
    return s + ": " + where + ": " + detail;
}
}  // namespace

JsonValueError::JsonValueError(const std::string& origin, const std::string& where, const std::string& detail,
                               bool at_key, long line, long column)
    : std::runtime_error(value_error_text(origin, where, detail, line, column)),
      origin_(origin), where_(where), detail_(detail), at_key_(at_key), line_(line), column_(column) {}

JsonSyntaxError json_syntax_error(const std::string& text, const nlohmann::json::parse_error& e) {
    JsonSyntaxError out;
    const auto lc = line_column(text, e.byte > 0 ? e.byte - 1 : 0);
    out.line = lc.first;
    out.column = lc.second;
    // nlohmann's text is "[json.exception.parse_error.101] parse error at line 3, column 5:
    // <what>"; the position is given in front already.
    out.what = e.what();
    const std::size_t col_at = out.what.find(", column ");
    const std::size_t colon = col_at == std::string::npos ? out.what.rfind(": ") : out.what.find(": ", col_at);
    if (colon != std::string::npos) out.what = out.what.substr(colon + 2);
    return out;
}

std::string json_text(const nlohmann::json& j, int indent) {
    return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string valid_utf8(const std::string& text) {
    return nlohmann::json::parse(json_text(nlohmann::json(text))).get<std::string>();
}

std::string json_brief(const nlohmann::json& j) {
    if (j.is_array()) return "an array of " + std::to_string(j.size()) + (j.size() == 1 ? " value" : " values");
    if (j.is_object()) return "an object of " + std::to_string(j.size()) + (j.size() == 1 ? " member" : " members");
    std::string s = json_text(j);
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
}

bool parse_json_text(const std::string& text, nlohmann::json& out, JsonSyntaxError& error) {
    // The parser reads a NUL as the end of the input: a document followed by a NUL run had
    // read as whole, and one of NULs alone as "unexpected end of input" at 1:1.
    if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
        const auto lc = line_column(text, nul);
        error.line = lc.first;
        error.column = lc.second;
        error.what = "a NUL byte at byte offset " + std::to_string(nul) +
                     ": a JSON document is text and holds none (a copy cut short by a power loss, or not a text file)";
        return false;
    }
    try {
        out = nlohmann::json::parse(text);
        const JsonLocator where(text);
        if (where.duplicate_key().empty()) return true;
        const auto lc = line_column(text, where.duplicate_offset());
        error.line = lc.first;
        error.column = lc.second;
        error.what = where.duplicate_key() + ": the key is given twice in its object (the last would win unseen)";
        return false;
    } catch (const nlohmann::json::parse_error& e) {
        error = json_syntax_error(text, e);
    } catch (const nlohmann::json::out_of_range& e) {
        // "[json.exception.out_of_range.406] number overflow parsing '3.7e358'": no byte
        // offset, so the number's text is looked up.
        const std::string what = e.what();
        const std::size_t open = what.find('\'');
        const std::size_t close = open == std::string::npos ? open : what.find('\'', open + 1);
        const std::string number = close == std::string::npos ? std::string() : what.substr(open + 1, close - open - 1);
        const std::size_t at = number.empty() ? std::string::npos : text.find(number);
        const auto lc = line_column(text, at == std::string::npos ? 0 : at);
        error.line = lc.first;
        error.column = lc.second;
        error.what = number.empty() ? what : "number " + number + " is beyond a double's range";
    }
    return false;
}

TextRead read_text_file(const std::string& path, std::string& text, std::size_t max_bytes) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return TextRead::IsDirectory;
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        // Said by its cause: a 5,000-character name had read "no such file".
        const int err = errno;
        if (err == EACCES || err == EPERM) return TextRead::Denied;
        if (err == ENAMETOOLONG) return TextRead::NameTooLong;
        return std::filesystem::exists(std::filesystem::symlink_status(path, ec)) ? TextRead::CannotOpen : TextRead::Missing;
    }
    text.clear();
    char block[64 * 1024];
    while (in) {
        in.read(block, sizeof block);
        text.append(block, static_cast<std::size_t>(in.gcount()));
        if (text.size() > max_bytes) return TextRead::TooLarge;
    }
    return in.bad() ? TextRead::CannotOpen : TextRead::Ok;
}

std::string text_read_message(TextRead r, const std::string& what) {
    switch (r) {
        case TextRead::Ok: return "";
        case TextRead::Missing: return "cannot open " + what + ": no such file";
        case TextRead::Denied: return "cannot open " + what + ": permission denied";
        case TextRead::NameTooLong: return "cannot open " + what + ": the path is too long";
        case TextRead::CannotOpen: return "cannot open " + what;
        case TextRead::IsDirectory: return "cannot open " + what + ": it is a directory";
        case TextRead::TooLarge: return what + " is larger than " + std::to_string(kMaxTextFileBytes >> 20) + " MiB";
    }
    return "cannot read " + what;
}

}  // namespace host
}  // namespace battsim
