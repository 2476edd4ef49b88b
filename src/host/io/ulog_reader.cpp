// PX4 ULog (.ulg) reader for topic battery_status, written from the ULog file format
// specification (PX4 docs "ULog File Format"):
//  * Header, 16 bytes: magic 'U' 'L' 'o' 'g' 0x01 0x12 0x35, version (1 byte), timestamp (uint64 us).
//  * Then messages, each: uint16 msg_size (payload bytes, header excluded), uint8 msg_type, payload.
//    Definitions: 'B' flag bits (first message; compat[8], incompat[8], appended_offsets[3]),
//    'F' format "name:type field;type[n] field;..." (types: the basic C types or another format,
//    nested, no cycles), 'I' info, 'M' multi info, 'P' parameter, 'Q' default parameter.
//    Data: 'A' subscription (multi_id u8, msg_id u16, name), 'R' unsubscription, 'D' data
//    (msg_id u16, bytes laid out by the format, packed, little-endian), 'L'/'C' logged strings,
//    'S' sync, 'O' dropout (u16 ms). Unknown message types are skipped by their size.
//  * A trailing '_padding' field may be left out of the logged data: shorter payloads are padded
//    with zeros up to the format size (battery_status on PX4 1.12 logs 156 of 160 bytes). A payload
//    that is missing a real (non-padding) field is dropped with a note.
//  * Unknown incompat flag bits make the log unreadable (the spec requires refusing it).
//    With DATA_APPENDED the data continues at each appended offset; a message that would run
//    across such an offset is discarded.
//  * A file that ends inside a message keeps everything before it (noted).
//
// Extracted: battery_status with multi_id 0 -> timestamp (us), voltage_v, current_a (positive =
// discharge), voltage_cell_v[] (the first cell_count entries, leading cells > 0), temperature (if
// finite). The streaming pass reads the data section once, in order; a pre-scan pass (aggregates
// only) finds the cell count, temperature presence and anything worth a note before streaming.
//
// Parameters: 'P' messages (key_len u8, key "type name", value; the spec allows int32_t and
// float, both 4 bytes little-endian) go to SourceInfo::parameters, from the definitions and the
// data section alike, first value per name only (later ones are changes in flight). 'Q' messages
// are defaults, not values in force, and are ignored. A malformed 'P' is skipped with a note.
//
// Decision, current_a == -1: PX4 logs -1 when the battery driver has no current measurement. Such
// samples are kept (the voltage is still valid) with current 0 A, and SourceInfo::notes says how many
// samples were affected, so a consumer can tell that 0 A means "unknown" there.
#include "host/io/ulog_reader.h"

#include <algorithm>
#include <iterator>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "host/io/dataflash_ulog_util.h"
#include "host/io/time_order.h"

