// Format names and open_reader(): opens a log and picks its reader from the content.
#include "host/io/sample_reader.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "host/io/csv_reader.h"
#include "host/io/dataflash_reader.h"
#include "host/io/ulog_reader.h"

namespace battsim {
namespace host {

const std::vector<LogFormatEntry>& log_formats() {
    static const std::vector<LogFormatEntry> formats{
        {LogFormat::Auto, "auto", "detected from the content"},
        {LogFormat::RawPbms, "raw", "the dissertation logger's 8 fields, no header"},
        {LogFormat::Csv, "csv", "CSV with a header row"},
        {LogFormat::DataflashText, "dataflash-text", "ArduPilot text log"},
        {LogFormat::DataflashBinary, "dataflash-bin", "ArduPilot .bin log"},
        {LogFormat::Ulog, "ulog", "PX4 .ulg log"},
    };
    return formats;
}

const char* to_string(LogFormat f) {
    for (const LogFormatEntry& e : log_formats())
        if (e.format == f) return e.name;
    return "unknown";
}

LogFormat parse_log_format(const std::string& name) {
    std::string names;
    for (const LogFormatEntry& e : log_formats()) {
        if (name == e.name) return e.format;
        names += (names.empty() ? "" : ", ") + std::string(e.name);
    }
    throw std::invalid_argument("unknown log format \"" + name + "\"; expected one of " + names);
}

std::string log_format_help() {
    std::string help = "Log format:";
    const char* separator = " ";
    for (const LogFormatEntry& e : log_formats()) {
        help += separator + std::string(e.name) + " (" + e.description + ")";
        separator = ", ";
    }
    return help;
}

namespace {

constexpr std::size_t kPeekBytes = 64 * 1024;
constexpr int kFmtSearchLines = 100;

// Reads up to kPeekBytes from the start of the file; throws InputError if the file cannot
// be read or is empty.
std::vector<unsigned char> peek(const std::string& path) {
    // Check the kind of file before opening it: opening a FIFO would block, and a pipe
    // cannot be read twice (once here to detect the format, once by the reader).
    if (path == "-")
        throw InputError(path, 0, 0,
                         "a log is not read from standard input (its format is detected before it is read); "
                         "expected a log file: save the stream to a file first (a file named -: give ./-)");
    struct stat st;
    errno = 0;
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        throw InputError(path, 0, 0, std::string("cannot open file: ") + (err ? std::strerror(err) : "unknown error"));
    }
    if (S_ISDIR(st.st_mode)) throw InputError(path, 0, 0, "cannot open file: it is a directory, expected a log file");
    if (!S_ISREG(st.st_mode)) {
        throw InputError(path, 0, 0,
                         "cannot open file: it is not a regular file (pipes and devices are not supported); "
                         "expected a log file");
    }
    errno = 0;
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (f == nullptr) {
        const int err = errno;
        throw InputError(path, 0, 0, std::string("cannot open file: ") + (err ? std::strerror(err) : "unknown error"));
    }
    std::vector<unsigned char> buf(kPeekBytes);
    errno = 0;
    const std::size_t got = std::fread(buf.data(), 1, buf.size(), f);
    const bool failed = std::ferror(f) != 0;
    const int err = errno;
    std::fclose(f);
    if (failed) {
        throw InputError(path, 0, 0, std::string("read error: ") + (err ? std::strerror(err) : "unknown error"));
    }
    if (got == 0) throw InputError(path, 0, 0, "file is empty");
    buf.resize(got);
    return buf;
}

// A byte no text log holds: a control character other than tab, CR and LF, or DEL.
bool odd_byte(unsigned char c) { return (c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7F; }

// Text in UTF-16 or UTF-32 ("Unicode" in a spreadsheet's or Windows' save dialogue): each
// ASCII character followed or preceded by NULs. "" if `head` does not look like it, else what
// it looks like ("UTF-16 (little-endian, with a byte-order mark)").
// `charset`: its name for iconv -f.
std::string wide_text(const std::vector<unsigned char>& head, std::string& charset) {
    const size_t n = head.size();
    charset = "UTF-32";
    if (n >= 4 && head[0] == 0xFF && head[1] == 0xFE && head[2] == 0 && head[3] == 0)
        return "UTF-32 (little-endian, with a byte-order mark)";
    if (n >= 4 && head[0] == 0 && head[1] == 0 && head[2] == 0xFE && head[3] == 0xFF)
        return "UTF-32 (big-endian, with a byte-order mark)";
    charset = "UTF-16";
    if (n >= 2 && head[0] == 0xFF && head[1] == 0xFE) return "UTF-16 (little-endian, with a byte-order mark)";
    if (n >= 2 && head[0] == 0xFE && head[1] == 0xFF) return "UTF-16 (big-endian, with a byte-order mark)";
    // Without a mark: nine pairs in ten an ASCII character beside a NUL, in the first 1 KiB.
    const size_t pairs = std::min<size_t>(n, 1024) / 2;
    if (pairs < 4) return "";
    size_t little = 0, big = 0;
    for (size_t k = 0; k < pairs; ++k) {
        const unsigned char a = head[2 * k], b = head[2 * k + 1];
        if (b == 0 && a != 0 && a < 0x80 && !odd_byte(a)) ++little;
        if (a == 0 && b != 0 && b < 0x80 && !odd_byte(b)) ++big;
    }
    // Named so: without a mark iconv's "UTF-16" is big-endian.
    charset = little > big ? "UTF-16LE" : "UTF-16BE";
    if (10 * little >= 9 * pairs) return "UTF-16 (little-endian, without a byte-order mark)";
    if (10 * big >= 9 * pairs) return "UTF-16 (big-endian, without a byte-order mark)";
    return "";
}

// Where a text log stops being text: the NUL at `nul` (an offset in `head`), on the line and
// field it falls in (fields counted as split_fields() does, quotes and all).
[[noreturn]] void refuse_nul_in_text(const std::string& path, const std::vector<unsigned char>& head, size_t begin,
                                     size_t nul) {
    long line = 1;
    size_t line_start = begin;
    for (size_t i = begin; i < nul; ++i)
        if (head[i] == '\n') {
            ++line;
            line_start = i + 1;
        }
    const std::string_view text_line(reinterpret_cast<const char*>(head.data()) + line_start, nul - line_start);
    throw InputError(path, line, text::field_at(text_line, text_line.size()),
                     "a NUL byte at byte offset " + std::to_string(nul) +
                         ": expected text (a CSV log holds no NUL bytes; a logger that lost power may have padded "
                         "its file with them: cut the file before this line)");
}

LogFormat detect(const std::string& path, const std::vector<unsigned char>& head) {
    static const unsigned char kUlogMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
    if (head.size() >= sizeof kUlogMagic && std::memcmp(head.data(), kUlogMagic, sizeof kUlogMagic) == 0)
        return LogFormat::Ulog;
    if (head.size() >= 2 && head[0] == 0xA3 && head[1] == 0x95) return LogFormat::DataflashBinary;
    // A compressed log (flight logs are often kept gzipped) would otherwise read as "binary".
    struct Packed {
        const char* magic;
        size_t size;
        const char* what;
        const char* unpack;
    };
    static const Packed kPacked[] = {{"\x1F\x8B", 2, "gzip-compressed", "gunzip"},
                                     {"PK\x03\x04", 4, "a zip archive", "unzip"},
                                     {"\xFD" "7zXZ\x00", 6, "xz-compressed", "unxz"},
                                     {"\x28\xB5\x2F\xFD", 4, "zstd-compressed", "unzstd"}};
    for (const Packed& k : kPacked) {
        if (head.size() >= k.size && std::memcmp(head.data(), k.magic, k.size) == 0) {
            throw InputError(path, 0, 0,
                             std::string("the file is ") + k.what + "; expected a log itself: unpack it first (" +
                                 k.unpack + ")");
        }
    }
    std::string charset;
    const std::string wide = wide_text(head, charset);
    if (!wide.empty())
        throw InputError(path, 0, 0,
                         "the file looks like " + wide +
                             " text; battsim reads text logs in UTF-8 (or ASCII): save it as UTF-8 (a spreadsheet's "
                             "\"CSV UTF-8\", or iconv -f " + charset + " -t UTF-8)");

    std::string_view txt(reinterpret_cast<const char*>(head.data()), head.size());
    if (txt.size() >= 3 && txt.compare(0, 3, "\xEF\xBB\xBF") == 0) txt.remove_prefix(3);
    const size_t begin = head.size() - txt.size();  // after a UTF-8 byte-order mark
    // Text up to a NUL run that lasts to the end of what was peeked is a log a logger cut
    // there when it lost power (it pads its file with NULs): the CSV reader checks the rest.
    if (const size_t z = txt.find('\0');
        z != std::string_view::npos && z > 0 && txt.find_first_not_of('\0', z) == std::string_view::npos &&
        std::none_of(txt.begin(), txt.begin() + static_cast<std::ptrdiff_t>(z),
                     [](char c) { return odd_byte(static_cast<unsigned char>(c)); }))
        txt = txt.substr(0, z);

    // Split the peeked text into lines (the last one may be incomplete).
    std::vector<std::string_view> lines;
    {
        std::size_t start = 0;
        while (start < txt.size() && lines.size() < static_cast<std::size_t>(kFmtSearchLines)) {
            std::size_t nl = txt.find('\n', start);
            if (nl == std::string_view::npos) nl = txt.size();
            std::string_view l = txt.substr(start, nl - start);
            if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
            lines.push_back(l);
            start = nl + 1;
        }
    }
    for (std::string_view l : lines) {
        const std::size_t b = l.find_first_not_of(" \t");
        if (b != std::string_view::npos && l.compare(b, 4, "FMT,") == 0) return LogFormat::DataflashText;
    }
    if (const size_t nul_in_txt = txt.find('\0'); nul_in_txt != std::string_view::npos) {
        // Said where: text up to a NUL is a text log with a damaged stretch; otherwise the
        // first byte that is no text's is where it stops looking like a log.
        const size_t nul = begin + nul_in_txt;
        size_t odd = begin;
        while (odd < nul && !odd_byte(head[odd])) ++odd;
        if (odd == nul && nul > begin) refuse_nul_in_text(path, head, begin, nul);
        char what[96];
        std::snprintf(what, sizeof what, "byte 0x%02X at offset %zu is not text", static_cast<unsigned>(head[odd]), odd);
        throw InputError(path, 0, 0,
                         std::string("unrecognised binary file (") + what +
                             (odd == nul ? "" : ", the first NUL at offset " + std::to_string(nul)) +
                             "): expected a ULog (.ulg), DataFlash (.bin) or text (CSV) log");
    }

    // First line neither blank nor a comment ('#', as the readers skip): all numbers means no header row.
    long comment_line = 0;  // the last comment before it, 1-based
    for (std::size_t i = 0; i < lines.size(); ++i) {
        const std::size_t first = lines[i].find_first_not_of(" \t");
        if (first == std::string_view::npos) continue;
        if (lines[i][first] == '#' && lines[i].substr(first + 1, 1) != ",") {  // "#," is a field named "#"
            comment_line = static_cast<long>(i) + 1;
            continue;
        }
        std::vector<std::string_view> fields;
        long bad = 0;
        if (!text::split_fields(lines[i], fields, bad)) return LogFormat::Csv;
        bool numeric = true;
        for (std::size_t k = 0; k < fields.size(); ++k) {
            double v = 0.0;
            const text::NumberStatus st = text::parse_number(fields[k], v);
            if (st == text::NumberStatus::NotANumber ||
                (st == text::NumberStatus::Empty && !(k + 1 == fields.size() && k > 0))) {
                numeric = false;
                break;
            }
        }
        if (!numeric) return LogFormat::Csv;
        const std::size_t n = fields.size();
        if (n == 8 || (n == 9 && fields[8].empty())) return LogFormat::RawPbms;
        throw InputError(path, static_cast<long>(i) + 1, 0,
                         "cannot detect the log format: the first line" +
                             std::string(comment_line > 0 ? " after the comments" : "") + " holds " + std::to_string(n) +
                             " fields of numbers and no header; expected a header row (CSV) or the 8 fields "
                             "of a predictive-bms log (time_ms, bus_voltage_v, cell1_v..cell4_v, current_ma, "
                             "shunt_mv)" +
                             (comment_line > 0 ? " (line " + std::to_string(comment_line) +
                                                     " starts with '#' and is skipped as a comment: if it is the "
                                                     "header, remove the '#')"
                                               : std::string()));
    }
    return LogFormat::Csv;
}

}  // namespace

LogFormat detect_log_format(const std::string& path) { return detect(path, peek(path)); }

double log_parameter(const SourceInfo& info, const std::string& name) {
    // Linear: called for a handful of names per log, and the readers keep only first values.
    for (const auto& p : info.parameters)
        if (p.first == name) return p.second;
    return std::nan("");
}

namespace {

// Means of consecutive samples over windows of a fixed length (ReaderOptions::average_us).
class AveragingReader final : public SampleReader {
public:
    AveragingReader(std::unique_ptr<SampleReader> inner, std::uint64_t window_us)
        : inner_(std::move(inner)), window_us_(window_us) {
        have_next_ = inner_->next(next_);
    }

