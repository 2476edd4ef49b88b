// Runs the battsim binary from the outside, as a user or a script would.
#pragma once
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "test_files.h"

namespace clitest {

using Result = testsupport::RunResult;
using testsupport::read_file;
using testsupport::write_file;

// A fresh directory, removed when the test program exits.
inline std::string temp_dir() { return testsupport::scratch_dir("cli"); }

// The first `rows` lines of the file at `from` (a log's start: its ground, a short flight),
// written to `to`.
inline void write_first_rows(const std::string& from, int rows, const std::string& to) {
    const std::string text = read_file(from);
    size_t end = 0;
    for (int k = 0; k < rows && end < text.size(); ++k) {
        const size_t nl = text.find('\n', end);
        end = nl == std::string::npos ? text.size() : nl + 1;
    }
    write_file(to, text.substr(0, end));
}

// `args` is appended to the binary path as shell words; quote paths yourself.
inline Result run(const std::string& args) { return testsupport::run_program(BATTSIM_BINARY, args); }

inline std::string q(const std::string& s) { return testsupport::shell_quoted(s); }

// Runs `args`, requires exit 0 (showing standard error if not) and parses standard output.
inline nlohmann::json run_json(const std::string& args) {
    const Result r = run(args);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    return nlohmann::json::parse(r.out);
}

// True when `out` is the object a failed --json run writes (cli/json_errors.h) and no more.
inline bool is_error_object(const std::string& out) {
    const nlohmann::json j = nlohmann::json::parse(out, nullptr, false);
    return j.is_object() && j.value("schema", std::string()) == "battsim.error";
}

}  // namespace clitest