namespace battsim {
namespace host {
namespace {

using logio::ByteStream;
using logio::fixed;
using logio::le;
using logio::NoteLog;
using logio::escaped_quoted;

constexpr uint8_t kMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
constexpr size_t kMaxDefinitionBytes = 8 * 1024 * 1024;  // all 'F' strings together
constexpr int kMaxNesting = 32;
constexpr size_t kMaxMessageBytes = 65535;
// Far above PX4's parameter count (~1500); bounds memory on corrupt input.

using Parameters = std::vector<std::pair<std::string, double>>;

int basic_size(const std::string& t) {
    static const std::map<std::string, int> sizes = {
        {"int8_t", 1},  {"uint8_t", 1},  {"int16_t", 2}, {"uint16_t", 2}, {"int32_t", 4},
        {"uint32_t", 4}, {"int64_t", 8}, {"uint64_t", 8}, {"float", 4},    {"double", 8},
        {"bool", 1},    {"char", 1}};
    auto it = sizes.find(t);
    return it == sizes.end() ? -1 : it->second;
}

// Reads a basic type at p as a double; false for unknown types.
bool read_basic(const std::string& t, const uint8_t* p, double& out) {
    if (t == "float") {
        uint32_t u = static_cast<uint32_t>(le(p, 4));
        float f;
        std::memcpy(&f, &u, 4);
        out = f;
    } else if (t == "double") {
        uint64_t u = le(p, 8);
        double d;
        std::memcpy(&d, &u, 8);
        out = d;
    } else if (t == "uint8_t" || t == "bool" || t == "char") {
        out = p[0];
    } else if (t == "int8_t") {
        out = static_cast<int8_t>(p[0]);
    } else if (t == "uint16_t") {
        out = static_cast<double>(le(p, 2));
    } else if (t == "int16_t") {
        out = static_cast<int16_t>(le(p, 2));
    } else if (t == "uint32_t") {
        out = static_cast<double>(le(p, 4));
    } else if (t == "int32_t") {
        out = static_cast<int32_t>(le(p, 4));
    } else if (t == "uint64_t") {
        out = static_cast<double>(le(p, 8));
    } else if (t == "int64_t") {
        out = static_cast<double>(static_cast<int64_t>(le(p, 8)));
    } else {
        return false;
    }
    return true;
}

struct UField {
    std::string type;
    std::string name;
    long count = 1;
    bool is_array = false;
};

struct UFormat {
    std::vector<UField> fields;
    uint64_t defined_at = 0;
};

bool name_char_ok(char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '/';
}

// Where a needed field sits in the battery_status payload.
struct Slot {
    bool present = false;
    std::string type;
    size_t offset = 0;
    long count = 1;
};

struct BatteryLayout {
    size_t full_size = 0;  // format size
    size_t min_size = 0;   // end of the last non-padding field
    Slot timestamp, voltage, current, discharged, temperature, cell_count, cells;
};

struct BatteryRecord {
    uint64_t offset = 0;
    double timestamp = 0;
    double voltage = 0, current = 0;
    double temperature = NAN;
    bool has_temperature_field = false;
    long cell_count = -1;  // -1 = no cell_count field
    long cells_in_array = 0;
    double cells[64] = {};
};

// Streams the messages of a ULog and hands out battery_status (multi_id 0) records.
class UlogStream {
public:
    // `params`: where parameter messages go; nullptr to skip them (pre-scan).
    UlogStream(const std::string& path, NoteLog& notes, Parameters* params = nullptr)
        : path_(path), in_(path), notes_(notes), params_(params), first_params_(params) {
        const size_t n = in_.ensure(16);
        if (n == 0) throw InputError(path, 0, 0, "empty file: expected a ULog (.ulg)");
        const uint8_t* p = in_.data();
        if (n < 7 || std::memcmp(p, kMagic, 7) != 0)
            throw InputError(path, 0, 0,
                             "byte 0: not a ULog file: expected magic 55 4C 6F 67 01 12 35 ('ULog' 01 12 35), found " +
                                 logio::hex_bytes(p, std::min<size_t>(n, 7)));
        if (n < 16)
            throw InputError(path, 0, 0, "truncated ULog header: the file has " + std::to_string(n) +
                                             " bytes, the header alone is 16 (magic, version, timestamp)");
        version_ = p[7];
        if (version_ > 1)
            notes_.add("version", "ULog version " + std::to_string(version_) +
                                      " is newer than the version 1 this reader knows; read anyway (the spec asks "
                                      "readers to do so)");
        in_.consume(16);
    }

    bool saw_subscription() const { return subscribed_ever_; }
    // Bytes skipped to find the framing again after corrupt headers, and where the first was.
    uint64_t corrupt_bytes() const { return corrupt_bytes_; }
    uint64_t first_corrupt() const { return first_corrupt_; }
    // Where the file ends inside a message (cut short), -1 when it ends between messages.
    int64_t cut_at() const { return cut_at_; }