    bool next(core::Sample& out) override {
        if (!have_next_) return false;
        const core::Sample first = next_;
        double v = 0.0, a = 0.0, t = 0.0, cells[core::kMaxCells] = {};
        long n = 0, n_temperature = 0;
        core::Sample last = first;
        // Samples with another cell count start a new window: they are not one sensor's.
        while (have_next_ && next_.time_us - first.time_us < window_us_ && next_.cell_count == first.cell_count) {
            last = next_;
            v += next_.voltage_v;
            a += next_.current_a;
            for (int c = 0; c < next_.cell_count; ++c) cells[c] += next_.cell_voltage_v[c];
            // A window keeps the mean of the temperatures it has: one dropped reading (nan,
            // empty) had cost the whole window its temperature.
            if (next_.has_temperature) {
                t += next_.temperature_c;
                ++n_temperature;
            }
            ++n;
            have_next_ = inner_->next(next_);
        }
        out = last;
        out.voltage_v = static_cast<float>(v / static_cast<double>(n));
        out.current_a = static_cast<float>(a / static_cast<double>(n));
        for (int c = 0; c < out.cell_count; ++c) out.cell_voltage_v[c] = static_cast<float>(cells[c] / static_cast<double>(n));
        out.has_temperature = n_temperature > 0;
        out.temperature_c = n_temperature > 0 ? static_cast<float>(t / static_cast<double>(n_temperature)) : 0.0f;
        samples_in_ += n;
        ++samples_out_;
        return true;
    }

