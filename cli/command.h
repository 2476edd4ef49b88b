// Each subcommand lives in its own cli/cmd_*.cpp and registers itself here, so adding
// one never touches main.cpp. A command only parses options and calls the library.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "exit_codes.h"

namespace battsim {
namespace cli {

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