    bool next(BatteryRecord& rec) {
        for (;;) {
            in_.consume(pending_);
            pending_ = 0;
            const uint64_t off = in_.offset();
            while (!appended_.empty() && appended_.front() <= off) {
                if (appended_.front() < off)
                    notes_.add("appended", "appended-data offset " + std::to_string(appended_.front()) +
                                               " lies inside an earlier message; ignored");
                appended_.erase(appended_.begin());
            }
            size_t avail = in_.ensure(3);
            if (avail == 0) return false;
            if (avail < 3) {
                cut_at_ = static_cast<int64_t>(off);
                notes_.add("truncated", "byte " + std::to_string(off) + ": file ends inside a message header (" +
                                            std::to_string(avail) + " bytes); ignored");
                in_.consume(avail);
                return false;
            }
            const uint8_t* p = in_.data();
            const size_t size = static_cast<size_t>(le(p, 2));
            const char type = static_cast<char>(p[2]);
            if (!appended_.empty() && off + 3 + size > appended_.front()) {
                notes_.add("appended", "byte " + std::to_string(off) + ": message runs across the appended-data "
                                       "offset " + std::to_string(appended_.front()) +
                                       " (cut off when the log was interrupted); skipped to the appended data");
                in_.seek_forward(appended_.front());
                continue;
            }
            avail = in_.ensure(3 + size);
            p = in_.data();
            if (avail < 3 + size) {
                cut_at_ = static_cast<int64_t>(off);
                notes_.add("truncated", "byte " + std::to_string(off) + ": message '" + printable(type) +
                                            "' declares " + std::to_string(size) + " payload bytes but the file "
                                            "ends after " + std::to_string(avail - 3) +
                                            "; the partial message is discarded");
                in_.consume(avail);
                return false;
            }
            pending_ = 3 + size;
            const uint8_t* payload = p + 3;
            const bool first = !seen_message_;
            seen_message_ = true;
            switch (type) {
                case 'B':
                    if (first)
                        flag_bits(payload, size, off);
                    else
                        notes_.add("flags", "byte " + std::to_string(off) +
                                                ": flag-bits message is not the first message; ignored");
                    break;
                case 'F': define(payload, size, off); break;
                case 'A': subscribe(payload, size, off); break;
                case 'R':
                    if (size >= 2 && subscribed_ && le(payload, 2) == battery_id_) subscribed_ = false;
                    break;
                case 'D':
                    if (size < 2) {
                        notes_.add("short", "byte " + std::to_string(off) + ": data message of " +
                                                std::to_string(size) + " bytes has no msg_id; skipped");
                        break;
                    }
                    if (subscribed_ && le(payload, 2) == battery_id_ && decode(payload + 2, size - 2, off, rec))
                        return true;
                    break;
                case 'O':
                    ++dropouts_;
                    if (size >= 2) dropout_ms_ += static_cast<long>(le(payload, 2));
                    break;
                case 'P': parameter(payload, size, off); break;
                case 'I': case 'M': case 'Q': case 'L': case 'C': case 'S': break;
                default:
                    if (type >= 'A' && type <= 'Z') {
                        // A message type of a newer ULog: the spec has readers skip it by its size.
                        notes_.add("unknown-type", "byte " + std::to_string(off) + ": unknown message type " +
                                                       escaped_quoted(std::string(1, type)) + " (" + std::to_string(size) +
                                                       " bytes) skipped");
                        break;
                    }
                    pending_ = 0;
                    resync(off, type);
            }
        }
    }

    // A header whose type is no letter is not a message: the framing is lost, most likely to a
    // size field that lied, which sends every later header into the middle of a payload. The
    // spec's sync messages (8 magic bytes) are there to find it again; the bytes between are
    // skipped, and said.
    void resync(uint64_t off, char type) {
        static constexpr uint8_t kSync[11] = {8, 0, 'S', 0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12};
        const std::string what = "byte " + std::to_string(off) + ": a message header of type '" + printable(type) +
                                 "', which no ULog message has: the log is corrupt before it (a message size that "
                                 "lied); ";
        if (corrupt_bytes_ == 0) first_corrupt_ = off;
        in_.consume(1);
        for (;;) {
            // Not past the next appended-data offset: a message starts there for sure.
            size_t avail = in_.ensure(ByteStream::kWindow);
            const bool capped = !appended_.empty() && appended_.front() - in_.offset() < avail;
            if (capped) avail = static_cast<size_t>(appended_.front() - in_.offset());
            const uint8_t* p = in_.data();
            const uint8_t* hit = std::search(p, p + avail, kSync, kSync + sizeof kSync);
            if (hit != p + avail || capped) {
                in_.consume(static_cast<size_t>(hit - p));
                corrupt_bytes_ += in_.offset() - off;
                notes_.add("corrupt", what + "skipped " + std::to_string(in_.offset() - off) + " bytes to the next " +
                                          (hit != p + avail ? "sync message" : "appended data") + " at byte " +
                                          std::to_string(in_.offset()) + "; samples in them are lost");
                return;
            }
            if (avail < sizeof kSync) {
                in_.consume(avail);
                corrupt_bytes_ += in_.offset() - off;
                notes_.add("corrupt", what + "no sync message follows, so the remaining " +
                                          std::to_string(in_.offset() - off) + " bytes are not read");
                return;
            }
            in_.consume(avail - (sizeof kSync - 1));
        }
    }

    void finish() {
        if (dropouts_ > 0)
            notes_.add("dropout", std::to_string(dropouts_) + " logging dropouts, " + std::to_string(dropout_ms_) +
                                      " ms in total (messages lost by the logger)");
    }

private:
    static std::string printable(char c) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7F) return std::string(1, c);
        return "\\x" + logio::hex_bytes(&u, 1);
    }