    const SourceInfo& info() const override {
        info_ = inner_->info();
        info_.averaged_in = samples_in_;
        info_.averaged_out = samples_out_;
        char buf[160];
        std::snprintf(buf, sizeof buf, "samples averaged over %.6g ms windows: %ld read into %ld",
                      static_cast<double>(window_us_) * 1e-3, samples_in_, samples_out_);
        info_.notes.push_back(buf);
        return info_;
    }

private:
    std::unique_ptr<SampleReader> inner_;
    std::uint64_t window_us_;
    core::Sample next_;
    bool have_next_ = false;
    long samples_in_ = 0, samples_out_ = 0;
    mutable SourceInfo info_;
};

// Moves the samples after a step of the log's clock back (ReaderOptions::clock_step_capacity_ah).
// Counted as a gap, a 3600 s step mid-flight had charged the pack 13.95 Ah (of 5.2) over it and
// read a model error of volts; only a jump the pack could not have flown through is moved.
class ClockStepReader final : public SampleReader {
public:
    // Shorter jumps are left to the monitor as gaps (TimeOrder::kJumpUs: the shared logs'
    // longest logging gap is 8.8 s).
    static constexpr std::uint64_t kMinStepUs = 30000000;
    // A config's capacity may be the label's, and a pack gives a little more; none gives half again.
    static constexpr double kCapacities = 1.5;
    // Or more than a quarter of it at the same flight load (currents within 20 %, at least
    // 1 C: at a ground load a resting pack's recovery can hide the drop) with the voltage not
    // 0.5 % lower after the gap.
    static constexpr double kUnsaggedCapacities = 0.25, kSameLoad = 0.2, kUnsaggedVoltage = 0.005, kFlightLoadPerHour = 1.0;

