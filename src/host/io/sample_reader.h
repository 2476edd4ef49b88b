// Streaming readers: every supported log format becomes a sequence of core::Sample.
// Host only (exceptions allowed). A reader never loads the whole file.
#pragma once
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/sample.h"
#include "core/sensor.h"

namespace battsim {
namespace host {

// Bad input: carries where it happened and what was expected, so the CLI can print
// "file:line:column: message" and exit non-zero.
class InputError : public std::runtime_error {
public:
    InputError(std::string file, long line, long column, const std::string& message)
        : std::runtime_error(format(file, line, column, message)),
          file_(std::move(file)), line_(line), column_(column), message_(message) {}
    const std::string& file() const { return file_; }
    long line() const { return line_; }      // 1-based; 0 = not applicable (binary: see message)
    long column() const { return column_; }  // 1-based field number; 0 = not applicable
    const std::string& message() const { return message_; }

private:
    static std::string format(const std::string& file, long line, long column, const std::string& msg) {
        if (file.empty()) return msg;  // of several files, none to name
        std::string s = file;
        if (line > 0) s += ":" + std::to_string(line);
        if (column > 0) s += ":" + std::to_string(column);
        return s + ": " + msg;
    }
    std::string file_;
    long line_;
    long column_;
    std::string message_;
};

enum class LogFormat { Auto, RawPbms, Csv, DataflashText, DataflashBinary, Ulog };

// A format's name (on the command line, in manifests and summaries) and a few words for help
// texts.
struct LogFormatEntry {
    LogFormat format;
    const char* name;
    const char* description;
};
// Every LogFormat, Auto first, in the order help texts and messages list them: the one list a
// new format is added to. to_string, parse_log_format, the --format and --log-format help and
// the reader fuzz harness all read it.
const std::vector<LogFormatEntry>& log_formats();

// The entry's name; "unknown" for a value not in log_formats().
const char* to_string(LogFormat f);
// Accepts a name from log_formats(); throws std::invalid_argument naming them all.
LogFormat parse_log_format(const std::string& name);
// The help text of an option taking a log format: every name, each with its description.
std::string log_format_help();

enum class CurrentSource { Auto, Current, Shunt };

// How headered CSV columns map to sample fields. Empty = use the default names
// (time_s|time_ms|time_us, voltage_v, current_a|current_ma, cellN_v, temperature_c; a
// header holding two names of one quantity needs that one mapped).
struct ColumnMapping {
    std::string time;            // column name
    double time_scale_to_s = 0;  // 0 = infer from the name suffix (_s, _ms, _us); else multiply
    std::string voltage;
    std::string current;
    double current_scale_to_a = 0;  // 0 = infer (_a, _ma); else multiply
    bool current_negative_is_discharge = false;
    std::vector<std::string> cells;  // in order cell 1..N
    std::string temperature;
};

struct ReaderOptions {
    LogFormat format = LogFormat::Auto;
    CurrentSource current_source = CurrentSource::Auto;  // raw logs: Auto = logged current_ma
    core::ShuntCalibration shunt;
    ColumnMapping columns;
    // > 0: consecutive samples are averaged over windows this long (a window starts at its
    // first sample and takes every sample before start + average_us), one sample per window
    // at its last sample's time. For logs sampled faster than the joint estimator's
    // resistance lags reach (blackbox logs at hundreds of hertz).
    std::uint64_t average_us = 0;
    // > 0: the pack's capacity, for telling a clock step from a logging gap. A forward jump
    // of the log's clock over which even the smaller current either side would have drawn
    // more than this is a step of the clock (a radio's RTC set by GPS, two files joined), not
    // time that passed: the samples after it are moved back to follow on (a note says so).
    double clock_step_capacity_ah = 0.0;
    // The log's temperature left out (every format): a config whose temperature terms its
    // self-heating state drives was fitted to that state's rise, not to a measurement.
    bool ignore_temperature = false;
};

// What the reader found out about the log, for summaries and the README tables.
struct SourceInfo {
    std::string path;
    LogFormat format = LogFormat::Auto;
    int cell_count = 0;
    // Cells the log carries when more than battsim keeps (core::kMaxCells; then cell_count is
    // that bound and the rest are dropped with a note), else 0.
    int cells_beyond_kept = 0;
    bool has_temperature = false;
    std::vector<std::string> notes;  // repairs and skipped lines, human readable, with line numbers
    // Parameters the autopilot recorded (ArduPilot PARM Name/Value, PX4 ULog parameter
    // messages), in the order first seen, each with its first value. Empty for CSV and raw
    // logs. Complete once next() has returned false.
    std::vector<std::pair<std::string, double>> parameters;
    // A CSV log's current column: the amperes one of its units was read as (1e-3: milliamperes;
    // 0: another format), for the note when a log in amperes read as milliamperes never flies.
    double current_scale_to_a = 0.0;
    // A CSV log's time column and the seconds one of its units was read as (1e-3: its name's
    // _ms, or --time-unit ms; 0: another format, or a wall clock), for the notes that judge
    // whether the log's clock was read in its unit.
    double time_scale_to_s = 0.0;
    std::string time_column;
    // With --average-ms: the samples read and the averaged samples made of them (0: none).
    long averaged_in = 0, averaged_out = 0;
};

// The first recorded value of `name` among `info.parameters`; NaN when the log has none.
double log_parameter(const SourceInfo& info, const std::string& name);

class SampleReader {
public:
    virtual ~SampleReader() = default;
    // Fills `out` with the next sample; false at the end of the log. Throws InputError
    // for input it cannot read or repair.
    virtual bool next(core::Sample& out) = 0;
    virtual const SourceInfo& info() const = 0;
};

// Opens `path` (throws InputError if missing/unreadable/empty) and detects the format
// from the content unless options.format says otherwise.
std::unique_ptr<SampleReader> open_reader(const std::string& path, const ReaderOptions& options);

// The format open_reader() would pick for `path` with options.format == Auto (never
// returns Auto). Reads only the first 64 KiB. Throws InputError like open_reader().
LogFormat detect_log_format(const std::string& path);

}  // namespace host
}  // namespace battsim