    [[noreturn]] void fail(uint64_t off, const std::string& msg) const {
        throw InputError(path_, 0, 0, "byte " + std::to_string(off) + ": " + msg);
    }

    // 'P' message: keeps the first value of each name.
    void parameter(const uint8_t* p, size_t size, uint64_t off) {
        if (!params_) return;
        const std::string at = "byte " + std::to_string(off) + ": parameter message";
        if (size < 1) {
            notes_.add("parameter", at + " is empty; skipped");
            return;
        }
        const size_t key_len = p[0];
        if (1 + key_len > size) {
            notes_.add("parameter", at + " declares a " + std::to_string(key_len) + "-byte key but has only " +
                                        std::to_string(size - 1) + " bytes after key_len; skipped");
            return;
        }
        const std::string key(reinterpret_cast<const char*>(p + 1), key_len);
        const size_t space = key.find(' ');
        const std::string type = space == std::string::npos ? std::string() : key.substr(0, space);
        const std::string name = space == std::string::npos ? std::string() : key.substr(space + 1);
        bool name_ok = !name.empty();
        for (char c : name) name_ok = name_ok && name_char_ok(c);
        if (!name_ok) {
            notes_.add("parameter", at + ": key " + escaped_quoted(key) + " is not 'type name'; skipped");
            return;
        }
        if (type != "float" && type != "int32_t") {
            notes_.add("parameter", at + " " + name + " has type " + escaped_quoted(type) +
                                        "; ULog parameters are int32_t or float; skipped");
            return;
        }
        const size_t value_len = size - 1 - key_len;
        if (value_len != 4) {
            notes_.add("parameter", at + " " + name + " has a " + std::to_string(value_len) + "-byte value, " +
                                        type + " needs 4; skipped");
            return;
        }
        if (first_params_.seen(name)) return;  // a later change; the first value is the one in force at start
        double value = 0;
        read_basic(type, p + 1 + key_len, value);
        if (!std::isfinite(value)) {
            notes_.add("parameter", at + " " + name + " = " + fixed(value, 3) + " is not a finite number; skipped");
            return;
        }
        first_params_.add(name, value, notes_, at);
    }

    void flag_bits(const uint8_t* p, size_t size, uint64_t off) {
        if (size < 40)
            fail(off, "flag-bits message has " + std::to_string(size) + " bytes, expected at least 40");
        const uint8_t* incompat = p + 8;
        bool unknown = (incompat[0] & ~1u) != 0;
        for (int i = 1; i < 8; ++i) unknown = unknown || incompat[i] != 0;
        if (unknown)
            fail(off, "the log sets incompatible flag bits this reader does not know (" +
                          logio::hex_bytes(incompat, 8) + "); the ULog spec requires refusing to parse it");
        if (incompat[0] & 1u) {
            for (int i = 0; i < 3; ++i) {
                const uint64_t a = le(p + 16 + 8 * i, 8);
                if (a != 0) appended_.push_back(a);
            }
            std::sort(appended_.begin(), appended_.end());
            if (!appended_.empty())
                notes_.add("appended", "log has appended data at byte offset(s) " + [&] {
                    std::string s;
                    for (auto a : appended_) s += (s.empty() ? "" : ", ") + std::to_string(a);
                    return s;
                }());
        }
    }

