// The exit code of what escapes a command (cli/run_guarded.h): no command lets an error out
// on purpose, so the mapping is checked here rather than through the binary.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "run_guarded.h"

using namespace battsim;

namespace {
struct Ran {
    int code;
    std::string err;
};
Ran guarded(const std::function<int()>& action) {
    std::ostringstream err;
    const int code = cli::run_guarded("batch", action, err);
    return {code, err.str()};
}
}  // namespace

TEST_CASE("an unexpected error exits 70, not batch's 'some logs failed' (1)", "[exit]") {
    CHECK(guarded([] { return 0; }).code == 0);
    CHECK(guarded([] { return int(cli::kExitFailure); }).code == 1);  // a command's own code passes through
    const Ran bug = guarded([]() -> int { throw std::logic_error("vector::_M_range_check"); });
    CHECK(bug.code == 70);
    CHECK(bug.code == cli::kExitInternal);
    CHECK(bug.err == "battsim batch: internal error: vector::_M_range_check (a bug in battsim, exit 70; please report "
                     "it with the command line)\n");
    const Ran odd = guarded([]() -> int { throw 42; });
    CHECK(odd.code == 70);
    CHECK_THAT(odd.err, Catch::Contains("an exception of unknown type"));
}

TEST_CASE("running out of memory exits 71 and says so, not 'a bug in battsim'", "[exit]") {
    const Ran oom = guarded([]() -> int { throw std::bad_alloc(); });
    CHECK(oom.code == 71);
    CHECK(oom.code == cli::kExitOutOfMemory);
    CHECK(oom.err == "battsim batch: out of memory (exit 71; try fewer --jobs, a shorter log or a machine with more "
                     "memory)\n");
}

TEST_CASE("an input or config error that gets out of a command keeps its documented code", "[exit]") {
    const Ran input = guarded([]() -> int { throw host::InputError("log.csv", 3, 2, "expected a number"); });
    CHECK(input.code == 3);
    CHECK(input.err == "battsim batch: log.csv:3:2: expected a number\n");
    const Ran config = guarded([]() -> int { throw host::ConfigError("c.json: $.battery.x: unknown key"); });
    CHECK(config.code == 4);
    CHECK(config.err == "battsim batch: config: c.json: $.battery.x: unknown key\n");
}

TEST_CASE("the README's exit-code table lists every exit code", "[exit]") {
    std::ifstream in(std::string(BATTSIM_SOURCE_DIR) + "/README.md");
    std::stringstream text;
    text << in.rdbuf();
    const std::string readme = text.str();
    const std::string section = readme.substr(readme.find("### Exit codes"));
    for (int code : {cli::kExitOk, cli::kExitFailure, cli::kExitUsage, cli::kExitInputError, cli::kExitConfigError,
                     cli::kExitOutputError, cli::kExitInternal, cli::kExitOutOfMemory}) {
        INFO(code);
        CHECK(section.find("\n| " + std::to_string(code) + " | ") != std::string::npos);
    }
}
