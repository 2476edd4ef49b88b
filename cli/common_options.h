// Options shared by the commands that read logs: config, format, column mapping.
#pragma once
#include <ostream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "host/config_json.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace cli {

struct InputArgs {
    std::string config;
    std::string format = "auto";
    std::string current_source = "auto";
    std::string time_col, voltage_col, current_col, temperature_col;
    std::string time_unit, current_unit;
    std::vector<std::string> cell_cols;
    bool negative_discharge = false;
    std::string estimator;  // empty = as the config says
};

void add_input_options(CLI::App& sub, InputArgs& a);
// Fills reader options and loads the config; prints the error and returns an exit code
// other than kExitOk on failure.
int resolve_input(const InputArgs& a, host::ReaderOptions& reader, host::LoadedConfig& config);
// Human-readable few lines about a summary.
void print_brief(const nlohmann::json& summary, std::ostream& out);

}  // namespace cli
}  // namespace battsim