    void define(const uint8_t* p, size_t size, uint64_t off) {
        definition_bytes_ += size;
        if (definition_bytes_ > kMaxDefinitionBytes)
            fail(off, "format definitions exceed " + std::to_string(kMaxDefinitionBytes) + " bytes in total");
        const std::string s(reinterpret_cast<const char*>(p), size);
        const size_t colon = s.find(':');
        if (colon == std::string::npos)
            fail(off, "format message " + escaped_quoted(s) + " has no ':' between the message name and its fields");
        const std::string name = s.substr(0, colon);
        if (name.empty()) fail(off, "format message " + escaped_quoted(s) + " has an empty message name");
        for (char c : name)
            if (!name_char_ok(c)) fail(off, "format message name " + escaped_quoted(name) + " has invalid characters");
        UFormat fmt;
        fmt.defined_at = off;
        size_t start = colon + 1;
        while (start < s.size()) {
            size_t semi = s.find(';', start);
            if (semi == std::string::npos) semi = s.size();
            std::string item = s.substr(start, semi - start);
            start = semi + 1;
            while (!item.empty() && item.front() == ' ') item.erase(item.begin());
            while (!item.empty() && item.back() == ' ') item.pop_back();
            if (item.empty()) continue;
            const size_t space = item.rfind(' ');
            if (space == std::string::npos)
                fail(off, "format " + escaped_quoted(name) + ": field " + escaped_quoted(item) + " has no type (expected 'type name')");
            UField f;
            f.name = item.substr(space + 1);
            std::string type = item.substr(0, space);
            while (!type.empty() && type.back() == ' ') type.pop_back();
            for (char c : f.name)
                if (!name_char_ok(c))
                    fail(off, "format " + escaped_quoted(name) + ": field name " + escaped_quoted(f.name) + " has invalid characters");
            const size_t open = type.find('[');
            const size_t close = type.find(']');
            if (open != std::string::npos) {
                if (close == std::string::npos || close < open || close != type.size() - 1)
                    fail(off, "format " + escaped_quoted(name) + ": unclosed or malformed array type " + escaped_quoted(type) +
                                  " (expected type[N])");
                const std::string n = type.substr(open + 1, close - open - 1);
                long count = 0;
                bool digits = !n.empty() && n.size() <= 6;
                for (char c : n) digits = digits && c >= '0' && c <= '9';
                if (digits) count = std::stol(n);
                if (!digits || count < 1 || count > static_cast<long>(kMaxMessageBytes))
                    fail(off, "format " + escaped_quoted(name) + ": array length " + escaped_quoted(n) + " in " + escaped_quoted(type) +
                                  " must be an integer 1.." + std::to_string(kMaxMessageBytes));
                f.count = count;
                f.is_array = true;
                type = type.substr(0, open);
            } else if (close != std::string::npos) {
                fail(off, "format " + escaped_quoted(name) + ": stray ']' in type " + escaped_quoted(type));
            }
            if (type.empty()) fail(off, "format " + escaped_quoted(name) + ": field " + escaped_quoted(f.name) + " has an empty type");
            for (char c : type)
                if (!name_char_ok(c))
                    fail(off, "format " + escaped_quoted(name) + ": type " + escaped_quoted(type) + " has invalid characters");
            f.type = type;
            fmt.fields.push_back(std::move(f));
        }
        if (fmt.fields.empty()) fail(off, "format " + escaped_quoted(name) + " defines no fields");
        formats_[name] = std::move(fmt);
        sizes_.clear();  // a (re)definition may change nested sizes
    }

    // Size of one value of `type`, resolving nested formats; errors name the chain.
    size_t type_size(const std::string& type, std::vector<std::string>& chain, uint64_t off) {
        const int b = basic_size(type);
        if (b > 0) return static_cast<size_t>(b);
        auto known = sizes_.find(type);
        if (known != sizes_.end()) return known->second;
        for (const auto& c : chain)
            if (c == type) {
                std::string loop;
                for (const auto& x : chain) loop += x + " -> ";
                fail(off, "recursive format definition: " + loop + type);
            }
        if (static_cast<int>(chain.size()) >= kMaxNesting)
            fail(off, "format nesting deeper than " + std::to_string(kMaxNesting) + " levels at " + escaped_quoted(type));
        auto it = formats_.find(type);
        if (it == formats_.end())
            fail(off, "unknown type " + escaped_quoted(type) + " used in format " + escaped_quoted(chain.empty() ? type : chain.back()) +
                          " (neither a basic type nor a defined format)");
        chain.push_back(type);
        size_t total = 0;
        for (const auto& f : it->second.fields) {
            total += type_size(f.type, chain, off) * static_cast<size_t>(f.count);
            if (total > kMaxMessageBytes)
                fail(off, "format " + escaped_quoted(type) + " is larger than " + std::to_string(kMaxMessageBytes) +
                              " bytes, more than any ULog message can carry");
        }
        chain.pop_back();
        sizes_[type] = total;
        return total;
    }

