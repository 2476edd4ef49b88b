// What the subcommands share: the input options (config, format, column mapping), the
// options and the error-to-exit-code plumbing of the model jobs, the --plot name check.
// (What replay prints for people is host/report/brief.h.)
#pragma once
#include <functional>
#include <ostream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "host/batch/manifest.h"
#include "host/config_json.h"
#include "host/io/output_paths.h"
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
    bool no_temperature = false;
    double average_ms = 0.0;  // 0 = off
    std::string estimator;  // empty = as the config says
};

void add_input_options(CLI::App& sub, InputArgs& a);

// A number option in [lo, hi] ((lo, hi] with `above_lo`): NaN and infinities refused, and
// the range said in plain figures (CLI11's PositiveNumber and Range let NaN through and
// print a 300-digit double's limit).
CLI::Validator number_in(double lo, double hi, bool above_lo = false);

// A comma-separated list (`--params e0,r`; repeatable, the lists joined). Each occurrence
// takes one argument, split here: CLI11 2.1's own delimiter read `--params ,` as no value
// and went on to take the next argument, even `-c`. An empty item is refused, and so is an
// item `check_item` answers with a message.
CLI::Option* add_list_option(CLI::App& sub, const std::string& flags, std::vector<std::string>& items,
                             const std::string& help,
                             const std::function<std::string(const std::string&)>& check_item = nullptr);

// What fit and residual share: the capacity bound, the report, the plot and the input.
struct ModelJobArgs {
    double max_capacity_factor = 1.5;
    std::string report, plot;
    bool json = false;
    InputArgs input;
};
// The fits' starting points (fit, residual): --starts and -j/--jobs.
struct StartArgs {
    int starts = 1;
    int jobs = 0;  // 0 = the machine's cores
    int threads() const;
};
// `each_fit` names what the starts are of ("the fit"); `parallel` what -j runs side by side.
void add_start_options(CLI::App& sub, StartArgs& a, const std::string& each_fit, const std::string& parallel);
// Adds those options after the command's own; `report` names the report in the help
// ("fit report"), `plot_help` says what the plot shows.
void add_model_job_options(CLI::App& sub, ModelJobArgs& a, const std::string& report, const std::string& plot_help);
// Fills reader options (through host::settings_from_strings, as batch and manifests) and
// loads the config (with its model extensions); prints the error, prefixed with `command`
// ("battsim replay"), and returns an exit code other than kExitOk on failure.
int resolve_input(const InputArgs& a, host::ReaderOptions& reader, host::LoadedConfig& config,
                  const std::string& command);
// The options as typed, for the batch planner, which validates them like a manifest's
// fields (batch, bench).
host::LogSettingStrings setting_strings(const InputArgs& a);
// Runs `job`, turning the host library's exceptions into exit codes with a message:
// bad input 3, a bad config 4, bad arguments 2, anything else (outputs) 5.
int run_job(const std::string& command, const std::function<void()>& job);
// Writes the report JSON to `path` (if given) atomically, then prints it (`json`) or the
// brief to `people`; returns the exit code.
int finish_report(const std::string& command, const nlohmann::json& report, const std::string& path, bool json,
                  const std::function<void(std::ostream&)>& brief, std::ostream& people = std::cout);
// kExitOk if `path` is empty or a plot name (.png, .svg) with gnuplot on PATH; else says why,
// kExitUsage (the name) or kExitOutputError (no gnuplot). Checked before the work, so a typo
// or a missing gnuplot does not cost a long run and the outputs after it.
int check_plot_option(const std::string& command, const std::string& path);
// kExitOk unless an output names an input or another output's file (host::check_output_paths;
// kExitUsage) or cannot be written (host::first_unwritable_output; kExitOutputError); then
// says which, prefixed with `command`. Called before the work.
int check_outputs(const std::string& command, const std::vector<host::NamedPath>& inputs,
                  const std::vector<host::NamedPath>& outputs);
// kExitOk unless two of `logs` name one file (by any name: a link, "./x" beside "x"); then
// says which, prefixed with `command`, and returns kExitUsage. A log given twice weighs
// twice in a fit, doubles a test's evidence, or counts twice in a score.
int check_logs_once(const std::string& command, const std::vector<host::NamedPath>& logs);
// An output of text that "-" sends to standard output (a table, a CSV, a JSON document).
host::NamedPath text_output(const std::string& what, const std::string& path, bool config = false);
// A flag that prints a document on standard output (--json), as check_outputs' output "-":
// a second output "-" beside it is refused.
host::NamedPath printed_output(const std::string& flag, bool given);
// Where the lines for people go: standard error when one of `outputs` is standard output
// ("-"), so that they do not mix into it; else standard output.
std::ostream& people_out(const std::vector<host::NamedPath>& outputs);
// Appends `paths` to `to`, each named `what` in check_outputs' messages ("a log").
void add_named(std::vector<host::NamedPath>& to, const std::string& what, const std::vector<std::string>& paths);
// Writes a config a command tuned the joint estimator in (calibrate, fit-ocv) to `path`,
// atomically, selecting that estimator: one left on the reference estimator changed nothing a
// replay or the firmware ran. Says so once written (not before a write that fails). The
// description gets `marker` + `rest` in place of an earlier note with the same marker (tuned
// again into its own file, it had said so twice). Returns the exit code.
int write_tuned_config(host::LoadedConfig config, const std::string& path, const char* command, const std::string& marker,
                       const std::string& rest);

}  // namespace cli
}  // namespace battsim