    ClockStepReader(std::unique_ptr<SampleReader> inner, double capacity_ah)
        : inner_(std::move(inner)), capacity_ah_(capacity_ah) {}

    bool next(core::Sample& out) override {
        if (!inner_->next(out)) return false;
        if (!have_) first_us_ = out.time_us;
        const std::uint64_t raw_us = out.time_us;
        out.time_us = raw_us >= shift_us_ ? raw_us - shift_us_ : 0;
        if (have_ && out.time_us > last_us_ + kMinStepUs) {
            const std::uint64_t jump_us = out.time_us - last_us_;
            const double before_a = std::fabs(static_cast<double>(last_a_)), after_a = std::fabs(static_cast<double>(out.current_a));
            const double least_ah = std::min(before_a, after_a) * static_cast<double>(jump_us) * 1e-6 / 3600.0;
            // A gap flown at a steady load drops the pack's voltage: a quarter of the capacity
            // is 0.05-0.2 V per cell. Where the load is the same on both sides and the voltage
            // has not dropped, no charge was drawn over it (a hover log paused for ten minutes
            // had been charged 1.4 Ah of 1.5 and read a 3.1 Ah pack).
            const double before_v = static_cast<double>(last_v_), after_v = static_cast<double>(out.voltage_v);
            const bool same_load = std::fabs(after_a - before_a) <= kSameLoad * std::max(before_a, after_a);
            const bool flight_load = std::min(before_a, after_a) >= kFlightLoadPerHour * capacity_ah_;
            const bool unsagged = same_load && flight_load && least_ah > kUnsaggedCapacities * capacity_ah_ && before_v > 0.0 &&
                                  after_v >= before_v * (1.0 - kUnsaggedVoltage);
            if (std::isfinite(least_ah) && (least_ah > kCapacities * capacity_ah_ || unsagged)) {
                // The step becomes one usual interval (the last one before it).
                const std::uint64_t step_us = jump_us - interval_us_;
                shift_us_ += step_us;
                out.time_us -= step_us;
                char buf[480];
                if (least_ah > kCapacities * capacity_ah_)
                    std::snprintf(buf, sizeof buf,
                                  "the log's clock steps %.6g s ahead at %.6g s into the log, with %.3g A before and %.3g A "
                                  "after: over a logging gap that long the pack would have delivered at least %.4g Ah, more "
                                  "than one and a half times the config's %.4g Ah, so the clock stepped (a radio's clock "
                                  "set by GPS, two files joined); the samples after it are read %.6g s earlier, to follow on",
                                  static_cast<double>(jump_us) * 1e-6, static_cast<double>(last_us_ - first_us_) * 1e-6,
                                  before_a, after_a, least_ah, capacity_ah_, static_cast<double>(step_us) * 1e-6);
                else
                    std::snprintf(buf, sizeof buf,
                                  "the log's clock steps %.6g s ahead at %.6g s into the log, with %.3g A before and %.3g A "
                                  "after and the pack at %.4g V before and %.4g V after: a gap that long at that load would "
                                  "have drawn at least %.4g Ah of the config's %.4g Ah and lowered the voltage, so no charge "
                                  "was drawn over it (the clock stepped, or the logger paused); the samples after it are read "
                                  "%.6g s earlier, to follow on",
                                  static_cast<double>(jump_us) * 1e-6, static_cast<double>(last_us_ - first_us_) * 1e-6,
                                  before_a, after_a, before_v, after_v, least_ah, capacity_ah_,
                                  static_cast<double>(step_us) * 1e-6);
                notes_.push_back(buf);
            }
        }
        if (have_ && out.time_us > last_us_ && out.time_us - last_us_ <= kMinStepUs) interval_us_ = out.time_us - last_us_;
        last_us_ = std::max(last_us_, out.time_us);
        last_a_ = out.current_a;
        last_v_ = out.voltage_v;
        have_ = true;
        return true;
    }