    void subscribe(const uint8_t* p, size_t size, uint64_t off) {
        if (size < 3) {
            notes_.add("short", "byte " + std::to_string(off) + ": subscription message of " + std::to_string(size) +
                                    " bytes is too short; skipped");
            return;
        }
        const int multi_id = p[0];
        const uint16_t msg_id = static_cast<uint16_t>(le(p + 1, 2));
        const std::string name(reinterpret_cast<const char*>(p + 3), size - 3);
        if (name != "battery_status") {
            if (subscribed_ && msg_id == battery_id_) subscribed_ = false;  // id reused
            return;
        }
        if (multi_id != 0) {
            notes_.add("instance", "byte " + std::to_string(off) + ": battery_status instance " +
                                       std::to_string(multi_id) + " ignored (only multi_id 0 is read)");
            return;
        }
        if (formats_.find(name) == formats_.end())
            fail(off, "subscription to battery_status before its format definition");
        layout_ = resolve_battery(off);
        battery_id_ = msg_id;
        subscribed_ = true;
        subscribed_ever_ = true;
        padded_.assign(layout_.full_size, 0);
    }

    BatteryLayout resolve_battery(uint64_t off) {
        const UFormat& fmt = formats_.at("battery_status");
        std::vector<std::string> chain{"battery_status"};
        BatteryLayout l;
        size_t pos = 0;
        for (const auto& f : fmt.fields) {
            const size_t one = type_size(f.type, chain, off);
            const size_t bytes = one * static_cast<size_t>(f.count);
            Slot s;
            s.present = true;
            s.type = f.type;
            s.offset = pos;
            s.count = f.count;
            auto need_number = [&](Slot& dst, bool array_ok) {
                if (basic_size(f.type) < 0 || (f.is_array && !array_ok))
                    fail(off, "battery_status field " + escaped_quoted(f.name) + " has type " + escaped_quoted(f.type) +
                                  (f.is_array ? "[" + std::to_string(f.count) + "]" : "") + ", expected a number");
                if (!dst.present) dst = s;
            };
            if (f.name == "timestamp") {
                if (f.type != "uint64_t" || f.is_array)
                    fail(off, "battery_status field 'timestamp' must be uint64_t, found " + escaped_quoted(f.type));
                if (!l.timestamp.present) l.timestamp = s;
            } else if (f.name == "voltage_v") {
                need_number(l.voltage, false);
            } else if (f.name == "current_a") {
                need_number(l.current, false);
            } else if (f.name == "discharged_mah") {
                need_number(l.discharged, false);
            } else if (f.name == "temperature") {
                need_number(l.temperature, false);
            } else if (f.name == "cell_count") {
                need_number(l.cell_count, false);
            } else if (f.name == "voltage_cell_v") {
                need_number(l.cells, true);
            }
            pos += bytes;
            if (pos > kMaxMessageBytes)
                fail(off, "format 'battery_status' is larger than " + std::to_string(kMaxMessageBytes) +
                              " bytes, more than any ULog message can carry");
            if (f.name.compare(0, 8, "_padding") != 0) l.min_size = pos;
        }
        l.full_size = pos;
        const char* missing = !l.timestamp.present ? "timestamp" : !l.voltage.present ? "voltage_v"
                                                              : !l.current.present ? "current_a" : nullptr;
        if (missing) fail(off, std::string("battery_status format has no field '") + missing + "'");
        return l;
    }

    bool decode(const uint8_t* data, size_t n, uint64_t off, BatteryRecord& rec) {
        if (n < layout_.min_size) {
            notes_.add("short", "byte " + std::to_string(off) + ": battery_status data has " + std::to_string(n) +
                                    " bytes, its format needs at least " + std::to_string(layout_.min_size) +
                                    " (" + std::to_string(layout_.full_size) + " with padding); dropped");
            return false;
        }
        if (n > layout_.full_size) {
            notes_.add("long", "byte " + std::to_string(off) + ": battery_status data has " + std::to_string(n) +
                                   " bytes, its format only " + std::to_string(layout_.full_size) +
                                   "; extra bytes ignored");
            n = layout_.full_size;
        }
        std::memcpy(padded_.data(), data, n);
        std::fill(padded_.begin() + static_cast<long>(n), padded_.end(), 0);
        const uint8_t* p = padded_.data();
        rec = BatteryRecord();
        rec.offset = off;
        rec.timestamp = static_cast<double>(le(p + layout_.timestamp.offset, 8));
        read_basic(layout_.voltage.type, p + layout_.voltage.offset, rec.voltage);
        read_basic(layout_.current.type, p + layout_.current.offset, rec.current);
        if (layout_.temperature.present) {
            rec.has_temperature_field = true;
            read_basic(layout_.temperature.type, p + layout_.temperature.offset, rec.temperature);
        }
        if (layout_.cell_count.present) {
            double c = 0;
            read_basic(layout_.cell_count.type, p + layout_.cell_count.offset, c);
            rec.cell_count = std::isfinite(c) && c > 0 ? static_cast<long>(std::min(c, 1e6)) : 0;
        }
        if (layout_.cells.present) {
            const int sz = basic_size(layout_.cells.type);
            rec.cells_in_array = std::min<long>(layout_.cells.count, 64);
            for (long i = 0; i < rec.cells_in_array; ++i)
                read_basic(layout_.cells.type, p + layout_.cells.offset + static_cast<size_t>(i * sz), rec.cells[i]);
        }
        return true;
    }

