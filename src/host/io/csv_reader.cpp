// CSV-family readers. Rules for bad input (every one has a unit test in
// tests/unit/test_io_csv.cpp):
//  * wrong field count, a field that is not a number, NaN/inf, a negative time or a time
//    earlier than the row before: InputError with line and field number;
//  * NaN/inf or an empty field in the temperature column (a sensor's dropout): that sample
//    has no temperature, with a note counting such rows;
//  * the last line of the file, when it has no newline and is visibly cut off (fewer
//    fields, or its last field does not parse, or it lacks the trailing comma every
//    earlier row had): skipped, with a note in SourceInfo::notes;
//  * repeated time stamps and blank lines: kept / skipped, one note each with a count
//    (added when the reader reaches the end of the file);
//  * no data rows at all: InputError when the reader is opened.
#include "host/io/csv_reader.h"

#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>

#include "core/sensor.h"
#include "host/io/line_reader.h"

namespace battsim {
namespace host {

namespace text {

NumberStatus parse_number(std::string_view field, double& out) {
    if (field.empty()) return NumberStatus::Empty;
    const char* b = field.data();
    const char* e = b + field.size();
    if (*b == '+') {
        ++b;
        if (b == e || *b == '+' || *b == '-') return NumberStatus::NotANumber;
    }
    double v = 0.0;
    const std::from_chars_result r = std::from_chars(b, e, v, std::chars_format::general);
    if (r.ec == std::errc::invalid_argument || r.ptr != e) return NumberStatus::NotANumber;
    if (r.ec == std::errc::result_out_of_range) return NumberStatus::OutOfRange;
    if (!std::isfinite(v)) return NumberStatus::NotFinite;
    out = v;
    return NumberStatus::Ok;
}

namespace {
inline std::string_view trim(std::string_view s) {
    std::size_t b = 0;
    std::size_t e = s.size();
    while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
    while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
    return s.substr(b, e - b);
}
}  // namespace

bool split_fields(std::string_view line, std::vector<std::string_view>& fields, long& bad_field) {
    fields.clear();
    const std::size_t n = line.size();
    const char* data = line.data();
    if (n == 0 || std::memchr(data, '"', n) == nullptr) {
        // Fast path: no quotes anywhere on the line.
        std::size_t start = 0;
        for (;;) {
            const void* hit = start < n ? std::memchr(data + start, ',', n - start) : nullptr;
            const std::size_t stop = hit ? static_cast<std::size_t>(static_cast<const char*>(hit) - data) : n;
            fields.push_back(trim(line.substr(start, stop - start)));
            if (hit == nullptr) return true;
            start = stop + 1;
        }
    }
    std::size_t i = 0;
    for (;;) {
        while (i < n && (line[i] == ' ' || line[i] == '\t')) ++i;
        if (i < n && line[i] == '"') {
            const std::size_t open = i + 1;
            std::size_t j = open;
            for (;;) {
                if (j >= n) {
                    bad_field = static_cast<long>(fields.size()) + 1;
                    return false;
                }
                if (line[j] == '"') {
                    if (j + 1 < n && line[j + 1] == '"') {
                        j += 2;
                        continue;
                    }
                    break;
                }
                ++j;
            }
            fields.push_back(line.substr(open, j - open));
            i = j + 1;
            while (i < n && (line[i] == ' ' || line[i] == '\t')) ++i;
            if (i == n) return true;
            if (line[i] != ',') {
                bad_field = static_cast<long>(fields.size());
                return false;
            }
            ++i;
            if (i == n) {
                fields.push_back(std::string_view());
                return true;
            }
            continue;
        }
        const std::size_t comma = line.find(',', i);
        const std::size_t stop = comma == std::string_view::npos ? n : comma;
        fields.push_back(trim(line.substr(i, stop - i)));
        if (comma == std::string_view::npos) return true;
        i = stop + 1;
        if (i == n) {
            fields.push_back(std::string_view());
            return true;
        }
    }
}

long field_at(std::string_view line, std::size_t pos) {
    long field = 1;
    bool quoted = false;
    for (std::size_t i = 0; i < pos && i < line.size(); ++i) {
        if (line[i] == '"') quoted = !quoted;
        else if (line[i] == ',' && !quoted) ++field;
    }
    return field;
}

std::string unquote(std::string_view field) {
    std::string s;
    s.reserve(field.size());
    for (std::size_t i = 0; i < field.size(); ++i) {
        s += field[i];
        if (field[i] == '"' && i + 1 < field.size() && field[i + 1] == '"') ++i;
    }
    return s;
}

std::string quote_for_message(std::string_view t) {
    constexpr std::size_t kMax = 60;
    std::string s = "\"";
    const std::size_t shown = std::min(t.size(), kMax);
    for (std::size_t i = 0; i < shown; ++i) {
        const unsigned char c = static_cast<unsigned char>(t[i]);
        if (c == '"' || c == '\\') {
            s += '\\';
            s += static_cast<char>(c);
        } else if (c == '\r') {
            s += "\\r";
        } else if (c == '\t') {
            s += "\\t";
        } else if (c < 0x20 || c >= 0x7F) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02X", c);
            s += hex;
        } else {
            s += static_cast<char>(c);
        }
    }
    if (t.size() > kMax) s += "...";
    s += '"';
    return s;
}

std::string number_error_message(NumberStatus status, std::string_view t) {
    switch (status) {
        case NumberStatus::NotFinite:
            return "expected a finite number, found " + quote_for_message(t);
        case NumberStatus::OutOfRange:
            return "expected a number within range, found " + quote_for_message(t);
        case NumberStatus::Ok:
        case NumberStatus::Empty:
        case NumberStatus::NotANumber:
            break;
    }
    return "expected a number, found " + quote_for_message(t);
}

}  // namespace text

namespace {

using text::NumberStatus;

// Largest time we accept, in microseconds (just under 2^63).
constexpr double kMaxTimeUs = 9.2e18;

std::string seconds_text(std::uint64_t us) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%llu.%06llu s", static_cast<unsigned long long>(us / 1000000u),
                  static_cast<unsigned long long>(us % 1000000u));
    return buf;
}