    const SourceInfo& info() const override {
        info_ = inner_->info();
        info_.notes.insert(info_.notes.end(), notes_.begin(), notes_.end());
        return info_;
    }

private:
    std::unique_ptr<SampleReader> inner_;
    double capacity_ah_;
    bool have_ = false;
    std::uint64_t first_us_ = 0, last_us_ = 0, shift_us_ = 0, interval_us_ = 0;
    float last_a_ = 0.0f, last_v_ = 0.0f;
    std::vector<std::string> notes_;
    mutable SourceInfo info_;
};

// A reader with one more note of its own (options that do not apply to the log's format).
class NotedReader final : public SampleReader {
public:
    NotedReader(std::unique_ptr<SampleReader> inner, std::string note) : inner_(std::move(inner)), note_(std::move(note)) {}
    bool next(core::Sample& out) override { return inner_->next(out); }
    const SourceInfo& info() const override {
        info_ = inner_->info();
        info_.notes.insert(info_.notes.begin(), note_);
        return info_;
    }

private:
    std::unique_ptr<SampleReader> inner_;
    std::string note_;
    mutable SourceInfo info_;
};

// The log's temperature left out (ReaderOptions::ignore_temperature), said when it had one.
class NoTemperatureReader final : public SampleReader {
public:
    explicit NoTemperatureReader(std::unique_ptr<SampleReader> inner) : inner_(std::move(inner)) {}