    std::string path_;
    ByteStream in_;
    NoteLog& notes_;
    int version_ = 0;
    size_t pending_ = 0;
    bool seen_message_ = false;
    std::vector<uint64_t> appended_;
    std::unordered_map<std::string, UFormat> formats_;
    std::unordered_map<std::string, size_t> sizes_;
    size_t definition_bytes_ = 0;
    bool subscribed_ = false;
    bool subscribed_ever_ = false;
    uint64_t corrupt_bytes_ = 0, first_corrupt_ = 0;
    int64_t cut_at_ = -1;
    uint16_t battery_id_ = 0;
    BatteryLayout layout_;
    std::vector<uint8_t> padded_;
    long dropouts_ = 0;
    long dropout_ms_ = 0;
    Parameters* params_;
    logio::FirstParameters first_params_;
};

// Cells of a record: the first cell_count entries (whole array without cell_count), leading
// cells > 0 only. `beyond` = valid cells past core::kMaxCells.
int record_cells(const BatteryRecord& r, float* out, int& beyond) {
    long n = r.cell_count >= 0 ? std::min(r.cell_count, r.cells_in_array) : r.cells_in_array;
    int k = 0;
    beyond = 0;
    for (long i = 0; i < n; ++i) {
        const double v = r.cells[i];
        if (!std::isfinite(v) || v <= 0) break;
        if (k < core::kMaxCells)
            out[k++] = static_cast<float>(v);
        else
            ++beyond;
    }
    return k;
}

class UlogReader final : public SampleReader {
public:
    explicit UlogReader(const std::string& path) : path_(path), notes_(&info_.notes) {
        info_.path = path;
        info_.format = LogFormat::Ulog;
        scan();
        stream_ = std::make_unique<UlogStream>(path, notes_, &info_.parameters);
    }

    bool next(core::Sample& out) override {
        if (order_.pop(out)) return true;
        if (done_) return false;
        BatteryRecord r;
        core::Sample sample;
        while (stream_->next(r)) {
            if (emit(r, sample)) {
                order_.offer(sample, r.timestamp, "byte " + std::to_string(r.offset));
                if (order_.pop(out)) return true;
            }
        }
        order_.finish();
        done_ = true;
        stream_->finish();
        notes_.finish();
        if (order_.accepted() == 0)
            throw InputError(path_, 0, 0, "no usable battery_status samples: all " + std::to_string(rows_) +
                                              " were dropped" + (first_drop_.empty() ? "" : " (first: " + first_drop_ + ")"));
        return order_.pop(out);
    }

