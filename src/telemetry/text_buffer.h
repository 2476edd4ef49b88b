// Fixed-capacity text building for the firmware's lines and display rows and the
// telemetry's sentences: no heap, truncation is remembered (a truncated line is never
// sent), always NUL-terminated.
#pragma once
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

namespace battsim {
namespace telemetry {

class TextBuffer {
public:
    TextBuffer(char* storage, size_t capacity) : buf_(storage), cap_(capacity) { clear(); }

    void clear() {
        len_ = 0;
        overflow_ = cap_ == 0;
        if (cap_ > 0) buf_[0] = '\0';
    }
    void append(const char* s) {
        while (*s) append_char(*s++);
    }
    void append(const char* s, size_t n) {
        for (size_t i = 0; i < n; ++i) append_char(s[i]);
    }
    void append_char(char c) {
        if (len_ + 1 >= cap_) {
            overflow_ = true;
            return;
        }
        buf_[len_++] = c;
        buf_[len_] = '\0';
    }
    // printf-style; floats must be passed as double explicitly (the core builds with
    // -Werror=double-promotion, and so does the firmware).
    void appendf(const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
        if (overflow_) return;
        va_list ap;
        va_start(ap, fmt);
        const int n = vsnprintf(buf_ + len_, cap_ - len_, fmt, ap);
        va_end(ap);
        if (n < 0 || static_cast<size_t>(n) >= cap_ - len_) {
            overflow_ = true;
            buf_[len_] = '\0';
            return;
        }
        len_ += static_cast<size_t>(n);
    }
    void append_uint(uint64_t v) {
        char digits[21];
        int n = 0;
        do {
            digits[n++] = static_cast<char>('0' + v % 10u);
            v /= 10u;
        } while (v != 0u);
        while (n > 0) append_char(digits[--n]);
    }
    // value / 10^decimals written exactly ("16.66000" for 1666000 with 5 decimals):
    // integer readings become decimals without a float in between.
    void append_fixed(int64_t value, int decimals) {
        uint64_t mag = value < 0 ? static_cast<uint64_t>(-(value + 1)) + 1u : static_cast<uint64_t>(value);
        if (value < 0) append_char('-');
        uint64_t scale = 1;
        for (int i = 0; i < decimals; ++i) scale *= 10u;
        append_uint(mag / scale);
        if (decimals <= 0) return;
        append_char('.');
        uint64_t frac = mag % scale;
        for (int i = decimals - 1; i >= 0; --i) {
            uint64_t p = 1;
            for (int k = 0; k < i; ++k) p *= 10u;
            append_char(static_cast<char>('0' + (frac / p) % 10u));
        }
    }

    const char* c_str() const { return buf_; }
    size_t size() const { return len_; }
    bool overflow() const { return overflow_; }

private:
    char* buf_;
    size_t cap_;
    size_t len_ = 0;
    bool overflow_ = false;
};

// A TextBuffer with its own storage.
template <size_t N>
class FixedText : public TextBuffer {
public:
    FixedText() : TextBuffer(storage_, N) {}
    FixedText(const FixedText&) = delete;
    FixedText& operator=(const FixedText&) = delete;

private:
    char storage_[N];
};

}  // namespace telemetry
}  // namespace battsim
