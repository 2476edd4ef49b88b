// With --json a program reads standard output; a failed run had printed nothing there, its
// reason on standard error alone. So a run asked for JSON that fails (exit 2 and above)
// without writing to standard output writes one object there instead (schema
// battsim.error), holding the exit code and what went to standard error; the text on
// standard error is unchanged. Exit 1 is a finding, not a failure: the job ran and wrote its
// outputs (batch's rows that failed are in its table, which may be a file).
// Header-only so the unit tests check the pieces without running the binary.
#pragma once
#include <algorithm>
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

// Passes everything to `target`, counting it and keeping the first `keep` bytes. Locked:
// batch's workers write notes from several threads.
class RecordingBuf : public std::streambuf {
public:
    RecordingBuf(std::streambuf* target, size_t keep) : target_(target), keep_(keep) {}
    size_t bytes() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return bytes_;
    }
    std::string text() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return text_;
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
            if (text_.size() < keep_) text_.append(s, std::min(static_cast<size_t>(written), keep_ - text_.size()));
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

// True when the command line asks for JSON on standard output: --json, or batch's
// --format json (before a "--", after which every word is an argument).
inline bool json_requested(const std::vector<std::string>& args) {
    const bool batch = args.size() > 1 && args[1] == "batch";
    for (size_t i = 1; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--") return false;
        if (a == "--json") return true;
        if (batch && ((a == "--format" && i + 1 < args.size() && args[i + 1] == "json") || a == "--format=json")) return true;
    }
    return false;
}

inline bool writes_error_object(int exit_code, size_t stdout_bytes) {
    return exit_code != kExitOk && exit_code != kExitFailure && stdout_bytes == 0;
}

// The object written for a failed run: `message` is the last line on standard error that is
// not a note (the reason), `stderr` every line kept (`stderr_truncated` when more was said
// than kept). Print it with dump_error_json: a file's name in a message may not be UTF-8.
inline nlohmann::json error_json(const std::string& command, int exit_code, const std::string& stderr_text,
                                 const std::string& version, bool stderr_truncated = false) {
    nlohmann::json lines = nlohmann::json::array();
    std::istringstream in(stderr_text);
    std::string message;
    for (std::string line; std::getline(in, line);) {
        if (line.empty()) continue;
        lines.push_back(line);
        if (line.find(": note: ") == std::string::npos && line.rfind("(", 0) != 0) message = line;
    }
    if (message.empty() && !lines.empty()) message = lines.back().get<std::string>();
    return {{"schema", "battsim.error"},
            {"schema_version", 1},
            {"battsim_version", version},
            {"command", command},
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