    const SourceInfo& info() const override { return info_; }
    void add_note(const std::string& text) { info_.notes.push_back(text); }

private:
    void scan() {
        NoteLog silent(nullptr);
        UlogStream s(path_, silent);
        BatteryRecord r;
        long rows = 0, unknown_current = 0, with_cells = 0, equal_cells = 0, temps = 0;
        int max_cells = 0;
        while (s.next(r)) {
            ++rows;
            if (r.current == -1.0) ++unknown_current;
            if (r.has_temperature_field && std::isfinite(r.temperature)) ++temps;
            float cells[core::kMaxCells];
            int beyond;
            const int n = record_cells(r, cells, beyond);
            max_cells = std::max(max_cells, n);
            if (n >= 2) {
                ++with_cells;
                bool same = true;
                for (int i = 1; i < n; ++i) same = same && cells[i] == cells[0];
                if (same) ++equal_cells;
            }
        }
        if (rows == 0) {
            // Corrupt headers skipped may have held the subscription or the data: say so.
            const std::string corrupt =
                s.corrupt_bytes() == 0 ? std::string()
                                       : " (or not where it can be read: the log is corrupt at byte " +
                                             std::to_string(s.first_corrupt()) + ", and " +
                                             std::to_string(s.corrupt_bytes()) +
                                             " bytes were skipped to find its messages again)";
            const std::string cut = s.cut_at() < 0 ? std::string()
                                                   : "; the file ends inside a message at byte " + std::to_string(s.cut_at()) +
                                                         ": it is cut short, and the battery data may be in the part missing";
            // A file cut short may hold the topic in the part missing: "not logged" would
            // contradict the cut it goes on to name, so it is said only of a whole file.
            const std::string why = !cut.empty()          ? std::string()
                                    : s.saw_subscription() ? ": the topic is subscribed but never logged"
                                                           : ": the topic is not logged";
            throw InputError(path_, 0, 0, "no battery_status data (multi_id 0) in this ULog" + why + corrupt + cut);
        }
        // PX4 fills every cell with pack / count when it cannot measure cells: such cells
        // say nothing of any cell, and their sum, rounded apart from the pack's, read as a
        // sensor fault. They are left out, so the monitor sees the pack alone.
        synthetic_cells_ = with_cells > 0 && equal_cells == with_cells;
        info_.cell_count = synthetic_cells_ ? 0 : max_cells;
        info_.has_temperature = temps > 0;
        if (unknown_current > 0)
            info_.notes.push_back(
                "current_a = -1 (PX4: no current measurement) in " + std::to_string(unknown_current) + " of " +
                std::to_string(rows) + " battery_status samples: those samples carry 0 A, which here means unknown");
        if (synthetic_cells_)
            info_.notes.push_back("battery_status.voltage_cell_v holds the same value for every cell in every sample: "
                                  "PX4 fills it with pack voltage / cell count when it cannot measure cells, so the "
                                  "cell voltages carry no per-cell information and are left out");
    }

    void drop(const char* kind, const std::string& text) {
        if (first_drop_.empty()) first_drop_ = text;
        notes_.add(kind, text);
    }

    bool emit(const BatteryRecord& r, core::Sample& out) {
        ++rows_;
        const std::string where = "byte " + std::to_string(r.offset);
        if (!std::isfinite(r.voltage) || r.voltage < 0 || r.voltage > 1000) {
            drop("bad-value", where + ": battery_status.voltage_v = " + fixed(r.voltage, 3) +
                                  " V is not a plausible pack voltage (finite, 0..1000 V); sample dropped");
            return false;
        }
        double current = r.current;
        if (current == -1.0) {
            current = 0.0;  // PX4: unknown; see the note from the pre-scan
        } else if (!std::isfinite(current) || std::fabs(current) > 10000) {
            drop("bad-value", where + ": battery_status.current_a = " + fixed(current, 3) +
                                  " A is not a plausible current; sample dropped");
            return false;
        }
        out = core::Sample();
        out.voltage_v = static_cast<float>(r.voltage);
        out.current_a = static_cast<float>(current);
        int beyond = 0;
        out.cell_count = synthetic_cells_ ? 0 : static_cast<uint8_t>(record_cells(r, out.cell_voltage_v, beyond));
        if (synthetic_cells_) std::fill(std::begin(out.cell_voltage_v), std::end(out.cell_voltage_v), 0.0f);
        if (beyond > 0) info_.cells_beyond_kept = std::max(info_.cells_beyond_kept, core::kMaxCells + beyond);
        if (beyond > 0)
            notes_.add("cells", where + ": battery_status reports " + std::to_string(core::kMaxCells + beyond) +
                                    " cells; cells beyond " + std::to_string(core::kMaxCells) + " are dropped");
        if (r.has_temperature_field && std::isfinite(r.temperature)) {
            out.has_temperature = true;
            out.temperature_c = static_cast<float>(r.temperature);
        }
        return true;
    }

    std::string path_;
    SourceInfo info_;
    NoteLog notes_;
    std::unique_ptr<UlogStream> stream_;
    bool synthetic_cells_ = false;  // every cell equal in every sample: PX4's pack / count
    long rows_ = 0;
    TimeOrder order_{"battery_status timestamp", "sample", [this](const char* kind, const std::string& text) { drop(kind, text); }};
    bool done_ = false;
    std::string first_drop_;
};

}  // namespace

std::unique_ptr<SampleReader> open_ulog(const std::string& path, const ReaderOptions& options) {
    auto r = std::make_unique<UlogReader>(path);
    if (options.current_source == CurrentSource::Shunt)
        r->add_note("the shunt current source applies to raw monitor logs only; battery_status.current_a is used");
    return r;
}

}  // namespace host
}  // namespace battsim
