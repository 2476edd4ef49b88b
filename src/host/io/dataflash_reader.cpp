// ArduPilot DataFlash logs: binary (.bin) and text (.log), driven by their FMT messages.
//
// Written from the DataFlash format description (ArduPilot LogStructure.h comments and the
// data README), not from any parser:
//  * Binary: every message is 0xA3 0x95 <id> <payload>. FMT (id 128, payload: Type B,
//    Length B, Name char[4], Format char[16], Columns char[64]) gives each id its name, total
//    length (3 header bytes + payload) and one format character per comma-separated column.
//    Format characters: a int16[32], b int8, B uint8, h int16, H uint16, i int32, I uint32,
//    f float, d double, n char[4], N char[16], Z char[64], c int16 x0.01, C uint16 x0.01,
//    e int32 x0.01, E uint32 x0.01, L int32 lat/lon x1e-7, M uint8 flight mode, q int64,
//    Q uint64. All little-endian, packed.
//  * Text: one message per line, "NAME, v1, v2, ...". FMT lines read
//    "FMT, id, length, NAME, format, Col1,Col2,...". Values are printed already scaled
//    (c/C/e/E/L), integer fields raw -- the same numbers the binary reader produces.
//
// Battery data (positive current = discharge):
//  * BAT (newer firmware): Volt/Curr in V/A (float or scaled types), TimeUS, Temp, optional
//    Instance/Inst field (only instance 0 is read). BAT is preferred when a log has both.
//  * CURR (older firmware): Volt/Curr logged as integers in centi-units (divided by 100);
//    TimeMS in binary logs of 3.1+, no timestamp at all in 3.0 text logs.
//    Rule used for both: an integer-typed Volt/Curr (b B h H i I q Q) is centi-units, a
//    float or an already-scaled type (c C e E) is V/A.
//  * BCL: per-cell voltages V1..V12 in mV (0 and 65535 = no cell); the latest BCL of
//    instance 0 is attached to every battery sample.
//
// Parameters: PARM (columns found by label: Name, a char field, and Value, a number; older logs
// "Nf" Name,Value, newer ones add TimeUS and Default) go to SourceInfo::parameters as the stream
// passes them, first value per name only (later rows are changes in flight). A row whose Value is
// not a finite number is skipped with a note.
//
// Time (output time stamps are non-decreasing; a row that would go backwards is dropped with a
// note):
//  1. A battery row with its own TimeUS/TimeMS uses it (boot time).
//  2. Otherwise it takes the latest time of the timed messages before it: boot time
//     (TimeUS/TimeMS of any message; in GPS messages "T") when the log has any, else GPS
//     time of week (GPS "Time"/"TimeMS"/"GMS", unwrapped across week roll-over, shifted so
//     the first sample is at 0).
//  3. Rows before the first timed message (e.g. before GPS fix), and every row of a log with no
//     time source at all, are placed at a constant spacing: the median of dCurrTot / mean(Curr)
//     over consecutive row pairs drawing >= 1 A (CurrTot is the autopilot's own mAh integral),
//     or 1 s when fewer than 5 such pairs exist. Rows before the first timed message are placed
//     before it at that spacing. Each such assumption is written to SourceInfo::notes.
//  A cheap pre-scan pass (aggregates only, memory independent of file length) finds which of
//  these applies before the streaming pass.
//
// Corrupt binary data: bytes that do not start a message are skipped up to the next 0xA3 0x95
// (noted); a message whose end is not followed by a header but that contains one is taken as
// cut short and dropped (noted); an id with no FMT is skipped the same way. An FMT whose length
// disagrees with its format, or is out of 3..255, is an InputError. A file that ends inside a
// message keeps everything before it (noted).
#include "host/io/dataflash_reader.h"
#include "host/io/dataflash_ulog_util.h"
#include "host/io/time_order.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace battsim {
namespace host {
namespace {

using logio::ByteStream;
using logio::fixed;
using logio::le;
using logio::NoteLog;
using logio::escaped_quoted;

constexpr size_t kMaxTextLine = 64 * 1024;
constexpr int kMaxFormatChars = 64;
constexpr int kMaxCellFields = 16;
constexpr double kGpsWeekMs = 604800000.0;

// ---------------------------------------------------------------------------------------------
// Format characters.
int char_size(char c) {
    switch (c) {
        case 'b': case 'B': case 'M': return 1;
        case 'h': case 'H': case 'c': case 'C': return 2;
        case 'i': case 'I': case 'f': case 'e': case 'E': case 'L': case 'n': return 4;
        case 'd': case 'q': case 'Q': return 8;
        case 'N': return 16;
        case 'Z': case 'a': return 64;
        default: return -1;
    }
}
double char_scale(char c) {
    switch (c) {
        case 'c': case 'C': case 'e': case 'E': return 0.01;
        case 'L': return 1e-7;
        default: return 1.0;
    }
}
bool char_is_number(char c) { return c != 'n' && c != 'N' && c != 'Z' && c != 'a' && char_size(c) > 0; }
bool char_is_text(char c) { return c == 'n' || c == 'N' || c == 'Z'; }
bool char_is_integer(char c) {
    switch (c) {
        case 'b': case 'B': case 'h': case 'H': case 'i': case 'I': case 'q': case 'Q': case 'M':
            return true;
        default: return false;
    }
}

enum class Role { None, Battery, Cells, Parameter };

struct DfFormat {
    bool defined = false;
    int id = -1;
    int length = 0;  // whole message including the 3 header bytes
    std::string name;
    std::string format;
    std::vector<std::string> labels;
    std::vector<int> offsets;  // payload byte offset of each column (binary)
    bool decodable = false;    // format characters known and columns match
    std::string why_not;       // when !decodable
    std::string defined_at;    // "line N" / "byte N"
    // Column indices, -1 = absent.
    int boot_time = -1;
    double boot_time_to_us = 0;
    int gps_week_ms = -1;
    Role role = Role::None;
    int volt = -1, curr = -1, curr_tot = -1, temp = -1, inst = -1;
    int cells[kMaxCellFields];
    int parm_name = -1, parm_value = -1;
    bool used() const { return role != Role::None || boot_time >= 0 || gps_week_ms >= 0; }
};

int column(const DfFormat& f, const char* label) {
    for (size_t i = 0; i < f.labels.size(); ++i)
        if (f.labels[i] == label) return static_cast<int>(i);
    return -1;
}

// Validates an FMT definition and works out which columns the reader uses. `where` is
// "line N" or "byte N"; text gives the line number for the InputError.
void complete_format(DfFormat& f, const std::string& path, long line, const std::string& where,
                     NoteLog& notes) {
    f.defined = true;
    f.defined_at = where;
    // Text errors carry the line number in InputError itself; binary ones name the byte offset.
    const std::string head =
        (line > 0 ? std::string() : where + ": ") + "FMT for type " + std::to_string(f.id) + " " + escaped_quoted(f.name);
    if (f.length < 3 || f.length > 255)
        throw InputError(path, line, 0,
                         head + " declares length " + std::to_string(f.length) +
                             "; a DataFlash message is 3..255 bytes (3-byte header + payload)");
    if (static_cast<int>(f.format.size()) > kMaxFormatChars)
        throw InputError(path, line, 0, head + " has a format string longer than " +
                                            std::to_string(kMaxFormatChars) + " characters");
    int size = 3;
    char unknown = 0;
    f.offsets.clear();
    for (char c : f.format) {
        int s = char_size(c);
        if (s < 0) {
            unknown = c;
            break;
        }
        f.offsets.push_back(size - 3);
        size += s;
    }
    f.decodable = true;
    f.why_not.clear();
    if (unknown) {
        f.decodable = false;
        f.why_not = "its format " + escaped_quoted(f.format) + " uses the unknown format character " +
                    escaped_quoted(std::string(1, unknown));
        f.offsets.clear();
    } else if (size != f.length) {
        throw InputError(path, line, 0,
                         head + " declares length " + std::to_string(f.length) + " but its format " +
                             escaped_quoted(f.format) + " needs " + std::to_string(size) +
                             " bytes (3-byte header + " + std::to_string(size - 3) + ")");
    } else if (f.labels.size() != f.format.size()) {
        f.decodable = false;
        f.why_not = "its FMT has " + std::to_string(f.labels.size()) + " column names for " +
                    std::to_string(f.format.size()) + " format characters";
    }

    f.boot_time = f.gps_week_ms = -1;
    f.role = Role::None;
    f.volt = f.curr = f.curr_tot = f.temp = f.inst = -1;
    for (int& c : f.cells) c = -1;
    f.parm_name = f.parm_value = -1;
    if (f.name == "BAT" || f.name == "CURR") f.role = Role::Battery;
    if (f.name == "BCL") f.role = Role::Cells;
    if (f.name == "PARM") f.role = Role::Parameter;
    if (!f.decodable) {
        if (f.role != Role::None)
            notes.add("fmt", where + ": " + f.name + " cannot be decoded: " + f.why_not);
        else
            notes.add("fmt", where + ": messages " + escaped_quoted(f.name) + " are skipped: " + f.why_not);
        return;
    }
    auto numeric = [&](int i) { return i >= 0 && char_is_number(f.format[static_cast<size_t>(i)]) ? i : -1; };
    const bool gps = f.name.compare(0, 3, "GPS") == 0;
    const int tus = numeric(column(f, "TimeUS"));
    const int tms = numeric(column(f, "TimeMS"));
    if (tus >= 0 && (f.format[static_cast<size_t>(tus)] == 'Q' || f.format[static_cast<size_t>(tus)] == 'q')) {
        f.boot_time = tus;
        f.boot_time_to_us = 1.0;
    } else if (tms >= 0 && !gps) {  // in old GPS messages TimeMS is GPS time of week
        f.boot_time = tms;
        f.boot_time_to_us = 1000.0;
    } else if (tus >= 0) {
        f.boot_time = tus;
        f.boot_time_to_us = 1.0;
    } else if (gps && numeric(column(f, "T")) >= 0) {
        f.boot_time = numeric(column(f, "T"));
        f.boot_time_to_us = 1000.0;
    }
    if (gps) {
        f.gps_week_ms = numeric(column(f, "GMS"));
        if (f.gps_week_ms < 0) f.gps_week_ms = tms;
        if (f.gps_week_ms < 0) f.gps_week_ms = numeric(column(f, "Time"));
    }
    if (f.role == Role::Battery) {
        f.volt = numeric(column(f, "Volt"));
        f.curr = numeric(column(f, "Curr"));
        f.curr_tot = numeric(column(f, "CurrTot"));
        f.temp = numeric(column(f, "Temp"));
        f.inst = numeric(column(f, "Instance"));
        if (f.inst < 0) f.inst = numeric(column(f, "Inst"));
        if (f.volt < 0 || f.curr < 0) {
            f.decodable = false;
            f.why_not = "its FMT has no numeric Volt and Curr columns (columns: " +
                        escaped_quoted([&] {
                            std::string s;
                            for (auto& l : f.labels) s += (s.empty() ? "" : ",") + l;
                            return s;
                        }(), 120) + ")";
        }
    } else if (f.role == Role::Cells) {
        f.inst = numeric(column(f, "Instance"));
        if (f.inst < 0) f.inst = numeric(column(f, "Inst"));
        for (int k = 0; k < kMaxCellFields; ++k) f.cells[k] = numeric(column(f, ("V" + std::to_string(k + 1)).c_str()));
    } else if (f.role == Role::Parameter) {
        const int name = column(f, "Name");
        f.parm_name = name >= 0 && char_is_text(f.format[static_cast<size_t>(name)]) ? name : -1;
        f.parm_value = numeric(column(f, "Value"));
        if (f.parm_name < 0 || f.parm_value < 0) {
            // Not fatal: parameters are extra information, the battery data does not need them.
            notes.add("fmt", where + ": PARM messages are skipped: their FMT has no text Name and numeric Value "
                                     "columns (format " + escaped_quoted(f.format) + ")");
            f.role = Role::None;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// One message's column values.
class FieldReader {
public:
    virtual ~FieldReader() = default;
    // The scaled numeric value of column i; false if it is not a readable number.
    virtual bool number(int i, double& out) const = 0;
    // The column as written, for messages.
    virtual std::string raw(int i) const = 0;
    // 1-based column (text: field number on the line), 0 for binary.
    virtual long column_of(int i) const = 0;
    // A text column (n/N/Z) as logged, without binary NUL padding or trailing spaces.
    virtual std::string text(int i) const = 0;
};

class MessageSource {
public:
    virtual ~MessageSource() = default;
    // Next message of a type the reader uses; false at the end of the file.
    virtual bool next(const DfFormat*& f, const FieldReader*& r, std::string& where, long& line) = 0;
};

// --- binary -----------------------------------------------------------------------------------

class BinaryFields final : public FieldReader {
public:
    const DfFormat* f = nullptr;
    const uint8_t* p = nullptr;  // payload
    bool number(int i, double& out) const override {
        if (i < 0 || static_cast<size_t>(i) >= f->offsets.size()) return false;
        const char c = f->format[static_cast<size_t>(i)];
        const uint8_t* q = p + f->offsets[static_cast<size_t>(i)];
        switch (c) {
            case 'b': out = static_cast<int8_t>(q[0]); break;
            case 'B': case 'M': out = q[0]; break;
            case 'h': case 'c': out = static_cast<int16_t>(le(q, 2)); break;
            case 'H': case 'C': out = static_cast<double>(le(q, 2)); break;
            case 'i': case 'e': case 'L': out = static_cast<int32_t>(le(q, 4)); break;
            case 'I': case 'E': out = static_cast<double>(le(q, 4)); break;
            case 'q': out = static_cast<double>(static_cast<int64_t>(le(q, 8))); break;
            case 'Q': out = static_cast<double>(le(q, 8)); break;
            case 'f': {
                uint32_t u = static_cast<uint32_t>(le(q, 4));
                float v;
                std::memcpy(&v, &u, 4);
                out = v;
                break;
            }
            case 'd': {
                uint64_t u = le(q, 8);
                double v;
                std::memcpy(&v, &u, 8);
                out = v;
                break;
            }
            default: return false;
        }
        out *= char_scale(c);
        return true;
    }
    std::string raw(int i) const override {
        double v;
        return number(i, v) ? fixed(v, 6) : std::string("?");
    }
    long column_of(int) const override { return 0; }
    std::string text(int i) const override {
        if (i < 0 || static_cast<size_t>(i) >= f->offsets.size()) return std::string();
        const char c = f->format[static_cast<size_t>(i)];
        if (!char_is_text(c)) return raw(i);
        const char* q = reinterpret_cast<const char*>(p + f->offsets[static_cast<size_t>(i)]);
        // The firmware pads with NULs; anything after the first NUL is not part of the name.
        size_t n = 0;
        const size_t cap = static_cast<size_t>(char_size(c));
        while (n < cap && q[n] != '\0') ++n;
        while (n > 0 && q[n - 1] == ' ') --n;
        return std::string(q, n);
    }
};

class BinarySource final : public MessageSource {
public:
    BinarySource(const std::string& path, NoteLog& notes) : path_(path), in_(path), notes_(notes) {
        size_t n = in_.ensure(3);
        if (n == 0) throw InputError(path, 0, 0, "empty file: expected a DataFlash binary log");
        const uint8_t* p = in_.data();
        if (n < 3 || p[0] != 0xA3 || p[1] != 0x95 || p[2] != 128) {
            const std::string found = logio::hex_bytes(p, std::min<size_t>(n, 3));
            throw InputError(path, 0, 0,
                             "byte 0: not a DataFlash binary log: expected an FMT message "
                             "(A3 95 80), found " + found);
        }
        DfFormat& fmt = formats_[128];
        fmt.id = 128;
        fmt.length = 89;
        fmt.name = "FMT";
        fmt.format = "BBnNZ";
        fmt.labels = {"Type", "Length", "Name", "Format", "Columns"};
        complete_format(fmt, path, 0, "built-in", notes_);
    }

    bool next(const DfFormat*& out_f, const FieldReader*& out_r, std::string& where, long& line) override {
        line = 0;
        for (;;) {
            in_.consume(pending_);
            pending_ = 0;
            size_t avail = in_.ensure(3);
            if (avail == 0) return false;
            const uint8_t* p = in_.data();
            const uint64_t off = in_.offset();
            if (avail < 2 || p[0] != 0xA3 || p[1] != 0x95) {
                uint64_t skipped = resync();
                notes_.add("resync", "byte " + std::to_string(off) + ": skipped " + std::to_string(skipped) +
                                         " bytes that do not start a DataFlash message (resynchronised on the "
                                         "next 0xA3 0x95)");
                continue;
            }
            if (avail < 3) {
                notes_.add("truncated", "byte " + std::to_string(off) + ": file ends inside a message header; " +
                                            std::to_string(avail) + " trailing bytes ignored");
                in_.consume(avail);
                return false;
            }
            const int id = p[2];
            const DfFormat& f = formats_[id];
            if (!f.defined) {
                in_.consume(2);
                uint64_t skipped = 2 + resync();
                notes_.add("unknown-id", "byte " + std::to_string(off) + ": message id " + std::to_string(id) +
                                             " has no FMT (yet); skipped " + std::to_string(skipped) +
                                             " bytes to the next 0xA3 0x95");
                continue;
            }
            const size_t len = static_cast<size_t>(f.length);
            avail = in_.ensure(len + 2);
            p = in_.data();
            if (avail < len) {
                notes_.add("truncated", "byte " + std::to_string(off) + ": file ends inside a message of type " +
                                            f.name + " (" + std::to_string(avail) + " of " + std::to_string(len) +
                                            " bytes); the partial message is ignored");
                in_.consume(avail);
                return false;
            }
            const bool framed = avail < len + 2 || (p[len] == 0xA3 && p[len + 1] == 0x95);
            if (!framed) {
                // A header inside the span means this message was cut short (bytes lost).
                size_t inner = 0;
                for (size_t k = 1; k < len; ++k)  // p has len + 2 bytes here
                    if (p[k] == 0xA3 && p[k + 1] == 0x95) {
                        inner = k;
                        break;
                    }
                if (inner) {
                    notes_.add("cut", "byte " + std::to_string(off) + ": " + f.name + " message is cut short by a "
                                          "message header at byte " + std::to_string(off + inner) + "; dropped");
                    in_.consume(inner);
                    continue;
                }
            }
            pending_ = len;
            if (id == 128) {
                define(p + 3, off, framed);
                continue;
            }
            if (!f.used()) continue;
            fields_.f = &f;
            fields_.p = p + 3;
            out_f = &f;
            out_r = &fields_;
            where = "byte " + std::to_string(off);
            return true;
        }
    }

private:
    // Skips to the next 0xA3 0x95 (or the end of the file); returns the bytes skipped.
    uint64_t resync() {
        uint64_t skipped = 0;
        for (;;) {
            size_t avail = in_.ensure(2);
            if (avail < 2) {
                in_.consume(avail);
                return skipped + avail;
            }
            const uint8_t* p = in_.data();
            if (p[0] == 0xA3 && p[1] == 0x95) return skipped;
            const void* q = std::memchr(p + 1, 0xA3, avail - 1);
            size_t step = q ? static_cast<size_t>(static_cast<const uint8_t*>(q) - p) : avail;
            in_.consume(step);
            skipped += step;
        }
    }

    static std::string cstr(const uint8_t* p, size_t n) {
        size_t k = 0;
        while (k < n && p[k] != 0) ++k;
        return std::string(reinterpret_cast<const char*>(p), k);
    }

    void define(const uint8_t* p, uint64_t off, bool framed) {
        const std::string where = "byte " + std::to_string(off);
        DfFormat f;
        f.id = p[0];
        f.length = p[1];
        f.name = cstr(p + 2, 4);
        f.format = cstr(p + 6, 16);
        std::string cols = cstr(p + 22, 64);
        bool printable = !f.name.empty();
        for (char c : f.name + f.format + cols)
            if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) printable = false;
        if (!printable) {
            if (!framed) {  // most likely a false header inside damaged data
                notes_.add("cut", where + ": unreadable FMT message not followed by a message header; ignored");
                return;
            }
            throw InputError(path_, 0, 0, where + ": FMT message has an unreadable name/format/columns " +
                                              escaped_quoted(f.name) + " " + escaped_quoted(f.format));
        }
        size_t start = 0;
        while (start <= cols.size() && !cols.empty()) {
            size_t comma = cols.find(',', start);
            if (comma == std::string::npos) comma = cols.size();
            f.labels.push_back(cols.substr(start, comma - start));
            start = comma + 1;
        }
        if (f.id == 128) {
            if (f.length != 89 || f.format != "BBnNZ")
                throw InputError(path_, 0, 0, where + ": FMT redefines FMT itself as length " +
                                                  std::to_string(f.length) + " format " + escaped_quoted(f.format) +
                                                  "; expected 89 and 'BBnNZ'");
            return;
        }
        DfFormat& slot = formats_[f.id];
        if (slot.defined && slot.name == f.name && slot.format == f.format && slot.length == f.length) return;
        if (!framed) {
            // Not followed by a message header: accept it only if it is self-consistent.
            try {
                NoteLog quiet(nullptr);
                DfFormat probe = f;
                complete_format(probe, path_, 0, where, quiet);
            } catch (const InputError& e) {
                notes_.add("cut", where + ": FMT message not followed by a message header and inconsistent (" +
                                      e.message() + "); ignored");
                return;
            }
        }
        if (slot.defined)
            notes_.add("fmt", where + ": FMT redefines type " + std::to_string(f.id) + " (" + slot.name + " -> " +
                                  f.name + ")");
        complete_format(f, path_, 0, where, notes_);
        slot = std::move(f);
    }

    std::string path_;
    ByteStream in_;
    NoteLog& notes_;
    std::array<DfFormat, 256> formats_;
    BinaryFields fields_;
    size_t pending_ = 0;
};

// --- text -------------------------------------------------------------------------------------
std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
}

bool parse_double(std::string_view s, double& out) {
    if (s.empty()) return false;
    if (s.front() == '+') s.remove_prefix(1);
    auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_long(std::string_view s, long& out) {
    if (s.empty()) return false;
    auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

class TextFields final : public FieldReader {
public:
    std::vector<std::string_view> v;  // v[0] = message name
    bool number(int i, double& out) const override {
        if (i < 0 || static_cast<size_t>(i) + 1 >= v.size()) return false;
        return parse_double(v[static_cast<size_t>(i) + 1], out);
    }
    std::string raw(int i) const override {
        if (i < 0 || static_cast<size_t>(i) + 1 >= v.size()) return "(missing)";
        return escaped_quoted(v[static_cast<size_t>(i) + 1]);
    }
    long column_of(int i) const override { return i + 2; }
    std::string text(int i) const override {
        if (i < 0 || static_cast<size_t>(i) + 1 >= v.size()) return std::string();
        return std::string(v[static_cast<size_t>(i) + 1]);
    }
};

class TextSource final : public MessageSource {
public:
    TextSource(const std::string& path, NoteLog& notes) : path_(path), in_(path), notes_(notes) {
        if (in_.ensure(1) == 0) throw InputError(path, 0, 0, "empty file: expected a DataFlash text log");
    }
    ~TextSource() override {}

    bool next(const DfFormat*& out_f, const FieldReader*& out_r, std::string& where, long& line) override {
        for (;;) {
            std::string_view text;
            if (!next_line(text)) {
                finish();
                return false;
            }
            split(text);
            const std::string_view name = fields_.v[0];
            if (name == "FMT") {
                define();
                continue;
            }
            auto it = by_name_.find(std::string(name));
            if (it == by_name_.end()) {
                if (!(fields_.v.size() == 1 && name.empty())) {
                    if (other_lines_++ == 0) first_other_ = lineno_;
                    if (other_example_.empty()) other_example_ = escaped_quoted(text, 30);
                    // The last one too: a garbled row mid-log hides behind a preamble line 1.
                    last_other_ = lineno_;
                    last_example_ = escaped_quoted(text, 30);
                }
                continue;
            }
            const DfFormat& f = formats_[static_cast<size_t>(it->second)];
            if (!f.used()) continue;
            if (!f.decodable) {
                if (f.role == Role::Battery)
                    throw InputError(path_, lineno_, 0, f.name + " rows cannot be read: " + f.why_not +
                                                            " (FMT at " + f.defined_at + ")");
                continue;
            }
            if (fields_.v.size() != f.format.size() + 1) {
                notes_.add("fields", "line " + std::to_string(lineno_) + ": " + f.name + " has " +
                                         std::to_string(fields_.v.size() - 1) + " values but its FMT (" +
                                         f.defined_at + ") defines " + std::to_string(f.format.size()) +
                                         "; line skipped");
                continue;
            }
            out_f = &f;
            out_r = &fields_;
            line = lineno_;
            where = "line " + std::to_string(lineno_);
            return true;
        }
    }

private:
    bool next_line(std::string_view& out) {
        in_.consume(pending_);
        pending_ = 0;
        size_t want = 1;
        for (;;) {
            size_t avail = in_.ensure(want);
            if (avail == 0) return false;
            const uint8_t* p = in_.data();
            const size_t from = want > 1 ? want - 4096 : 0;
            const void* nl = std::memchr(p + std::min(from, avail), '\n', avail - std::min(from, avail));
            if (nl) {
                size_t len = static_cast<size_t>(static_cast<const uint8_t*>(nl) - p);
                if (len > kMaxTextLine) too_long();
                pending_ = len + 1;
                if (len > 0 && p[len - 1] == '\r') --len;  // CRLF line endings
                out = std::string_view(reinterpret_cast<const char*>(p), len);
                ++lineno_;
                return true;
            }
            if (avail < want) {  // end of file: last line without a newline
                if (avail > kMaxTextLine) too_long();
                out = std::string_view(reinterpret_cast<const char*>(p), avail);
                pending_ = avail;
                ++lineno_;
                return true;
            }
            if (avail > kMaxTextLine) too_long();
            want = avail + 4096;
        }
    }
    [[noreturn]] void too_long() {
        throw InputError(path_, lineno_ + 1, 0,
                         "line is longer than " + std::to_string(kMaxTextLine) +
                             " bytes: not a DataFlash text log");
    }

    void split(std::string_view text) {
        fields_.v.clear();
        size_t start = 0;
        for (;;) {
            size_t comma = text.find(',', start);
            if (comma == std::string_view::npos) {
                fields_.v.push_back(trim(text.substr(start)));
                break;
            }
            fields_.v.push_back(trim(text.substr(start, comma - start)));
            start = comma + 1;
        }
    }

    void define() {
        const auto& v = fields_.v;
        const std::string where = "line " + std::to_string(lineno_);
        if (v.size() < 4)
            throw InputError(path_, lineno_, 0,
                             "FMT line has " + std::to_string(v.size()) +
                                 " fields; expected FMT, type, length, name, format, columns");
        long id = 0, length = 0;
        if (!parse_long(v[1], id) || id < 0 || id > 255)
            throw InputError(path_, lineno_, 2, "FMT type must be an integer 0..255, found " + escaped_quoted(v[1]));
        if (!parse_long(v[2], length))
            throw InputError(path_, lineno_, 3, "FMT length must be an integer, found " + escaped_quoted(v[2]));
        DfFormat f;
        f.id = static_cast<int>(id);
        f.name = std::string(v[3]);
        if (v.size() > 4) f.format = std::string(v[4]);  // "FMT, 10, 3, STRT" has no columns at all
        if (f.name.empty() || f.name.size() > 16)
            throw InputError(path_, lineno_, 4, "FMT name must be 1..16 characters, found " + escaped_quoted(v[3]));
        for (size_t i = 5; i < v.size(); ++i)
            if (!v[i].empty()) f.labels.emplace_back(v[i]);
        if (length < 3 || length > 255)
            throw InputError(path_, lineno_, 3,
                             "FMT for type " + std::to_string(f.id) + " " + escaped_quoted(f.name) +
                                 " declares length " + std::string(v[2]) +
                                 "; a DataFlash message is 3..255 bytes (3-byte header + payload)");
        f.length = static_cast<int>(length);
        if (f.name == "FMT") return;  // the definition of FMT itself; FMT lines are read directly
        complete_format(f, path_, lineno_, where, notes_);
        auto it = by_name_.find(f.name);
        if (it != by_name_.end() && it->second != f.id) formats_[static_cast<size_t>(it->second)] = DfFormat();
        DfFormat& slot = formats_[static_cast<size_t>(f.id)];
        if (slot.defined && slot.name != f.name) by_name_.erase(slot.name);
        by_name_[f.name] = f.id;
        slot = std::move(f);
    }

    void finish() {
        if (finished_) return;
        finished_ = true;
        if (other_lines_ > 0)
            notes_.add("other-lines", std::to_string(other_lines_) +
                                          " line(s) are not messages of a type defined by an FMT line (first: line " +
                                          std::to_string(first_other_) + " " + other_example_ +
                                          (other_lines_ > 1 ? "; last: line " + std::to_string(last_other_) + " " + last_example_
                                                            : std::string()) +
                                          "); ignored");
    }

    std::string path_;
    ByteStream in_;
    NoteLog& notes_;
    std::array<DfFormat, 256> formats_;
    std::unordered_map<std::string, int> by_name_;
    TextFields fields_;
    size_t pending_ = 0;
    long lineno_ = 0;
    long other_lines_ = 0;
    long first_other_ = 0;
    long last_other_ = 0;
    std::string other_example_;
    std::string last_example_;
    bool finished_ = false;
};

// ---------------------------------------------------------------------------------------------
// What the pre-scan learns (aggregates only).
struct Candidate {
    long rows = 0;  // instance-0 rows
    long other_instance = 0;
    bool any_own_time = false;
    long untimed_before_boot = 0;
    long untimed_before_gps = 0;
    std::vector<uint32_t> spacing_hist;  // 1 ms bins of dCurrTot/mean(Curr), up to 60 s
    long spacing_pairs = 0;
    bool have_prev = false;
    double prev_q = 0, prev_i = 0;
    long temp_rows = 0, temp_nonzero = 0;
};
constexpr size_t kSpacingBins = 60000;

struct ScanStats {
    Candidate bat, curr;
    bool boot_seen = false, gps_seen = false;
    double first_boot_us = 0, first_gps_us = 0;
    int max_cells = 0;
    bool cut_short = false;  // the file ends inside a message
};

enum class Clock { Boot, Gps, None };

struct Plan {
    std::string battery;  // "BAT" or "CURR"
    Clock clock = Clock::None;
    long rows_before = 0;
    double first_clock_us = 0;
    double spacing_us = 1e6;
    double origin_us = 0;
    bool use_temp = false;
};

// Tracks the latest boot time and GPS time of week (unwrapped) of the timed messages.
struct Clocks {
    bool boot_seen = false, gps_seen = false;
    double boot_us = 0, gps_us = 0;
    double first_boot_us = 0, first_gps_us = 0;
    double gps_last_raw = -1, gps_wrap = 0;

    // A clock's new reading: messages of several types a few ms out of order keep the clock
    // where it was, but a step back of a second or more is taken, so that the clock returns
    // from a corrupt time stamp (which TimeOrder then drops) instead of sticking at it.
    static double latest(double clock_us, double reading_us) {
        return reading_us < clock_us && clock_us - reading_us < 1.0e6 ? clock_us : reading_us;
    }

    void update(const DfFormat& f, const FieldReader& r) {
        double v;
        if (f.boot_time >= 0 && r.number(f.boot_time, v) && std::isfinite(v) && v >= 0) {
            v *= f.boot_time_to_us;
            if (!boot_seen) first_boot_us = v;
            boot_us = boot_seen ? latest(boot_us, v) : v;
            boot_seen = true;
        }
        if (f.gps_week_ms >= 0 && r.number(f.gps_week_ms, v) && std::isfinite(v) && v > 0 && v < kGpsWeekMs) {
            if (gps_last_raw >= 0 && v < gps_last_raw - kGpsWeekMs / 2) gps_wrap += kGpsWeekMs;
            gps_last_raw = v;
            double t = (v + gps_wrap) * 1000.0;
            if (!gps_seen) first_gps_us = t;
            gps_us = gps_seen ? latest(gps_us, t) : t;
            gps_seen = true;
        }
    }
};

double battery_scale(const DfFormat& f, int column_index) {
    return char_is_integer(f.format[static_cast<size_t>(column_index)]) ? 0.01 : 1.0;
}

bool read_instance(const DfFormat& f, const FieldReader& r, double& inst) {
    inst = 0;
    if (f.inst < 0) return true;
    return r.number(f.inst, inst);
}

// Latest BCL cells; returns the number of leading valid cells.
int read_cells(const DfFormat& f, const FieldReader& r, float* cells, int& beyond) {
    int n = 0;
    beyond = 0;
    for (int k = 0; k < kMaxCellFields; ++k) {
        double mv;
        if (f.cells[k] < 0 || !r.number(f.cells[k], mv) || !std::isfinite(mv) || mv <= 0 || mv >= 65535) break;
        if (k < core::kMaxCells)
            cells[k] = static_cast<float>(mv / 1000.0);
        else
            ++beyond;
        n = k + 1;
    }
    return std::min(n, core::kMaxCells);
}

// The first cell field whose value ends the cells (0, 65535, not finite) while a later one
// reads a voltage: a broken value, not the end of the pack's cells. -1 when there is none.
int cell_hole(const DfFormat& f, const FieldReader& r) {
    const auto valid = [&](int k) {
        double mv;
        return f.cells[k] >= 0 && r.number(f.cells[k], mv) && std::isfinite(mv) && mv > 0 && mv < 65535;
    };
    for (int k = 0; k < kMaxCellFields && f.cells[k] >= 0; ++k) {
        if (valid(k)) continue;
        for (int later = k + 1; later < kMaxCellFields && f.cells[later] >= 0; ++later)
            if (valid(later)) return k;
        return -1;
    }
    return -1;
}

void scan_message(const DfFormat& f, const FieldReader& r, const std::string& where, long line,
                  const std::string& path, ScanStats& s, Clocks& clocks) {
    clocks.update(f, r);
    if (!s.boot_seen && clocks.boot_seen) {
        s.boot_seen = true;
        s.first_boot_us = clocks.first_boot_us;
    }
    if (!s.gps_seen && clocks.gps_seen) {
        s.gps_seen = true;
        s.first_gps_us = clocks.first_gps_us;
    }
    if (f.role == Role::Cells && f.decodable) {
        double inst;
        if (!read_instance(f, r, inst) || inst != 0) return;
        float cells[core::kMaxCells];
        int beyond;
        s.max_cells = std::max(s.max_cells, read_cells(f, r, cells, beyond));
        return;
    }
    if (f.role != Role::Battery) return;
    if (!f.decodable)
        throw InputError(path, line, 0, (line > 0 ? std::string() : where + ": ") + f.name +
                                            " rows cannot be read: " + f.why_not +
                                            " (FMT at " + f.defined_at + ")");
    Candidate& c = f.name == "BAT" ? s.bat : s.curr;
    double inst;
    if (!read_instance(f, r, inst)) return;
    if (inst != 0) {
        ++c.other_instance;
        return;
    }
    ++c.rows;
    if (f.boot_time >= 0) {  // own time stamp (an unreadable one drops the row later)
        c.any_own_time = true;
    } else {
        if (!clocks.boot_seen) ++c.untimed_before_boot;
        if (!clocks.gps_seen) ++c.untimed_before_gps;
    }
    double temp;
    if (f.temp >= 0 && r.number(f.temp, temp) && std::isfinite(temp)) {
        ++c.temp_rows;
        if (temp != 0) ++c.temp_nonzero;
    }
    double q, i;
    if (f.curr_tot >= 0 && r.number(f.curr_tot, q) && r.number(f.curr, i) && std::isfinite(q) && std::isfinite(i)) {
        i *= battery_scale(f, f.curr);
        if (c.have_prev) {
            const double dq = q - c.prev_q;
            const double im = 0.5 * (i + c.prev_i);
            if (im >= 1.0 && dq > 0) {
                const double sec = dq / im * 3.6;  // mAh / A -> s
                if (sec >= 0.001 && sec < 60.0) {
                    if (c.spacing_hist.empty()) c.spacing_hist.assign(kSpacingBins, 0);
                    ++c.spacing_hist[static_cast<size_t>(sec * 1000.0)];
                    ++c.spacing_pairs;
                }
            }
        }
        c.have_prev = true;
        c.prev_q = q;
        c.prev_i = i;
    } else {
        c.have_prev = false;
    }
}

Plan make_plan(const ScanStats& s, const std::string& path, std::vector<std::string>& notes) {
    Plan p;
    const Candidate* c = nullptr;
    if (s.bat.rows > 0) {
        p.battery = "BAT";
        c = &s.bat;
        if (s.curr.rows > 0)
            notes.push_back("log has both BAT (" + std::to_string(s.bat.rows) + " rows) and CURR (" +
                            std::to_string(s.curr.rows) + " rows): BAT is used");
    } else if (s.curr.rows > 0) {
        p.battery = "CURR";
        c = &s.curr;
    } else {
        std::string extra;
        if (s.bat.other_instance + s.curr.other_instance > 0)
            extra = " (only rows of battery instances other than 0: " +
                    std::to_string(s.bat.other_instance + s.curr.other_instance) + ")";
        if (s.cut_short) extra += "; the file ends inside a message: it is cut short, and the battery data may be in the part missing";
        throw InputError(path, 0, 0, "no BAT or CURR messages (battery data) in this DataFlash log" + extra);
    }
    if (c->other_instance > 0)
        notes.push_back(std::to_string(c->other_instance) + " " + p.battery +
                        " rows of battery instances other than 0 are ignored");

    bool need_spacing = false;
    if (c->any_own_time || s.boot_seen) {
        p.clock = Clock::Boot;
        p.rows_before = c->untimed_before_boot;
        p.first_clock_us = s.first_boot_us;
        if (!c->any_own_time)
            notes.push_back(p.battery + " rows carry no time stamp: each takes the latest boot time "
                            "(TimeUS/TimeMS) of the messages logged before it");
    } else if (s.gps_seen) {
        p.clock = Clock::Gps;
        p.rows_before = c->untimed_before_gps;
        p.first_clock_us = s.first_gps_us;
        notes.push_back(p.battery + " rows carry no time stamp and the log has no boot time: each row takes the "
                        "GPS time of week of the latest GPS row before it (so its resolution is the GPS rate)");
    } else {
        p.clock = Clock::None;
        need_spacing = true;
    }
    if (p.rows_before > 0) need_spacing = true;

    if (need_spacing) {
        std::string how;
        if (c->spacing_pairs >= 5) {
            long half = (c->spacing_pairs + 1) / 2, acc = 0;
            size_t bin = 0;
            for (; bin < c->spacing_hist.size(); ++bin) {
                acc += c->spacing_hist[bin];
                if (acc >= half) break;
            }
            p.spacing_us = (static_cast<double>(bin) + 0.5) * 1000.0;
            how = fixed(p.spacing_us / 1e6, 4) + " s, the median of dCurrTot / mean(Curr) over " +
                  std::to_string(c->spacing_pairs) + " consecutive row pairs drawing >= 1 A";
        } else {
            p.spacing_us = 1e6;
            how = "1 s (assumed: fewer than 5 row pairs with >= 1 A and a growing CurrTot to infer it from)";
        }
        if (p.clock == Clock::None)
            notes.push_back("no time source in this log (no TimeUS/TimeMS fields, no GPS time): the " +
                            std::to_string(c->rows) + " " + p.battery +
                            " rows are assumed evenly spaced at " + how + "; times are inferred, not measured");
        else
            notes.push_back("the first " + std::to_string(p.rows_before) + " " + p.battery +
                            " rows come before the first timed message (e.g. before GPS fix): they are placed "
                            "before it at " + how + "; their times are inferred, not measured");
    }
    if (p.clock == Clock::Boot) {
        p.origin_us = std::min(0.0, p.first_clock_us - static_cast<double>(p.rows_before) * p.spacing_us);
        if (p.origin_us < 0)
            notes.push_back("time axis shifted by " + fixed(-p.origin_us / 1e6, 3) +
                            " s so the inferred times of the first rows are not negative");
    } else if (p.clock == Clock::Gps) {
        p.origin_us = p.first_clock_us - static_cast<double>(p.rows_before) * p.spacing_us;
        notes.push_back("time 0 = GPS time of week " + fixed(p.origin_us / 1000.0, 0) + " ms");
    }
    if (c->temp_rows > 0 && c->temp_nonzero > 0) {
        p.use_temp = true;
    } else if (c->temp_rows > 0) {
        notes.push_back(p.battery + ".Temp is 0 in every row: treated as no temperature sensor");
    }
    return p;
}

// ---------------------------------------------------------------------------------------------
class DataflashReader final : public SampleReader {
public:
    DataflashReader(const std::string& path, bool text) : path_(path), text_(text), notes_(&info_.notes) {
        info_.path = path;
        info_.format = text ? LogFormat::DataflashText : LogFormat::DataflashBinary;
        {
            NoteLog silent(nullptr);
            auto src = open_source(silent);
            ScanStats stats;
            Clocks clocks;
            const DfFormat* f;
            const FieldReader* r;
            std::string where;
            long line;
            while (src->next(f, r, where, line)) scan_message(*f, *r, where, line, path_, stats, clocks);
            stats.cut_short = silent.count("truncated") > 0;
            plan_ = make_plan(stats, path_, info_.notes);
            info_.cell_count = stats.max_cells;
            info_.has_temperature = plan_.use_temp;
        }
        src_ = open_source(notes_);
        order_.emplace(plan_.battery + " time", "row", [this](const char* kind, const std::string& text) { drop(kind, text); });
    }

    bool next(core::Sample& out) override {
        if (order_->pop(out)) return true;
        if (done_) return false;
        const DfFormat* f;
        const FieldReader* r;
        std::string where;
        long line;
        core::Sample sample;
        double t_us;
        // A battery row waits for the next message: ArduPilot writes each update's BAT and then
        // its BCL with the same TimeUS, so the cells that belong to a BAT row come after it.
        while (src_->next(f, r, where, line)) {
            if (step(*f, *r, where, line, sample, t_us)) {
                flush_pending();
                pending_ = sample;
                pending_t_us_ = t_us;
                pending_where_ = where;
                pending_stamp_us_ = row_stamp_us_;
            } else if (cells_stamp_us_ >= 0 && pending_ && cells_stamp_us_ == pending_stamp_us_) {
                pending_->cell_count = static_cast<uint8_t>(cell_count_);
                std::copy(cells_, cells_ + core::kMaxCells, pending_->cell_voltage_v);
            }
            cells_stamp_us_ = -1;
            if (order_->pop(out)) return true;
        }
        flush_pending();
        order_->finish();
        done_ = true;
        if (beyond_cells_ > 0)
            notes_.add("cells", "BCL reports more than " + std::to_string(core::kMaxCells) + " cells in " +
                                    std::to_string(beyond_cells_) + " rows; cells beyond " +
                                    std::to_string(core::kMaxCells) + " are dropped");
        if (unknown_current_ > 0)
            info_.notes.push_back(plan_.battery + ".Curr is NaN (the battery monitor measures no current) in " +
                                  std::to_string(unknown_current_) + " of " + std::to_string(rows_) +
                                  " rows: read as 0 A, so those samples carry the voltage alone");
        notes_.finish();
        if (order_->accepted() == 0)
            throw InputError(path_, 0, 0, "no usable " + plan_.battery + " rows: all " + std::to_string(rows_) +
                                              " were dropped" +
                                              (first_drop_.empty() ? std::string() : " (first: " + first_drop_ + ")"));
        return order_->pop(out);
    }

    const SourceInfo& info() const override { return info_; }
    void add_note(const std::string& text) { info_.notes.push_back(text); }

private:
    void flush_pending() {
        if (!pending_) return;
        order_->offer(*pending_, pending_t_us_, pending_where_);
        pending_.reset();
    }
    // The row's own time stamp in µs as logged (-1: none), to pair a BCL row with its BAT row.
    static double own_stamp_us(const DfFormat& f, const FieldReader& r) {
        double t;
        if (f.boot_time < 0 || !r.number(f.boot_time, t) || !std::isfinite(t)) return -1;
        return t * f.boot_time_to_us;
    }

    // PARM row: keeps the first finite value of each name.
    void parameter(const DfFormat& f, const FieldReader& r, const std::string& where) {
        const std::string name = r.text(f.parm_name);
        const std::string at = where + (r.column_of(f.parm_value) ? " column " + std::to_string(r.column_of(f.parm_value)) : "");
        bool printable = !name.empty();
        for (char c : name)
            if (static_cast<unsigned char>(c) <= 0x20 || static_cast<unsigned char>(c) >= 0x7F) printable = false;
        if (!printable) {
            notes_.add("parameter", where + ": PARM.Name " + escaped_quoted(name) + " is not a parameter name; row skipped");
            return;
        }
        if (first_params_.seen(name)) return;  // a later change; the first value is the one in force at start
        double value;
        if (!r.number(f.parm_value, value) || !std::isfinite(value)) {
            notes_.add("parameter", at + ": PARM " + name + ".Value: expected a finite number, found " +
                                        r.raw(f.parm_value) + "; parameter row skipped");
            return;
        }
        first_params_.add(name, value, notes_, where);
    }

    std::unique_ptr<MessageSource> open_source(NoteLog& notes) {
        if (text_) return std::make_unique<TextSource>(path_, notes);
        return std::make_unique<BinarySource>(path_, notes);
    }

    void drop(const char* kind, const std::string& text) {
        if (first_drop_.empty()) first_drop_ = text;
        notes_.add(kind, text);
    }

    // A battery row read into `out`, its time (µs, not yet checked for order) into `t`.
    bool step(const DfFormat& f, const FieldReader& r, const std::string& where, long line, core::Sample& out,
              double& t) {
        (void)line;
        clocks_.update(f, r);
        if (f.role == Role::Parameter && f.decodable) {
            parameter(f, r, where);
            return false;
        }
        if (f.role == Role::Cells && f.decodable) {
            double inst;
            if (!read_instance(f, r, inst) || inst != 0) return false;
            // Text where a cell's millivolts belong (a text log's "abc"): the row is skipped and
            // said, as a battery row is; read on, it had ended the cells there without a word.
            for (int k = 0; k < kMaxCellFields && f.cells[k] >= 0; ++k) {
                double mv;
                if (r.number(f.cells[k], mv)) continue;
                notes_.add("unreadable", where + (r.column_of(f.cells[k]) ? " column " + std::to_string(r.column_of(f.cells[k])) : "") +
                                             ": " + f.name + "." + f.labels[static_cast<size_t>(f.cells[k])] +
                                             ": expected a number, found " + r.raw(f.cells[k]) +
                                             "; cell row skipped (the cells before it are kept)");
                return false;
            }
            const int hole = cell_hole(f, r);
            if (hole >= 0)
                notes_.add("cell-hole", where + (r.column_of(f.cells[hole]) ? " column " + std::to_string(r.column_of(f.cells[hole])) : "") +
                                            ": " + f.name + "." + f.labels[static_cast<size_t>(f.cells[hole])] + " reads " +
                                            r.raw(f.cells[hole]) + " while a later cell reads a voltage: the cells are read up to the one before it");
            int beyond = 0;
            float cells[core::kMaxCells] = {};
            cell_count_ = read_cells(f, r, cells, beyond);
            std::copy(cells, cells + core::kMaxCells, cells_);
            cells_stamp_us_ = own_stamp_us(f, r);
            if (beyond) ++beyond_cells_;
            if (beyond) info_.cells_beyond_kept = std::max(info_.cells_beyond_kept, core::kMaxCells + beyond);
            return false;
        }
        if (f.role != Role::Battery || f.name != plan_.battery) return false;
        double inst;
        if (!read_instance(f, r, inst) || inst != 0) return false;
        ++rows_;
        row_stamp_us_ = own_stamp_us(f, r);
        // Time first: a row dropped below still occupies its slot in an inferred spacing.
        if (f.boot_time >= 0) {
            if (!r.number(f.boot_time, t) || !std::isfinite(t)) {
                drop("unreadable", where + ": " + f.name + "." + f.labels[static_cast<size_t>(f.boot_time)] +
                                       ": expected a time, found " + r.raw(f.boot_time) + "; row skipped");
                return false;
            }
            t *= f.boot_time_to_us;
        } else if (plan_.clock == Clock::Boot && clocks_.boot_seen) {
            t = clocks_.boot_us;
        } else if (plan_.clock == Clock::Gps && clocks_.gps_seen) {
            t = clocks_.gps_us;
        } else {
            const long k = untimed_++;
            if (plan_.clock == Clock::None)
                t = static_cast<double>(k) * plan_.spacing_us;
            else
                t = plan_.first_clock_us - static_cast<double>(std::max(0L, plan_.rows_before - k)) * plan_.spacing_us;
        }
        t -= plan_.origin_us;
        double volt, curr;
        if (!r.number(f.volt, volt)) {
            drop("unreadable", where + (r.column_of(f.volt) ? " column " + std::to_string(r.column_of(f.volt)) : "") +
                                   ": " + f.name + ".Volt: expected a number, found " + r.raw(f.volt) + "; row skipped");
            return false;
        }
        if (!r.number(f.curr, curr)) {
            drop("unreadable", where + (r.column_of(f.curr) ? " column " + std::to_string(r.column_of(f.curr)) : "") +
                                   ": " + f.name + ".Curr: expected a number, found " + r.raw(f.curr) + "; row skipped");
            return false;
        }
        volt *= battery_scale(f, f.volt);
        // ArduPilot logs Curr (and CurrTot) as NaN when its battery monitor measures no
        // current (a voltage-only monitor): the voltage is still good, so the row is kept at
        // 0 A and the count said, as the ULog reader does with PX4's -1.
        if (std::isnan(curr)) {
            curr = 0.0;
            ++unknown_current_;
        }
        curr *= battery_scale(f, f.curr);
        if (!std::isfinite(volt) || volt < 0 || volt > 1000) {
            drop("bad-value", where + ": " + f.name + ".Volt = " + fixed(volt, 3) +
                                  " V is not a plausible pack voltage (finite, 0..1000 V); row dropped");
            return false;
        }
        if (!std::isfinite(curr) || std::fabs(curr) > 10000) {
            drop("bad-value", where + ": " + f.name + ".Curr = " + fixed(curr, 3) +
                                  " A is not a plausible current (finite, |I| <= 10000 A); row dropped");
            return false;
        }
        out = core::Sample();
        out.voltage_v = static_cast<float>(volt);
        out.current_a = static_cast<float>(curr);
        out.cell_count = static_cast<uint8_t>(cell_count_);
        std::copy(cells_, cells_ + core::kMaxCells, out.cell_voltage_v);
        double temp;
        if (plan_.use_temp && f.temp >= 0 && r.number(f.temp, temp) && std::isfinite(temp)) {
            out.has_temperature = true;
            out.temperature_c = static_cast<float>(temp);
        }
        return true;
    }

    std::string path_;
    bool text_;
    SourceInfo info_;
    NoteLog notes_;
    logio::FirstParameters first_params_{&info_.parameters};
    Plan plan_;
    std::unique_ptr<MessageSource> src_;
    Clocks clocks_;
    int cell_count_ = 0;
    float cells_[core::kMaxCells] = {};
    long beyond_cells_ = 0;
    long untimed_ = 0;
    long rows_ = 0;
    long unknown_current_ = 0;  // battery rows whose Curr is NaN, read as 0 A
    std::optional<TimeOrder> order_;  // made once the plan names the battery message
    std::optional<core::Sample> pending_;  // the latest battery row, until the message after it
    double pending_t_us_ = 0;
    std::string pending_where_;
    double pending_stamp_us_ = -1;
    double row_stamp_us_ = -1;    // own time stamp of the battery row step() just read
    double cells_stamp_us_ = -1;  // own time stamp of the BCL row step() just read, else -1
    bool done_ = false;
    std::string first_drop_;
};

}  // namespace

namespace {
std::unique_ptr<SampleReader> open_dataflash(const std::string& path, const ReaderOptions& options, bool text) {
    auto r = std::make_unique<DataflashReader>(path, text);
    if (options.current_source == CurrentSource::Shunt)
        r->add_note("the shunt current source applies to raw monitor logs only; the logged Curr is used");
    return r;
}
}  // namespace

std::unique_ptr<SampleReader> open_dataflash_text(const std::string& path, const ReaderOptions& options) {
    return open_dataflash(path, options, true);
}

std::unique_ptr<SampleReader> open_dataflash_binary(const std::string& path, const ReaderOptions& options) {
    return open_dataflash(path, options, false);
}

}  // namespace host
}  // namespace battsim
