// Streaming text line reader for the text log readers (CSV, DataFlash text).
// Reads the file in fixed-size blocks and hands out each line as a view into its own
// buffer, so memory does not grow with the file and no line is copied into a
// std::string. Line ends "\n" and "\r\n" are both accepted; a UTF-8 byte-order mark at
// the start of the file is skipped. A final line without a newline is still returned,
// and line_had_newline() says so, so a reader can treat it as possibly cut off.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

namespace battsim {
namespace host {

// 1-based line and column of byte `offset` in `text` ("\n" ends a line), for messages
// about a document parsed whole (JSON manifests and tables).
std::pair<long, long> line_column(std::string_view text, std::size_t offset);

class LineReader {
public:
    static constexpr std::size_t kBlockBytes = 256 * 1024;
    static constexpr std::size_t kDefaultMaxLineBytes = 1024 * 1024;

    // Opens `path`; throws InputError if it cannot be opened or is a directory.
    explicit LineReader(const std::string& path, std::size_t max_line_bytes = kDefaultMaxLineBytes);
    ~LineReader();
    LineReader(const LineReader&) = delete;
    LineReader& operator=(const LineReader&) = delete;

    // Sets `line` to the next line without its line end and returns true; false at the
    // end of the file. The view stays valid until the next call. Throws InputError on a
    // read error or a line longer than the limit.
    bool next(std::string_view& line);

    // 1-based number of the line last returned by next() (0 before the first call).
    long line_number() const { return line_number_; }
    // False only when the line last returned ended at the end of the file without "\n".
    bool line_had_newline() const { return had_newline_; }
    // True once a byte-order mark was skipped at the start of the file.
    bool had_bom() const { return had_bom_; }
    // Bytes of the file consumed so far (including line ends and any BOM).
    std::uint64_t bytes_consumed() const { return bytes_consumed_; }
    const std::string& path() const { return path_; }

private:
    bool refill();  // false when no more bytes could be read (end of file)

    std::string path_;
    std::FILE* file_ = nullptr;
    std::size_t max_line_bytes_;
    std::unique_ptr<char[]> buf_;
    std::size_t capacity_ = 0;
    std::size_t begin_ = 0;  // first unconsumed byte
    std::size_t end_ = 0;    // one past the last valid byte
    bool eof_ = false;
    bool started_ = false;
    bool had_bom_ = false;
    bool had_newline_ = true;
    long line_number_ = 0;
    std::uint64_t bytes_consumed_ = 0;
};

}  // namespace host
}  // namespace battsim