std::string number_text(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

std::string lower(std::string_view s) {
    std::string r(s);
    for (char& c : r) {
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    }
    return r;
}

bool ends_with(const std::string& s, const char* suffix) {
    const std::size_t n = std::strlen(suffix);
    return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

// A lower-case column name carries `unit` as a suffix "_unit" or in parentheses at its end,
// "name(unit)" or "name (unit)", as radio and blackbox_decode logs write them.
bool has_unit(const std::string& name, const char* unit) {
    return ends_with(name, (std::string("_") + unit).c_str()) || ends_with(name, (std::string("(") + unit + ")").c_str());
}

// Days since 1970-01-01 of a proleptic Gregorian date (counting 400-year eras of 146097
// days from 0000-03-01, so the leap day falls at the end of each shifted year).
long long days_from_civil(long long y, unsigned m, unsigned d) {
    y -= m <= 2 ? 1 : 0;
    const long long era = (y >= 0 ? y : y - 399) / 400;
    const unsigned yoe = static_cast<unsigned>(y - era * 400);               // 0..399
    const unsigned doy = (153 * (m > 2 ? m - 3 : m + 9) + 2) / 5 + d - 1;   // 0..365
    const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;              // 0..146096
    return era * 146097 + static_cast<long long>(doe) - 719468;
}

// Parses exactly `n` decimal digits at s[pos..] into v; false if any is not a digit.
bool digits(std::string_view s, std::size_t pos, std::size_t n, unsigned& v) {
    if (pos + n > s.size()) return false;
    v = 0;
    for (std::size_t i = pos; i < pos + n; ++i) {
        if (s[i] < '0' || s[i] > '9') return false;
        v = v * 10 + static_cast<unsigned>(s[i] - '0');
    }
    return true;
}

// "YYYY-MM-DD" → days since 1970-01-01; false if malformed or not a calendar date.
bool parse_date_days(std::string_view s, long long& days) {
    unsigned y = 0, m = 0, d = 0;
    if (s.size() != 10 || s[4] != '-' || s[7] != '-' || !digits(s, 0, 4, y) || !digits(s, 5, 2, m) ||
        !digits(s, 8, 2, d) || m < 1 || m > 12 || d < 1)
        return false;
    static const unsigned kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    if (d > kDays[m - 1] + (m == 2 && leap ? 1u : 0u)) return false;
    days = days_from_civil(y, m, d);
    return true;
}

// "HH:MM:SS" with an optional fraction of 1–6 digits → microseconds since midnight.
bool parse_clock_us(std::string_view s, std::uint64_t& us) {
    unsigned h = 0, mi = 0, se = 0;
    if (s.size() < 8 || s[2] != ':' || s[5] != ':' || !digits(s, 0, 2, h) || !digits(s, 3, 2, mi) ||
        !digits(s, 6, 2, se) || h > 23 || mi > 59 || se > 60)
        return false;
    std::uint64_t frac_us = 0;
    if (s.size() > 8) {
        const std::size_t n = s.size() - 9;
        unsigned f = 0;
        if (s[8] != '.' || n < 1 || n > 6 || !digits(s, 9, n, f)) return false;
        frac_us = f;
        for (std::size_t k = n; k < 6; ++k) frac_us *= 10;
    }
    us = ((static_cast<std::uint64_t>(h) * 60 + mi) * 60 + se) * 1000000u + frac_us;
    return true;
}

// Shared line loop of both CSV readers: blank lines, field count, trailing comma,
// cut-off last line, time order and the notes.
// Every reading of two samples alike (the time aside).
bool same_readings(const core::Sample& a, const core::Sample& b) {
    if (a.voltage_v != b.voltage_v || a.current_a != b.current_a || a.cell_count != b.cell_count ||
        a.has_temperature != b.has_temperature || (a.has_temperature && a.temperature_c != b.temperature_c))
        return false;
    for (int c = 0; c < a.cell_count && c < core::kMaxCells; ++c)
        if (a.cell_voltage_v[c] != b.cell_voltage_v[c]) return false;
    return true;
}

class TextSampleReader : public SampleReader {
public:
    const SourceInfo& info() const override { return info_; }

    bool next(core::Sample& out) override {
        if (has_pending_) {
            out = pending_;
            has_pending_ = false;
            return true;
        }
        if (failed_) throw *failed_;  // a reader that threw stays failed: no rows past a bad one
        if (finished_) return false;
        try {
            if (read_row(out)) return true;
        } catch (const InputError& e) {
            failed_.reset(new InputError(e));
            throw;
        }
        // A clock that does not move: most rows at the time stamp of the row before (a frozen
        // logger clock, or another column taken for time) had replayed 3802 samples as "0.3 s,
        // no flight", exit 0. A few shared stamps are kept (a note says how many).
        if (rows_ >= 20 && dup_count_ * 2 > rows_) {
            failed_.reset(new InputError(info_.path, first_dup_line_, 0,
                                         "the time does not advance: " + std::to_string(dup_count_) + " of " +
                                             std::to_string(rows_) +
                                             " rows repeat the time stamp of the row before (the first here): a frozen "
                                             "clock, stamps coarser than the rows (whole seconds at several rows a "
                                             "second), or not the time column"));
            throw *failed_;
        }
        finish();
        return false;
    }

protected:
    TextSampleReader(const std::string& path, LogFormat format) : lines_(path) {
        info_.path = path;
        info_.format = format;
    }

    // Reads the first data row, so a file without data fails when it is opened.
    // only_skipped: the message goes on to say what the file held instead (a raw log, which
    // has no header line: every line was blank or a comment).
    void prime(const std::string& no_data_message, bool only_skipped = false) {
        has_pending_ = read_row(pending_);
        if (!has_pending_) {
            if (cut_line_ > 0) {
                throw InputError(info_.path, cut_line_, 0,
                                 "no complete data rows: the only data line is cut off (" + cut_reason_ + ")");
            }
            throw InputError(info_.path, 0, 0,
                             lines_.line_number() == 0 ? "file is empty"
                             : only_skipped ? no_data_message + " (the file holds only " + only_skipped_text() + ")"
                                            : no_data_message + no_rows_detail());
        }
    }
    // Why the rows there are gave no sample (appended to "no data rows..."); "" if none were skipped.
    virtual std::string no_rows_detail() const { return ""; }

    // What a file without a header or data row holds: "blank lines", "comment lines ('#')".
    std::string only_skipped_text() const {
        return comment_count_ == 0  ? std::string("blank lines")
               : blank_count_ == 0 ? std::string("comment lines ('#')")
                                   : std::string("comment lines ('#') and blank lines");
    }

    // Next line that is neither blank nor a comment ('#' first); false at the end of the file.
    bool next_nonblank(std::string_view& line) {
        for (;;) {
            if (!lines_.next(line)) return false;
            std::size_t i = 0;
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
            // "#," is a header or row whose first field is "#" (an index column), not a comment.
            if (i < line.size() && (line[i] != '#' || (i + 1 < line.size() && line[i + 1] == ','))) return true;
            if (i < line.size()) {
                // A comment: a lab rig's preamble (pack, date, settings) or a note between runs.
                if (comment_count_ == 0) first_comment_line_ = lines_.line_number();
                ++comment_count_;
                continue;
            }
            if (blank_count_ == 0) first_blank_line_ = lines_.line_number();
            ++blank_count_;
        }
    }

    // What parse_row made of a row: a sample (its time set), a cut-off last line (after
    // get_number/get_time_us returned false: reading ends), or a row the reader leaves out
    // on purpose and counts itself (reading goes on).
    enum class Row { Kept, CutOff, Skipped };
    // Parses fields_ (count already checked) into `out`.
    virtual Row parse_row(core::Sample& out) = 0;
    // Notes only the derived reader can give, added when the end of the file is reached.
    virtual void finish_notes() {}

    // Field `idx` (0-based) as a number. Throws InputError for a bad field, except for the
    // last field of a last line without newline, which returns false (cut off).
    bool get_number(std::size_t idx, double& v) {
        const std::string_view t = fields_[idx];
        const NumberStatus st = text::parse_number(t, v);
        if (st == NumberStatus::Ok) return true;
        if (idx + 1 == cut_field_ && (st == NumberStatus::NotANumber || st == NumberStatus::Empty)) {
            add_cut_note("its last field " + text::quote_for_message(t) + " is incomplete");
            return false;
        }
        throw InputError(info_.path, lines_.line_number(), static_cast<long>(idx) + 1,
                         text::number_error_message(st, t));
    }

    float to_float(double v, std::size_t idx) const {
        if (!(std::fabs(v) <= static_cast<double>(FLT_MAX))) {
            throw InputError(info_.path, lines_.line_number(), static_cast<long>(idx) + 1,
                             "expected a number that fits a 32-bit float, found " +
                                 text::quote_for_message(fields_[idx]));
        }
        return static_cast<float>(v);
    }

    // Field `idx` as a time: value * factor_us microseconds. When factor_int > 0 the factor is
    // that exact integer and plain integer fields are converted exactly.
    bool get_time_us(std::size_t idx, double factor_us, std::uint64_t factor_int, std::uint64_t& out) {
        const std::string_view t = fields_[idx];
        if (factor_int > 0 && !t.empty() && t.size() <= 19 && t.front() >= '0' && t.front() <= '9') {
            std::uint64_t n = 0;
            const auto r = std::from_chars(t.data(), t.data() + t.size(), n);
            if (r.ec == std::errc() && r.ptr == t.data() + t.size()) {
                if (n <= static_cast<std::uint64_t>(kMaxTimeUs) / factor_int) {
                    out = n * factor_int;
                    return true;
                }
                throw InputError(info_.path, lines_.line_number(), static_cast<long>(idx) + 1,
                                 "expected a time below 2^63 microseconds, found " + text::quote_for_message(t));
            }
        }
        double v = 0.0;
        if (!get_number(idx, v)) return false;
        if (v < 0.0) {
            throw InputError(info_.path, lines_.line_number(), static_cast<long>(idx) + 1,
                             "expected a time that is not negative, found " + text::quote_for_message(t));
        }
        const double us = v * factor_us;
        if (!(us < kMaxTimeUs)) {
            throw InputError(info_.path, lines_.line_number(), static_cast<long>(idx) + 1,
                             "expected a time below 2^63 microseconds, found " + text::quote_for_message(t));
        }
        out = static_cast<std::uint64_t>(std::llround(us));
        return true;
    }

    LineReader lines_;
    SourceInfo info_;
    std::vector<std::string_view> fields_;
    std::size_t expected_fields_ = 0;  // without a trailing comma
    std::string count_text_;           // "8 fields (...)" for the wrong-count message
    std::size_t time_field_ = 0;
    std::size_t cut_field_ = 0;  // 1-based field whose failure means "cut off"; 0 = none
    long cut_line_ = 0;
    std::string cut_reason_ = "no newline at the end";  // why line cut_line_ is cut off

    void add_cut_note(const std::string& why) {
        cut_line_ = lines_.line_number();
        info_.notes.push_back("line " + std::to_string(cut_line_) +
                              ": last line is cut off (no newline at the end, " + why + "); skipped");
    }

private:
    // Digits after the decimal point of a plain number ("2.350" 3, "12" 0); -1 for anything
    // else (an exponent, a word): a cut number is told by a fixed format's lost decimals.
    static int decimals_of(std::string_view t) {
        const std::size_t dot = t.find('.');
        if (t.find_first_of("eEnN") != std::string_view::npos) return -1;
        if (dot == std::string_view::npos) return 0;
        std::size_t end = t.find_last_not_of(" \t\r");
        return end == std::string_view::npos || end < dot ? 0 : static_cast<int>(end - dot);
    }

    // A NUL at byte `z` of `line`: a logger that lost power leaves its file padded with NULs
    // to the end, and the rows before them are the flight up to the loss, kept (a crash's log
    // had been refused whole, or read with the NUL run as one cut-off field). NULs with text
    // after them are damage inside the log: refused where they start.
    void end_at_nul_padding(std::string_view line, std::size_t z) {
        const long ln = lines_.line_number();
        const long field = text::field_at(line, z);
        std::uint64_t nuls = 0;
        bool padding = true;
        for (std::string_view rest = line.substr(z);;) {
            if (rest.find_first_not_of('\0') != std::string_view::npos) {
                padding = false;
                break;
            }
            nuls += rest.size();
            if (!lines_.next(rest)) break;
            ++nuls;  // the line end between two runs (a '\n' byte, or the NUL run broke a line)
        }
        if (!padding)
            throw InputError(info_.path, ln, field,
                             "a NUL byte: expected text (a CSV log holds no NUL bytes; text follows these, so they "
                             "are not the NUL padding a logger that lost power leaves at the end of its file)");
        const bool partial = line.substr(0, z).find_first_not_of(" \t") != std::string_view::npos;
        info_.notes.push_back("line " + std::to_string(ln) + ": the file ends in NUL bytes (about " + std::to_string(nuls) +
                              "), the padding a logger that lost power leaves; the rows before are kept" +
                              (partial ? ", the part of line " + std::to_string(ln) + " before them skipped" : ""));
        if (partial) {
            cut_line_ = ln;
            cut_reason_ = "NUL bytes in it, to the end of the file";
        }
    }

    bool read_row(core::Sample& out) {
        std::string_view line;
        while (next_nonblank(line)) {
            const long ln = lines_.line_number();
            if (const std::size_t z = line.find('\0'); z != std::string_view::npos) {
                end_at_nul_padding(line, z);
                return false;
            }
            const bool at_eof_no_newline = !lines_.line_had_newline();
            long bad = 0;
            if (!text::split_fields(line, fields_, bad)) {
                if (at_eof_no_newline) {
                    add_cut_note("a quoted field is not closed");
                    return false;
                }
                throw InputError(info_.path, ln, bad,
                                 "expected a closing '\"' and then a comma or the end of the line");
            }
            std::size_t n = fields_.size();
            const bool trailing = n == expected_fields_ + 1 && fields_[n - 1].empty();
            if (trailing) {
                n = expected_fields_;
            } else if (n != expected_fields_) {
                if (at_eof_no_newline && n < expected_fields_) {
                    add_cut_note("it has " + std::to_string(n) + " of " + std::to_string(expected_fields_) +
                                 " fields");
                    return false;
                }
                // The column is the first field missing or the first one too many, as a
                // manifest's CSV says it: "file:line" alone left a pipeline to count commas.
                throw InputError(info_.path, ln, static_cast<long>(std::min(n, expected_fields_)) + 1,
                                 "expected " + count_text_ + ", found " + std::to_string(fields_.size()));
            }
            if (at_eof_no_newline && !trailing && rows_ > 0 && all_trailing_) {
                add_cut_note("it lacks the trailing comma every earlier row has, so its last number may be cut off");
                return false;
            }
            const int decimals = decimals_of(fields_[n - 1]);
            if (at_eof_no_newline && !trailing && rows_ > 1 && last_decimals_ > 0 && decimals < last_decimals_) {
                add_cut_note("its last number has " + std::to_string(std::max(decimals, 0)) + " decimals where every earlier row's has " +
                             std::to_string(last_decimals_));
                return false;
            }
            cut_field_ = at_eof_no_newline && !trailing ? n : 0;
            const Row row = parse_row(out);
            if (row == Row::CutOff) return false;
            if (row == Row::Skipped) continue;
            if (!trailing) all_trailing_ = false;
            // Kept while every row writes its last number with the same decimals (a fixed format).
            last_decimals_ = rows_ == 0 || decimals == last_decimals_ ? decimals : -1;
            if (rows_ > 0) {
                if (out.time_us < last_time_us_) {
                    throw InputError(info_.path, ln, static_cast<long>(time_field_) + 1,
                                     "time goes backwards: " + seconds_text(out.time_us) + " is earlier than " +
                                         seconds_text(last_time_us_) + " on line " + std::to_string(last_time_line_));
                }
                if (out.time_us == last_time_us_ && same_readings(out, last_sample_)) {
                    // A logger that wrote a row twice measured once: read twice, each filter
                    // had taken the reading as two (every row of the bundled flight doubled
                    // moved its capacity at 20 % from 1.589 to 1.624 Ah).
                    if (repeat_count_ == 0) first_repeat_line_ = ln;
                    ++repeat_count_;
                    continue;
                }
                if (out.time_us == last_time_us_) {
                    if (dup_count_ == 0) first_dup_line_ = ln;
                    ++dup_count_;
                }
            }
            last_sample_ = out;
            last_time_us_ = out.time_us;
            last_time_line_ = ln;
            ++rows_;
            return true;
        }
        return false;
    }

    void finish() {
        finished_ = true;
        finish_notes();
        if (repeat_count_ > 0) {
            info_.notes.push_back(std::to_string(repeat_count_) +
                                  (repeat_count_ == 1 ? " row repeats" : " rows repeat") +
                                  " the row before, time and every reading (first on line " +
                                  std::to_string(first_repeat_line_) + "): read once");
        }
        if (dup_count_ > 0) {
            info_.notes.push_back(std::to_string(dup_count_) +
                                  (dup_count_ == 1 ? " row repeats" : " rows repeat") +
                                  " the time stamp of the row before (first on line " +
                                  std::to_string(first_dup_line_) + "); kept");
        }
        if (blank_count_ > 0) {
            info_.notes.push_back(std::to_string(blank_count_) + (blank_count_ == 1 ? " blank line" : " blank lines") +
                                  " skipped (first on line " + std::to_string(first_blank_line_) + ")");
        }
        if (comment_count_ > 0) {
            info_.notes.push_back(std::to_string(comment_count_) +
                                  (comment_count_ == 1 ? " comment line" : " comment lines") +
                                  " (starting with '#') skipped (first on line " + std::to_string(first_comment_line_) + ")");
        }
    }

    core::Sample pending_;
    std::unique_ptr<InputError> failed_;
    bool has_pending_ = false;
    bool finished_ = false;
    bool all_trailing_ = true;
    int last_decimals_ = -1;  // decimals of every row's last number so far; -1 when they differ
    long rows_ = 0;
    std::uint64_t last_time_us_ = 0;
    core::Sample last_sample_;
    long repeat_count_ = 0;
    long first_repeat_line_ = 0;
    long last_time_line_ = 0;
    long dup_count_ = 0;
    long first_dup_line_ = 0;
    long blank_count_ = 0;
    long first_blank_line_ = 0;
    long comment_count_ = 0;
    long first_comment_line_ = 0;
};

// ---------------------------------------------------------------------------------------
// predictive-bms raw log

class RawPbmsReader final : public TextSampleReader {
public:
    RawPbmsReader(const std::string& path, const ReaderOptions& options)
        : TextSampleReader(path, LogFormat::RawPbms),
          use_shunt_(options.current_source == CurrentSource::Shunt),
          cal_(options.shunt) {
        if (use_shunt_ && !(std::isfinite(cal_.scale_mv_per_10a) && cal_.scale_mv_per_10a != 0.0f &&
                            std::isfinite(cal_.offset_ma))) {
            throw InputError(path, 0, 0, "shunt calibration needs a finite, non-zero scale and a finite offset");
        }
        expected_fields_ = kFields;
        count_text_ = "8 fields (9 with a trailing comma): time_ms, bus_voltage_v, cell1_v..cell4_v, current_ma, shunt_mv";
        time_field_ = 0;
        info_.cell_count = 4;
        info_.has_temperature = false;
        prime("no data rows", true);
    }

private:
    static constexpr std::size_t kFields = 8;

    Row parse_row(core::Sample& out) override {
        out = core::Sample{};
        if (!get_time_us(0, 1000.0, 1000u, out.time_us)) return Row::CutOff;
        double v[kFields];
        for (std::size_t i = 1; i < kFields; ++i) {
            if (!get_number(i, v[i])) return Row::CutOff;
        }
        out.voltage_v = to_float(v[1], 1);
        out.cell_count = 4;
        for (int c = 0; c < 4; ++c) out.cell_voltage_v[c] = to_float(v[2 + c], 2 + static_cast<std::size_t>(c));
        const float current_ma = to_float(v[6], 6);  // range-checked even when the shunt is used
        const float shunt_mv = to_float(v[7], 7);
        if (use_shunt_) {
            const float ma = core::current_ma_from_shunt_mv(shunt_mv, cal_);
            if (!std::isfinite(ma)) {
                throw InputError(info_.path, lines_.line_number(), 8,
                                 "shunt voltage " + text::quote_for_message(fields_[7]) +
                                     " gives a current out of range");
            }
            out.current_a = ma / 1000.0f;
        } else {
            (void)current_ma;
            out.current_a = static_cast<float>(v[6] / 1000.0);
        }
        return Row::Kept;
    }

    bool use_shunt_;
    core::ShuntCalibration cal_;
};

// ---------------------------------------------------------------------------------------
// Headered CSV

class HeaderedCsvReader final : public TextSampleReader {
public:
    HeaderedCsvReader(const std::string& path, const ReaderOptions& options)
        : TextSampleReader(path, LogFormat::Csv) {
        std::string_view line;
        const bool any = next_nonblank(line);
        if (!any) {
            throw InputError(path, 0, 0,
                             lines_.line_number() == 0 ? "file is empty"
                                                       : "file holds only " + only_skipped_text() + "; expected a header row");
        }
        header_line_ = lines_.line_number();
        if (line.find('\r') != std::string_view::npos) {
            throw InputError(path, header_line_, 0,
                             "the header contains a bare carriage return; expected \"\\n\" or \"\\r\\n\" line ends");
        }
        long bad = 0;
        if (!text::split_fields(line, fields_, bad)) {
            throw InputError(path, header_line_, bad, "expected a closing '\"' and then a comma or the end of the line");
        }
        for (std::string_view f : fields_) names_.push_back(text::unquote(f));
        for (std::string& n : names_) {
            // Quoted names may carry inner spaces; trim them too.
            const std::size_t b = n.find_first_not_of(" \t");
            const std::size_t e = n.find_last_not_of(" \t");
            n = b == std::string::npos ? std::string() : n.substr(b, e - b + 1);
        }
        if (names_.size() > 1 && names_.back().empty()) names_.pop_back();  // header with a trailing comma
        for (const std::string& n : names_) lower_names_.push_back(lower(n));
        expected_fields_ = names_.size();
        count_text_ = std::to_string(expected_fields_) + " fields (as in the header on line " +
                      std::to_string(header_line_) + ")";

        resolve(options);
        time_field_ = static_cast<std::size_t>(time_col_);
        prime("no data rows after the header on line " + std::to_string(header_line_));
    }

private:
    // Index of the column named `name` (case-insensitive), -1 if absent; throws if it
    // appears twice.
    int find(const std::string& name) const {
        const std::string want = lower(name);
        int found = -1;
        for (std::size_t i = 0; i < lower_names_.size(); ++i) {
            if (lower_names_[i] != want) continue;
            if (found >= 0) {
                throw InputError(info_.path, header_line_, static_cast<long>(i) + 1,
                                 "column \"" + name + "\" appears twice in the header (fields " +
                                     std::to_string(found + 1) + " and " + std::to_string(i + 1) +
                                     "); expected unique column names");
            }
            found = static_cast<int>(i);
        }
        return found;
    }

    std::string columns_found() const {
        std::string s;
        const std::size_t shown = std::min<std::size_t>(names_.size(), 60);
        for (std::size_t i = 0; i < shown; ++i) {
            if (i > 0) s += ", ";
            // A name with bytes a terminal would act on is quoted with them escaped.
            const std::string& n = names_[i];
            const bool plain = std::all_of(n.begin(), n.end(), [](char c) { return c >= 0x20 && c < 0x7F; });
            s += n.empty() ? std::string("(empty)") : plain ? n : text::quote_for_message(n);
        }
        if (names_.size() > shown) s += ", ... (" + std::to_string(names_.size()) + " in all)";
        bool all_numbers = true;
        for (const std::string& n : names_) {
            double d = 0.0;
            if (text::parse_number(n, d) == NumberStatus::Ok) continue;
            if (!(n.empty() && &n == &names_.back())) all_numbers = false;
        }
        if (all_numbers) s += " (the first line looks like data, not a header row)";
        // A spreadsheet's export in a locale that writes decimal commas separates with ';'.
        if (names_.size() == 1 && names_[0].find_first_of(";\t") != std::string::npos)
            s += " (one column: the header is separated by ';' or tabs, and battsim reads comma-separated CSV; "
                 "convert the separators, and decimal commas to points, first)";
        return s;
    }

    [[noreturn]] void missing(const std::string& what, const std::string& expected) const {
        throw InputError(info_.path, header_line_, 0,
                         "missing " + what + " column " + expected + "; columns found: " + columns_found());
    }

    int require(const std::string& what, const std::string& name) const {
        const int i = find(name);
        if (i < 0) missing(what, "\"" + name + "\"");
        return i;
    }

    // The column among the default `names` of one quantity, -1 if none. Two of them in one
    // header (time_s and time_ms) would silently give one reading or the other: refused,
    // saying which option picks one.
    int find_one_of(std::initializer_list<const char*> names, const std::string& what, const std::string& option,
                    const std::string& manifest_key) const {
        int found = -1;
        for (const char* n : names) {
            const int i = find(n);
            if (i < 0) continue;
            if (found >= 0) {
                const int first = std::min(found, i), second = std::max(found, i);
                throw InputError(info_.path, header_line_, second + 1,
                                 "columns \"" + names_[static_cast<std::size_t>(first)] + "\" (field " +
                                     std::to_string(first + 1) + ") and \"" + names_[static_cast<std::size_t>(second)] +
                                     "\" (field " + std::to_string(second + 1) + ") both give the " + what +
                                     "; expected one, or choose it with " + option + " NAME (in a manifest, " +
                                     manifest_key + ")");
            }
            found = i;
        }
        return found;
    }

    // The first column (case-insensitive) whose name starts with one of `prefixes`, in the
    // order given; -1 if none.
    int find_prefixed(std::initializer_list<const char*> prefixes) const {
        for (const char* p : prefixes) {
            for (std::size_t i = 0; i < lower_names_.size(); ++i) {
                if (lower_names_[i].compare(0, std::strlen(p), p) == 0) return static_cast<int>(i);
            }
        }
        return -1;
    }

    // Logs other programs write, recognised by their column names when no column option is
    // given and the log has none of battsim's own time columns; the note says which.
    ColumnMapping recognise(const ColumnMapping& given) {
        const bool mapped = !given.time.empty() || !given.voltage.empty() || !given.current.empty() ||
                            !given.cells.empty() || !given.temperature.empty();
        if (mapped || find("time_s") >= 0 || find("time_ms") >= 0 || find("time_us") >= 0) return given;
        ColumnMapping m = given;
        const auto name = [&](int i) { return names_[static_cast<std::size_t>(i)]; };
        // EdgeTX / OpenTX radio logs: wall-clock Date and Time, the flight pack's voltage as
        // VFAS (FrSky) or RxBt (Crossfire / ExpressLRS battery sensor; on FrSky receivers RxBt
        // is the receiver's own supply, hence VFAS first), current as Curr.
        const int date = find("date");
        const int clock = find("time");
        const int volts = find_prefixed({"vfas(", "rxbt("});
        const int amps = find_prefixed({"curr("});
        // A layout that is all there but one column is said as such: the time column had been
        // called missing when a blackbox log had no current (a craft without a current sensor).
        const auto partly = [&](const char* layout, std::initializer_list<std::pair<const char*, int>> found,
                                const char* lacking) {
            std::string have;
            for (const auto& f : found) {
                if (f.second < 0) continue;
                have += (have.empty() ? "" : ", ") + std::string(f.first) + " \"" + name(f.second) + "\"";
            }
            partial_ = std::string("the columns look like ") + layout + " (" + have + ") but have no " + lacking +
                       "; battsim needs the pack's time, voltage and current, or name them with --time-col, "
                       "--voltage-col and --current-col";
        };
        if (date >= 0 && clock >= 0 && volts >= 0 && amps >= 0) {
            date_col_ = date;
            radio_log_ = true;
            m.time = name(clock);
            m.voltage = name(volts);
            m.current = name(amps);
            info_.notes.push_back("columns read as an EdgeTX/OpenTX radio log: time from \"" + name(date) + "\" and \"" +
                                  name(clock) + "\", voltage \"" + m.voltage + "\", current \"" + m.current +
                                  "\"; rows without battery telemetry (empty or 0 V) are skipped");
            return m;
        }
        if (partial_.empty() && date >= 0 && clock >= 0 && (volts >= 0) != (amps >= 0))
            partly("an EdgeTX/OpenTX radio log", {{"time", clock}, {"voltage", volts}, {"current", amps}},
                   volts < 0 ? "voltage column (VFAS or RxBt)" : "current column (Curr)");
        // Betaflight / INAV blackbox logs decoded by blackbox_decode.
        const int bb_time = find("time (us)");
        const int bb_volts = find_prefixed({"vbatlatest"});
        const int bb_amps = find_prefixed({"amperagelatest"});
        if (bb_time >= 0 && bb_volts >= 0 && bb_amps >= 0) {
            m.time = name(bb_time);
            m.voltage = name(bb_volts);
            m.current = name(bb_amps);
            info_.notes.push_back("columns read as a blackbox_decode log: time \"" + m.time + "\", voltage \"" +
                                  m.voltage + "\", current \"" + m.current + "\"");
            return m;
        }
        if (partial_.empty() && bb_time >= 0 && (bb_volts >= 0) != (bb_amps >= 0))
            partly("a blackbox_decode log", {{"time", bb_time}, {"voltage", bb_volts}, {"current", bb_amps}},
                   bb_volts < 0 ? "voltage column (vbatLatest)"
                                 : "current column (amperageLatest; a craft without a current sensor logs none, and "
                                   "no monitor can weigh a pack without its current)");
        // The CMU Matrice 100 delivery flights (seconds, volts, amps).
        const int m100_time = find("time");
        const int m100_volts = find("battery_voltage");
        const int m100_amps = find("battery_current");
        if (m100_time >= 0 && m100_volts >= 0 && m100_amps >= 0) {
            m.time = name(m100_time);
            m.time_scale_to_s = 1.0;
            m.voltage = name(m100_volts);
            m.current = name(m100_amps);
            m.current_scale_to_a = 1.0;
            info_.notes.push_back("columns read as a DJI Matrice 100 log (CMU): time \"" + m.time + "\" in s, voltage \"" +
                                  m.voltage + "\" in V, current \"" + m.current + "\" in A");
        } else if (partial_.empty() && m100_time >= 0 && (m100_volts >= 0) != (m100_amps >= 0)) {
            partly("a DJI Matrice 100 log (CMU)", {{"time", m100_time}, {"voltage", m100_volts}, {"current", m100_amps}},
                   m100_volts < 0 ? "voltage column (battery_voltage)" : "current column (battery_current)");
        }
        return m;
    }

    void resolve(const ReaderOptions& options) {
        const ColumnMapping m = recognise(options.columns);

        // Time.
        std::string time_name;
        if (!m.time.empty()) {
            time_col_ = require("time", m.time);
            time_name = lower_names_[static_cast<std::size_t>(time_col_)];
        } else {
            time_col_ = find_one_of({"time_s", "time_ms", "time_us"}, "time", "--time-col", "columns.time or time_col");
            if (time_col_ < 0 && !partial_.empty())
                throw InputError(info_.path, header_line_, 0, partial_ + "; columns found: " + columns_found());
            if (time_col_ < 0) missing("time", "(expected time_s, time_ms or time_us)");
            time_name = lower_names_[static_cast<std::size_t>(time_col_)];
        }
        if (date_col_ >= 0) {
            // Wall-clock time: parsed per row (parse_row).
        } else if (m.time_scale_to_s != 0.0) {
            if (!(std::isfinite(m.time_scale_to_s) && m.time_scale_to_s > 0.0)) {
                throw InputError(info_.path, 0, 0,
                                 "time scale must be a positive number of seconds per unit, got " +
                                     number_text(m.time_scale_to_s));
            }
            time_factor_us_ = m.time_scale_to_s * 1e6;
            // Whole microseconds per unit (s, ms, us): convert integer times exactly.
            const double whole = std::round(time_factor_us_);
            time_factor_int_ = 0;
            if (whole >= 1.0 && whole <= 1e12 && std::fabs(time_factor_us_ - whole) <= 1e-9 * whole)
                time_factor_int_ = static_cast<std::uint64_t>(whole);
        } else if (has_unit(time_name, "us")) {
            time_factor_us_ = 1.0;
            time_factor_int_ = 1u;
        } else if (has_unit(time_name, "ms")) {
            time_factor_us_ = 1000.0;
            time_factor_int_ = 1000u;
        } else if (has_unit(time_name, "s")) {
            time_factor_us_ = 1e6;
            time_factor_int_ = 1000000u;
        } else {
            throw InputError(info_.path, header_line_, time_col_ + 1,
                             "cannot tell the unit of time column \"" + names_[static_cast<std::size_t>(time_col_)] +
                                 "\": expected a name ending in _s, _ms or _us (or (s), (ms), (us)), or give the unit: --time-unit s, ms or us (manifest: columns.time_unit or time_unit)");
        }

        if (date_col_ < 0) {
            info_.time_scale_to_s = time_factor_us_ * 1e-6;
            info_.time_column = names_[static_cast<std::size_t>(time_col_)];
        }

        // Voltage (volts unless the name ends in _mv).
        if (!m.voltage.empty()) {
            voltage_col_ = require("voltage", m.voltage);
        } else {
            voltage_col_ = find_one_of({"voltage_v", "voltage_mv"}, "voltage", "--voltage-col",
                                       "columns.voltage or voltage_col");
            if (voltage_col_ < 0) missing("voltage", "(expected voltage_v or voltage_mv)");
        }
        voltage_scale_ = has_unit(lower_names_[static_cast<std::size_t>(voltage_col_)], "mv") ? 1e-3 : 1.0;

        // Current.
        if (options.current_source == CurrentSource::Shunt) {
            shunt_col_ = find("shunt_mv");
            if (shunt_col_ < 0) {
                throw InputError(info_.path, header_line_, 0,
                                 "current source \"shunt\" needs a shunt_mv column; columns found: " + columns_found());
            }
            cal_ = options.shunt;
            if (!(std::isfinite(cal_.scale_mv_per_10a) && cal_.scale_mv_per_10a != 0.0f &&
                  std::isfinite(cal_.offset_ma))) {
                throw InputError(info_.path, 0, 0, "shunt calibration needs a finite, non-zero scale and a finite offset");
            }
        } else {
            if (!m.current.empty()) {
                current_col_ = require("current", m.current);
            } else {
                current_col_ = find_one_of({"current_a", "current_ma"}, "current", "--current-col",
                                           "columns.current or current_col");
                if (current_col_ < 0) missing("current", "(expected current_a or current_ma)");
            }
            const std::string& cname = lower_names_[static_cast<std::size_t>(current_col_)];
            if (m.current_scale_to_a != 0.0) {
                if (!std::isfinite(m.current_scale_to_a)) {
                    throw InputError(info_.path, 0, 0, "current scale must be a finite, non-zero number of amps per unit");
                }
                current_scale_ = m.current_scale_to_a;
            } else if (has_unit(cname, "ma")) {
                current_scale_ = 1e-3;
            } else if (has_unit(cname, "a")) {
                current_scale_ = 1.0;
            } else {
                throw InputError(info_.path, header_line_, current_col_ + 1,
                                 "cannot tell the unit of current column \"" +
                                     names_[static_cast<std::size_t>(current_col_)] +
                                     "\": expected a name ending in _a or _ma (or (a), (ma)), or give the unit: --current-unit A or mA (manifest: columns.current_unit or current_unit)");
            }
            info_.current_scale_to_a = current_scale_;
            if (m.current_negative_is_discharge) current_scale_ = -current_scale_;
        }

        // Cells.
        std::vector<int> cells;
        std::vector<std::string> cell_names;
        if (!m.cells.empty()) {
            for (const std::string& c : m.cells) {
                cells.push_back(require("cell voltage", c));
                cell_names.push_back(c);
            }
        } else {
            // cell1_v, cell2_v, ... (or cellN_mv) numbered 1..N without gaps.
            std::vector<std::pair<long, int>> numbered;
            for (std::size_t i = 0; i < lower_names_.size(); ++i) {
                const std::string& n = lower_names_[i];
                const std::size_t unit = ends_with(n, "_mv") ? 3 : ends_with(n, "_v") ? 2 : 0;
                if (unit == 0 || n.size() < 5 + unit || n.compare(0, 4, "cell") != 0) continue;
                const std::string digits = n.substr(4, n.size() - 4 - unit);
                if (digits.empty() || digits.size() > 3 ||
                    digits.find_first_not_of("0123456789") != std::string::npos)
                    continue;
                numbered.emplace_back(std::stol(digits), static_cast<int>(i));
            }
            std::sort(numbered.begin(), numbered.end());
            for (std::size_t k = 0; k < numbered.size(); ++k) {
                const long want = static_cast<long>(k) + 1;
                if (k > 0 && numbered[k].first == numbered[k - 1].first) {
                    throw InputError(info_.path, header_line_, numbered[k].second + 1,
                                     "cell " + std::to_string(numbered[k].first) + " has two columns (" +
                                         names_[static_cast<std::size_t>(numbered[k - 1].second)] + ", " +
                                         names_[static_cast<std::size_t>(numbered[k].second)] +
                                         "); expected one per cell, or choose with --cell-cols");
                }
                if (numbered[k].first != want) {
                    throw InputError(info_.path, header_line_, 0,
                                     "cell voltage columns must be numbered cell1_v..cellN_v without gaps; cell" +
                                         std::to_string(want) + "_v is missing; columns found: " + columns_found());
                }
                cells.push_back(numbered[k].second);
                cell_names.push_back(names_[static_cast<std::size_t>(numbered[k].second)]);
            }
        }
        if (cells.size() > static_cast<std::size_t>(core::kMaxCells)) {
            info_.cells_beyond_kept = static_cast<int>(cells.size());
            info_.notes.push_back("columns " + cell_names[core::kMaxCells] + ".." + cell_names.back() +
                                  " dropped: at most " + std::to_string(core::kMaxCells) +
                                  " cell voltages are supported");
            cells.resize(core::kMaxCells);
        }
        for (int c : cells) {
            cell_cols_.push_back(c);
            cell_scales_.push_back(has_unit(lower_names_[static_cast<std::size_t>(c)], "mv") ? 1e-3 : 1.0);
        }
        info_.cell_count = static_cast<int>(cell_cols_.size());

        // Temperature (optional unless named explicitly).
        temp_col_ = m.temperature.empty() ? find("temperature_c") : require("temperature", m.temperature);
        info_.has_temperature = temp_col_ >= 0;
        // A column named in kelvin ("Temperature (K)", "temp_k") is read so: it had been taken
        // as degrees Celsius and only the "in kelvin?" note asked for 273.15 off.
        if (temp_col_ >= 0 && has_unit(lower_names_[static_cast<std::size_t>(temp_col_)], "k")) {
            temperature_offset_c_ = -273.15;
            info_.notes.push_back("the temperature column \"" + names_[static_cast<std::size_t>(temp_col_)] +
                                  "\" is read in kelvin, as its name says, and converted to degrees Celsius");
        }
    }

    // A radio log's row before the receiver sends battery telemetry, or after it is lost;
    // counted for the note at the end.
    bool no_battery_telemetry() {
        const std::string_view v = fields_[static_cast<std::size_t>(voltage_col_)];
        const std::string_view a = fields_[static_cast<std::size_t>(current_col_)];
        double x = 0.0;
        if (!(v.empty() || a.empty() || (text::parse_number(v, x) == NumberStatus::Ok && x == 0.0))) return false;
        if (skipped_rows_++ == 0) first_skipped_line_ = lines_.line_number();
        return true;
    }

    // Date and Time fields → microseconds since midnight of the first row's date.
    bool get_clock_time_us(std::uint64_t& out) {
        const std::size_t dc = static_cast<std::size_t>(date_col_);
        const std::size_t tc = static_cast<std::size_t>(time_col_);
        long long days = 0;
        std::uint64_t clock_us = 0;
        if (!parse_date_days(fields_[dc], days)) {
            if (dc + 1 == cut_field_) {
                add_cut_note("its date " + text::quote_for_message(fields_[dc]) + " is incomplete");
                return false;
            }
            throw InputError(info_.path, lines_.line_number(), static_cast<long>(dc) + 1,
                             "expected a date as YYYY-MM-DD, found " + text::quote_for_message(fields_[dc]));
        }
        if (!parse_clock_us(fields_[tc], clock_us)) {
            if (tc + 1 == cut_field_) {
                add_cut_note("its time " + text::quote_for_message(fields_[tc]) + " is incomplete");
                return false;
            }
            throw InputError(info_.path, lines_.line_number(), static_cast<long>(tc) + 1,
                             "expected a time of day as HH:MM:SS or HH:MM:SS.fff, found " +
                                 text::quote_for_message(fields_[tc]));
        }
        if (!have_first_day_) {
            first_day_ = days;
            have_first_day_ = true;
        }
        if (days < first_day_) {
            throw InputError(info_.path, lines_.line_number(), static_cast<long>(dc) + 1,
                             "time goes backwards: date " + text::quote_for_message(fields_[dc]) +
                                 " is earlier than the first row's");
        }
        out = static_cast<std::uint64_t>(days - first_day_) * 86400000000ull + clock_us;
        return true;
    }

    Row parse_row(core::Sample& out) override {
        out = core::Sample{};
        if (radio_log_ && no_battery_telemetry()) return Row::Skipped;
        if (date_col_ >= 0) {
            if (!get_clock_time_us(out.time_us)) return Row::CutOff;
        } else if (!get_time_us(static_cast<std::size_t>(time_col_), time_factor_us_, time_factor_int_, out.time_us)) {
            return Row::CutOff;
        }
        double v = 0.0;
        const std::size_t vc = static_cast<std::size_t>(voltage_col_);
        if (!get_number(vc, v)) return Row::CutOff;
        out.voltage_v = to_float(v * voltage_scale_, vc);
        if (shunt_col_ >= 0) {
            const std::size_t sc = static_cast<std::size_t>(shunt_col_);
            if (!get_number(sc, v)) return Row::CutOff;
            const float ma = core::current_ma_from_shunt_mv(to_float(v, sc), cal_);
            if (!std::isfinite(ma)) {
                throw InputError(info_.path, lines_.line_number(), shunt_col_ + 1,
                                 "shunt voltage " + text::quote_for_message(fields_[sc]) +
                                     " gives a current out of range");
            }
            out.current_a = ma / 1000.0f;
        } else {
            const std::size_t cc = static_cast<std::size_t>(current_col_);
            if (!get_number(cc, v)) return Row::CutOff;
            out.current_a = to_float(v * current_scale_, cc);
        }
        out.cell_count = static_cast<std::uint8_t>(cell_cols_.size());
        for (std::size_t k = 0; k < cell_cols_.size(); ++k) {
            const std::size_t c = static_cast<std::size_t>(cell_cols_[k]);
            if (!get_number(c, v)) return Row::CutOff;
            out.cell_voltage_v[k] = to_float(v * cell_scales_[k], c);
        }
        if (temp_col_ >= 0) {
            const std::size_t tc = static_cast<std::size_t>(temp_col_);
            const NumberStatus st = text::parse_number(fields_[tc], v);
            // A temperature sensor's dropout ("nan", "inf", an empty field) loses that sample's
            // temperature, not the flight: the sample goes on without one, as a ULog's NaN
            // temperature does, and the monitor's model holds or models it meanwhile. An
            // empty last field of a cut-off last line stays a cut (get_number below).
            const bool cut_here = tc + 1 == cut_field_ && st == NumberStatus::Empty;
            if ((st == NumberStatus::NotFinite || st == NumberStatus::Empty) && !cut_here) {
                if (no_temperature_rows_++ == 0) first_no_temperature_line_ = lines_.line_number();
            } else {
                if (!get_number(tc, v)) return Row::CutOff;
                out.temperature_c = to_float(v + temperature_offset_c_, tc);
                out.has_temperature = true;
                ++temperature_rows_;
            }
        }
        return Row::Kept;
    }

    std::string no_rows_detail() const override {
        if (skipped_rows_ == 0) return "";
        return ": all " + std::to_string(skipped_rows_) + (skipped_rows_ == 1 ? " row is" : " rows are") +
               " without battery telemetry (0 V, or an empty voltage or current; the first on line " +
               std::to_string(first_skipped_line_) + "), as a radio logs before the receiver sends the pack's readings";
    }

    void finish_notes() override {
        if (skipped_rows_ > 0) {
            info_.notes.push_back(std::to_string(skipped_rows_) + (skipped_rows_ == 1 ? " row" : " rows") +
                                  " without battery telemetry skipped (first on line " +
                                  std::to_string(first_skipped_line_) + ")");
        }
        if (no_temperature_rows_ > 0) {
            const std::string& column = names_[static_cast<std::size_t>(temp_col_)];
            info_.notes.push_back(std::to_string(no_temperature_rows_) + (no_temperature_rows_ == 1 ? " row has" : " rows have") +
                                  " no temperature (\"nan\", \"inf\" or an empty field in column " +
                                  std::to_string(temp_col_ + 1) + " \"" + column + "\", first on line " +
                                  std::to_string(first_no_temperature_line_) + "): " +
                                  (temperature_rows_ == 0 ? "read as a log without a temperature"
                                                          : "kept, without a temperature"));
            // As a ULog whose temperatures are all NaN: the summary says the log has none.
            if (temperature_rows_ == 0) info_.has_temperature = false;
        }
    }

    long header_line_ = 0;
    int date_col_ = -1;      // wall-clock logs: the Date column beside the Time column
    std::string partial_;    // a recognised layout lacking one column, said instead of "missing time column"
    bool radio_log_ = false;
    long long first_day_ = 0;
    bool have_first_day_ = false;
    long skipped_rows_ = 0;
    long first_skipped_line_ = 0;
    double temperature_offset_c_ = 0.0;  // -273.15 for a column in kelvin
    long no_temperature_rows_ = 0;  // a temperature column's dropouts (parse_row)
    long first_no_temperature_line_ = 0;
    long temperature_rows_ = 0;
    std::vector<std::string> names_;
    std::vector<std::string> lower_names_;
    int time_col_ = -1;
    double time_factor_us_ = 1e6;
    std::uint64_t time_factor_int_ = 0;
    int voltage_col_ = -1;
    double voltage_scale_ = 1.0;
    int current_col_ = -1;
    double current_scale_ = 1.0;
    int shunt_col_ = -1;
    core::ShuntCalibration cal_;
    std::vector<int> cell_cols_;
    std::vector<double> cell_scales_;
    int temp_col_ = -1;
};

}  // namespace

std::unique_ptr<SampleReader> open_raw_pbms(const std::string& path, const ReaderOptions& options) {
    return std::unique_ptr<SampleReader>(new RawPbmsReader(path, options));
}

std::unique_ptr<SampleReader> open_csv(const std::string& path, const ReaderOptions& options) {
    return std::unique_ptr<SampleReader>(new HeaderedCsvReader(path, options));
}

}  // namespace host
}  // namespace battsim
