#include "host/io/line_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

LineReader::LineReader(const std::string& path, std::size_t max_line_bytes)
    : path_(path), max_line_bytes_(max_line_bytes == 0 ? kDefaultMaxLineBytes : max_line_bytes) {
    errno = 0;
    file_ = std::fopen(path.c_str(), "rb");
    if (file_ == nullptr) {
        const int err = errno;
        throw InputError(path, 0, 0, std::string("cannot open file: ") + (err ? std::strerror(err) : "unknown error"));
    }
    struct stat st;
    if (::fstat(::fileno(file_), &st) == 0 && S_ISDIR(st.st_mode)) {
        std::fclose(file_);
        file_ = nullptr;
        throw InputError(path, 0, 0, "cannot open file: it is a directory, expected a log file");
    }
    capacity_ = kBlockBytes < max_line_bytes_ + 2 ? kBlockBytes : max_line_bytes_ + 2;
    buf_.reset(new char[capacity_]);
}

LineReader::~LineReader() {
    if (file_ != nullptr) std::fclose(file_);
}

bool LineReader::refill() {
    if (eof_) return false;
    // Keep the unconsumed tail (a partial line) at the front of the buffer.
    if (begin_ > 0) {
        std::memmove(buf_.get(), buf_.get() + begin_, end_ - begin_);
        end_ -= begin_;
        begin_ = 0;
    }
    if (end_ == capacity_) {
        // One line fills the whole buffer: grow, but never beyond the line limit.
        std::size_t limit = max_line_bytes_ + 2;  // the line plus "\r\n"
        std::size_t grown = capacity_ * 2 < limit ? capacity_ * 2 : limit;
        if (grown <= capacity_) {
            throw InputError(path_, line_number_ + 1, 0,
                             "line is longer than " + std::to_string(max_line_bytes_) +
                                 " bytes; expected a text log with one record per line");
        }
        std::unique_ptr<char[]> bigger(new char[grown]);
        std::memcpy(bigger.get(), buf_.get(), end_);
        buf_ = std::move(bigger);
        capacity_ = grown;
    }
    const std::size_t want = capacity_ - end_;
    errno = 0;
    const std::size_t got = std::fread(buf_.get() + end_, 1, want, file_);
    end_ += got;
    if (got < want) {
        if (std::ferror(file_)) {
            const int err = errno;
            throw InputError(path_, line_number_ + 1, 0,
                             std::string("read error: ") + (err ? std::strerror(err) : "unknown error"));
        }
        eof_ = true;
    }
    return got > 0;
}

bool LineReader::next(std::string_view& line) {
    if (!started_) {
        started_ = true;
        refill();
        if (end_ >= 3 && static_cast<unsigned char>(buf_[0]) == 0xEF &&
            static_cast<unsigned char>(buf_[1]) == 0xBB && static_cast<unsigned char>(buf_[2]) == 0xBF) {
            begin_ = 3;
            bytes_consumed_ = 3;
            had_bom_ = true;
        }
    }
    std::size_t scan_from = begin_;
    for (;;) {
        const char* base = buf_.get();
        const void* hit = end_ > scan_from ? std::memchr(base + scan_from, '\n', end_ - scan_from) : nullptr;
        if (hit != nullptr) {
            const std::size_t pos = static_cast<std::size_t>(static_cast<const char*>(hit) - base);
            std::size_t len = pos - begin_;
            const std::size_t start = begin_;
            if (len > max_line_bytes_ + 1) {
                throw InputError(path_, line_number_ + 1, 0,
                                 "line is longer than " + std::to_string(max_line_bytes_) +
                                     " bytes; expected a text log with one record per line");
            }
            begin_ = pos + 1;
            bytes_consumed_ += len + 1;
            if (len > 0 && base[start + len - 1] == '\r') --len;
            line = std::string_view(base + start, len);
            ++line_number_;
            had_newline_ = true;
            return true;
        }
        if (end_ - begin_ > max_line_bytes_ + 1) {
            throw InputError(path_, line_number_ + 1, 0,
                             "line is longer than " + std::to_string(max_line_bytes_) +
                                 " bytes; expected a text log with one record per line");
        }
        if (eof_) {
            if (begin_ == end_) return false;
            // Last line, no newline after it.
            std::size_t len = end_ - begin_;
            const std::size_t start = begin_;
            begin_ = end_;
            bytes_consumed_ += len;
            if (base[start + len - 1] == '\r') --len;
            line = std::string_view(base + start, len);
            ++line_number_;
            had_newline_ = false;
            return true;
        }
        const std::size_t scanned = end_ - begin_;
        refill();
        scan_from = begin_ + scanned;
    }
}

std::pair<long, long> line_column(std::string_view text, std::size_t offset) {
    long line = 1, col = 1;
    for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    return {line, col};
}

}  // namespace host
}  // namespace battsim
