// Small helpers shared by the DataFlash and ULog readers (host only, internal):
// capped note list, byte quoting for messages, and a bounded-window buffered file input.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>
#include <unordered_set>
#include <utility>
#include <vector>

#include "host/io/sample_reader.h"

namespace battsim {
namespace host {
namespace logio {

// Notes with a cap per kind, so a badly damaged file cannot grow the list without bound.
// A NoteLog over nullptr keeps no text (used by pre-scan passes), only the counts.
class NoteLog {
public:
    static constexpr long kPerKind = 8;
    explicit NoteLog(std::vector<std::string>* out) : out_(out) {}
    void add(const char* kind, const std::string& text) {
        for (auto& k : kinds_) {
            if (k.name == kind) {
                if (++k.count <= kPerKind && out_) out_->push_back(text);
                return;
            }
        }
        kinds_.push_back({kind, 1});
        if (out_) out_->push_back(text);
    }
    // How many notes of `kind` were added (listed or not).
    long count(const char* kind) const {
        for (const auto& k : kinds_)
            if (k.name == kind) return k.count;
        return 0;
    }
    // Appends "... and N more" for every kind that hit the cap. Idempotent.
    void finish() {
        if (!out_ || finished_) return;
        finished_ = true;
        for (const auto& k : kinds_)
            if (k.count > kPerKind)
                out_->push_back("... and " + std::to_string(k.count - kPerKind) +
                                " more notes of the same kind (" + k.name + ") not listed");
    }

private:
    struct Kind {
        std::string name;
        long count;
    };
    std::vector<std::string>* out_;
    std::vector<Kind> kinds_;
    bool finished_ = false;
};

// The parameters a log recorded: the first value of each name (later ones are changes in
// flight), at most kMax names, so a corrupt file cannot grow memory without bound.
class FirstParameters {
public:
    static constexpr size_t kMax = 100000;  // far above any autopilot's (ArduPilot ~1500)
    explicit FirstParameters(std::vector<std::pair<std::string, double>>* out) : out_(out) {}
    bool seen(const std::string& name) const { return names_.count(name) != 0; }
    // Keeps a name not seen before; past the cap, notes it once (under `where`) and drops it.
    void add(const std::string& name, double value, NoteLog& notes, const std::string& where);

private:
    std::vector<std::pair<std::string, double>>* out_;
    std::unordered_set<std::string> names_;
    bool capped_ = false;
};

inline void FirstParameters::add(const std::string& name, double value, NoteLog& notes, const std::string& where) {
    if (names_.count(name)) return;
    if (names_.size() >= kMax) {
        if (!capped_)
            notes.add("parameter", where + ": more than " + std::to_string(kMax) +
                                       " distinct parameter names; further parameters ignored");
        capped_ = true;
        return;
    }
    names_.insert(name);
    out_->emplace_back(name, value);
}

// Quotes bytes for a message: printable ASCII as is, anything else as \xNN.
inline std::string escaped_quoted(std::string_view s, size_t max_len = 40) {
    static const char* hex = "0123456789ABCDEF";
    std::string r = "'";
    for (size_t i = 0; i < s.size() && i < max_len; ++i) {
        unsigned char c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7F) {
            r += static_cast<char>(c);
        } else {
            r += "\\x";
            r += hex[c >> 4];
            r += hex[c & 15];
        }
    }
    if (s.size() > max_len) r += "...";
    return r + "'";
}

inline std::string hex_bytes(const uint8_t* p, size_t n) {
    static const char* hex = "0123456789ABCDEF";
    std::string r;
    for (size_t i = 0; i < n; ++i) {
        if (i) r += ' ';
        r += hex[p[i] >> 4];
        r += hex[p[i] & 15];
    }
    return r;
}

inline std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

// Little-endian unsigned integer of n <= 8 bytes.
inline uint64_t le(const uint8_t* p, int n) {
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

// Buffered file input with a fixed window: memory does not depend on the file length.
class ByteStream {
public:
    static constexpr size_t kWindow = 160 * 1024;  // > largest request (ULog message 65535+3)
    explicit ByteStream(const std::string& path) : path_(path), buf_(kWindow) {
        f_.open(path, std::ios::binary);
        if (!f_) throw InputError(path, 0, 0, "cannot open file");
    }
    // Makes at least n bytes (n <= kWindow) available if the file has them; returns how many are.
    size_t ensure(size_t n) {
        if (end_ - pos_ >= n || eof_) return end_ - pos_;
        if (pos_ > 0) {
            std::memmove(buf_.data(), buf_.data() + pos_, end_ - pos_);
            base_ += pos_;
            end_ -= pos_;
            pos_ = 0;
        }
        n = std::min(n, buf_.size());
        while (end_ < n && !eof_) {
            f_.read(reinterpret_cast<char*>(buf_.data() + end_), static_cast<std::streamsize>(buf_.size() - end_));
            const std::streamsize got = f_.gcount();
            if (f_.bad()) throw InputError(path_, 0, 0, "read error near byte " + std::to_string(base_ + end_));
            if (got <= 0) eof_ = true;
            end_ += static_cast<size_t>(std::max<std::streamsize>(got, 0));
        }
        return end_ - pos_;
    }
    const uint8_t* data() const { return buf_.data() + pos_; }
    void consume(size_t n) { pos_ += std::min(n, end_ - pos_); }
    uint64_t offset() const { return base_ + pos_; }
    // Skips forward to absolute offset `target` (>= offset()); false if the file ends first.
    bool seek_forward(uint64_t target) {
        while (offset() < target) {
            size_t avail = ensure(1);
            if (avail == 0) return false;
            consume(static_cast<size_t>(std::min<uint64_t>(avail, target - offset())));
        }
        return true;
    }

private:
    std::string path_;
    std::ifstream f_;
    std::vector<uint8_t> buf_;
    size_t pos_ = 0, end_ = 0;
    uint64_t base_ = 0;
    bool eof_ = false;
};

}  // namespace logio
}  // namespace host
}  // namespace battsim