    bool next(core::Sample& out) override {
        if (!inner_->next(out)) return false;
        if (out.has_temperature) ++dropped_;
        out.has_temperature = false;
        out.temperature_c = 0.0f;
        return true;
    }
    const SourceInfo& info() const override {
        info_ = inner_->info();
        if (info_.has_temperature || dropped_ > 0)
            info_.notes.push_back("the log's temperature is left out (--no-temperature; a manifest's \"no_temperature\")");
        info_.has_temperature = false;
        return info_;
    }

private:
    std::unique_ptr<SampleReader> inner_;
    long dropped_ = 0;
    mutable SourceInfo info_;
};

std::unique_ptr<SampleReader> open_format(const std::string& path, const ReaderOptions& options) {
    const std::vector<unsigned char> head = peek(path);
    LogFormat format = options.format;
    if (format == LogFormat::Auto) format = detect(path, head);
    // Options for one format given for a log of another: they had been dropped without a
    // word (a log counting discharge as negative then flew nothing); now a note says so.
    std::vector<std::string> foreign;
    const ColumnMapping& c = options.columns;
    if (format != LogFormat::Csv) {
        const std::pair<bool, const char*> csv_only[] = {
            {!c.time.empty(), "--time-col"},        {c.time_scale_to_s != 0, "--time-unit"},
            {!c.voltage.empty(), "--voltage-col"},  {!c.current.empty(), "--current-col"},
            {c.current_scale_to_a != 0, "--current-unit"}, {c.current_negative_is_discharge, "--negative-discharge"},
            {!c.cells.empty(), "--cell-cols"},      {!c.temperature.empty(), "--temperature-col"}};
        std::string names;
        size_t count = 0;
        for (const auto& [given, name] : csv_only)
            if (given) names += (count++ ? ", " : "") + std::string(name);
        if (count) foreign.push_back(names + (count > 1 ? " apply" : " applies") + " to headered CSV logs only");
    }
    if (format != LogFormat::RawPbms && format != LogFormat::Csv && options.current_source != CurrentSource::Auto)
        foreign.push_back("--current-source applies to raw and CSV logs only");
    std::unique_ptr<SampleReader> reader;
    switch (format) {
        case LogFormat::RawPbms: reader = open_raw_pbms(path, options); break;
        case LogFormat::Csv: reader = open_csv(path, options); break;
        case LogFormat::DataflashText: reader = open_dataflash_text(path, options); break;
        case LogFormat::DataflashBinary: reader = open_dataflash_binary(path, options); break;
        case LogFormat::Ulog: reader = open_ulog(path, options); break;
        case LogFormat::Auto: throw InputError(path, 0, 0, "cannot detect the log format");
    }
    if (foreign.empty()) return reader;
    // Said, not refused: a manifest's defaults for a fleet's CSV logs reach its .bin logs too,
    // and no entry can unset them.
    std::string what;
    for (const std::string& f : foreign) what += (what.empty() ? "" : "; ") + f;
    return std::unique_ptr<SampleReader>(new NotedReader(
        std::move(reader), what + ", and this log reads as " + to_string(format) +
                               ": ignored (if the log is of another format, give it: --format, in batch --log-format or "
                               "a manifest's \"format\")"));
}

}  // namespace

std::unique_ptr<SampleReader> open_reader(const std::string& path, const ReaderOptions& options) {
    std::unique_ptr<SampleReader> reader = open_format(path, options);
    if (options.ignore_temperature) reader = std::unique_ptr<SampleReader>(new NoTemperatureReader(std::move(reader)));
    if (options.clock_step_capacity_ah > 0.0)
        reader = std::unique_ptr<SampleReader>(new ClockStepReader(std::move(reader), options.clock_step_capacity_ah));
    if (options.average_us == 0) return reader;
    return std::unique_ptr<SampleReader>(new AveragingReader(std::move(reader), options.average_us));
}

}  // namespace host
}  // namespace battsim
