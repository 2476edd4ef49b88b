// Each subcommand lives in its own cli/cmd_*.cpp and registers itself here, so adding
// one never touches main.cpp. A command only parses options and calls the library.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace battsim {
namespace cli {

// Exit codes shared by every subcommand (documented in the README).
enum ExitCode : int {
    kExitOk = 0,
    kExitFailure = 1,      // the job ran but found failures (batch rows in error, regressions)
    kExitUsage = 2,        // bad command line
    kExitInputError = 3,   // unreadable or malformed input file
    kExitConfigError = 4,  // bad configuration file
    kExitOutputError = 5,  // could not write an output
};

struct Command {
    std::string name;
    std::string description;
    // Adds options to `sub` and returns the action run when the subcommand was chosen.
    std::function<std::function<int()>(CLI::App& sub)> setup;
};

std::vector<Command>& command_registry();

struct RegisterCommand {
    explicit RegisterCommand(Command c) { command_registry().push_back(std::move(c)); }
};

}  // namespace cli
}  // namespace battsim
