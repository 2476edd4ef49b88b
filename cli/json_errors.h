// With --json a program reads standard output; a failed run had printed nothing there, its
// reason on standard error alone. So a run asked for JSON that fails without writing to
// standard output writes one object there instead (schema battsim.error), holding the exit
// code and what went to standard error; the text on standard error is unchanged. batch's and
// merge's exit 1 is a finding, not a failure: their table, which may be a file, holds the
// rows that failed.
// Header-only so the unit tests check the pieces without running the binary.
#pragma once
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <mutex>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "exit_codes.h"

namespace battsim {
namespace cli {

// Passes everything to `target`, counting it and keeping the last `keep` bytes or so (a
// failure's reason comes last, after the notes). Locked: batch's workers write notes from
// several threads.
class RecordingBuf : public std::streambuf {
public:
    RecordingBuf(std::streambuf* target, size_t keep) : target_(target), keep_(keep) {}
    size_t bytes() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return bytes_;
    }
    // What was kept; when more was said, it starts after the first line break kept.
    std::string text() const {
        std::lock_guard<std::mutex> lock(mutex_);
        if (text_.size() <= keep_ && bytes_ == text_.size()) return text_;
        std::string tail = text_.substr(text_.size() > keep_ ? text_.size() - keep_ : 0);
        const size_t line = tail.find('\n');
        return line == std::string::npos ? std::string() : tail.substr(line + 1);
    }
    bool truncated() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return bytes_ > text_.size() || text_.size() > keep_;
    }

protected:
    int overflow(int c) override {
        if (c == traits_type::eof()) return traits_type::not_eof(c);
        const char ch = static_cast<char>(c);
        return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
    }
    std::streamsize xsputn(const char* s, std::streamsize n) override {
        std::lock_guard<std::mutex> lock(mutex_);
        const std::streamsize written = target_->sputn(s, n);
        if (written > 0) {
            bytes_ += static_cast<size_t>(written);
            if (keep_ > 0) {
                text_.append(s, static_cast<size_t>(written));
                if (text_.size() > 2 * keep_) text_.erase(0, text_.size() - keep_);  // amortised
            }
        }
        return written;
    }
    int sync() override {
        std::lock_guard<std::mutex> lock(mutex_);
        return target_->pubsync();
    }

private:
    std::streambuf* target_;
    size_t keep_;
    mutable std::mutex mutex_;
    size_t bytes_ = 0;
    std::string text_;
};

// batch and merge print a table whose exit 1 is a finding, and take --format json.
inline bool table_command(const std::string& command) { return command == "batch" || command == "merge"; }

// The command: the first word that is not an option ("" for none).
inline std::string command_word(const std::vector<std::string>& args) {
    for (size_t i = 1; i < args.size(); ++i) {
        if (args[i] == "--") break;
        if (!args[i].empty() && args[i][0] != '-') return args[i];
    }
    return std::string();
}

// True when the command line asks for JSON on standard output: --json, or batch's and
// merge's --format json (before a "--", after which every word is an argument).
inline bool json_requested(const std::vector<std::string>& args) {
    const std::string command = command_word(args);
    const bool batch = table_command(command);
    for (size_t i = 1; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--") return false;
        if (a == "--json") return true;
        if (batch && ((a == "--format" && i + 1 < args.size() && args[i + 1] == "json") || a == "--format=json")) return true;
    }
    return false;
}

inline bool writes_error_object(const std::string& command, int exit_code, size_t stdout_bytes) {
    const bool finding = exit_code == kExitFailure && table_command(command);
    return exit_code != kExitOk && !finding && stdout_bytes == 0;
}

// One line as a terminal would show it: what follows the last carriage return (a progress
// bar redraws itself with them), without escape sequences.
inline std::string shown_line(const std::string& raw) {
    const size_t cr = raw.rfind('\r');
    const std::string line = cr == std::string::npos ? raw : raw.substr(cr + 1);
    std::string out;
    for (size_t i = 0; i < line.size(); ++i) {
        if (line[i] == '\033' && i + 1 < line.size() && line[i + 1] == '[') {
            i += 2;
            while (i < line.size() && !std::isalpha(static_cast<unsigned char>(line[i]))) ++i;
            continue;
        }
        out += line[i];
    }
    return out;
}

// The object written for a failed run. `message` is the reason: the last line battsim itself
// wrote ("battsim CMD: ...") that is not a note, else the last line; `stderr` every line
// kept (non-empty, as a terminal shows it), `stderr_truncated` when more was said than kept.
// `command` is the one the message names, else the command line's; null when neither has one.
// Print it with dump_error_json: a file's name in a message may not be UTF-8.
inline nlohmann::json error_json(const std::string& command, int exit_code, const std::string& stderr_text,
                                 const std::string& version, bool stderr_truncated = false) {
    nlohmann::json lines = nlohmann::json::array();
    std::istringstream in(stderr_text);
    std::string message, named;
    for (std::string raw; std::getline(in, raw);) {
        const std::string line = shown_line(raw);
        if (line.empty()) continue;
        lines.push_back(line);
        const size_t colon = line.find(": ");
        if (line.rfind("battsim", 0) == 0 && colon != std::string::npos && line.find(": note: ") == std::string::npos) {
            message = line;
            named = line.compare(0, 8, "battsim ") == 0 ? line.substr(8, colon - 8) : std::string();
        }
    }
    if (message.empty() && !lines.empty()) message = lines.back().get<std::string>();
    const std::string who = !named.empty() ? named : command;
    return {{"schema", "battsim.error"},
            {"schema_version", 1},
            {"battsim_version", version},
            {"command", who.empty() ? nlohmann::json(nullptr) : nlohmann::json(who)},
            {"exit_code", exit_code},
            {"message", message},
            {"stderr", lines},
            {"stderr_truncated", stderr_truncated}};
}

// Bytes that are not UTF-8 (a Latin-1 file name) become U+FFFD rather than an exception.
inline std::string dump_error_json(const nlohmann::json& j) {
    return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace cli
}  // namespace battsim
