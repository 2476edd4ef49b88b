// Batch manifests: which logs to replay, and for each its pack id, test label, battery
// config and reader settings (format, column mapping). JSON (schema battsim.manifest)
// or CSV (a header row naming the settings); the format is documented in
// configs/manifests/README.md. Errors are InputErrors with the manifest's line and column.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

constexpr const char* kManifestSchema = "battsim.manifest";
constexpr int kManifestVersion = 1;

// Settings of one log, every one optional; unset ones are inherited. Layers, lowest
// first: built-in defaults, the manifest's "defaults", the log's entry, the options
// given on the command line.
struct LogSettings {
    std::optional<std::string> test;    // row label; default: the log's file stem
    std::optional<std::string> pack;    // pack id; rows without one stay out of the pack table
    // The monitor (its current sensor) that logged it; rows without one stay out of the
    // monitor table, which pools the charger checks of each monitor's flights.
    std::optional<std::string> monitor;
    std::optional<std::string> config;  // path of a battsim.config JSON, already resolved
    std::optional<core::EstimatorKind> estimator;  // overrides the config's choice
    std::optional<LogFormat> format;
    std::optional<CurrentSource> current_source;
    std::optional<std::string> time_col, voltage_col, current_col, temperature_col;
    std::optional<double> time_scale_to_s, current_scale_to_a;
    std::optional<std::vector<std::string>> cell_cols;
    std::optional<bool> negative_discharge;
    std::optional<bool> no_temperature;  // ReaderOptions::ignore_temperature
    std::optional<double> average_ms;  // ReaderOptions::average_us, in ms
    // What the charger put back after this log (a single log's entry only): the current
    // sensor is checked against it (`charger_check` in the summary).
    std::optional<double> charged_mah;

    // Every field set in `top` replaces ours.
    void overlay(const LogSettings& top);
    // Reader options with these settings applied over `base`.
    ReaderOptions reader_options(ReaderOptions base = ReaderOptions()) const;
};

struct ManifestEntry {
    std::string path;  // resolved (may be a directory or a pattern, expanded later)
    long line = 0;     // where the entry starts in the manifest, for messages
    long column = 0;   // 0 for CSV manifests (the whole row)
    LogSettings settings;
};

struct Manifest {
    std::string path;
    std::string description;
    LogSettings defaults;
    std::vector<ManifestEntry> logs;
};

// Reader and config options as typed on a command line; empty (or "auto") = not given.
struct LogSettingStrings {
    std::string config, format, current_source, estimator;
    std::string time_col, time_unit, voltage_col, current_col, current_unit, temperature_col;
    std::vector<std::string> cell_cols;
    bool negative_discharge = false;  // a flag: only "given" when set
    bool no_temperature = false;      // a flag: only "given" when set
    double average_ms = 0.0;          // 0 = not given
};
// Validated like manifest fields; throws std::invalid_argument naming the option.
LogSettings settings_from_strings(const LogSettingStrings& s);

// By extension (.json / .csv), else by content ('{' first = JSON). Throws InputError.
Manifest load_manifest(const std::string& path);
// `path` names the manifest in messages and anchors its relative paths.
Manifest parse_manifest_json(const std::string& text, const std::string& path);
Manifest parse_manifest_csv(const std::string& text, const std::string& path);

// "s", "ms", "us" → seconds per unit; "A", "mA" → amperes per unit. Throw
// std::invalid_argument naming the accepted units.
double time_unit_scale(const std::string& unit);
double current_unit_scale(const std::string& unit);
CurrentSource parse_current_source(const std::string& name);
// An averaging window (ms) as given: returned if in [0.001, 60000], else std::invalid_argument.
double average_window_ms(double ms);
// "reference" or "joint".
core::EstimatorKind parse_estimator(const std::string& name);
const char* to_string(core::EstimatorKind kind);

}  // namespace host
}  // namespace battsim
