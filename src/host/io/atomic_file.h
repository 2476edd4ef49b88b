// Outputs are written to a temporary file beside the target and renamed into place on
// commit, so a crash or a bad input never leaves a half-written file behind.
#pragma once
#include <cstdio>
#include <string>

namespace battsim {
namespace host {

class AtomicFile {
public:
    explicit AtomicFile(const std::string& path);  // throws std::runtime_error if it cannot create
    ~AtomicFile();                                 // discards the temporary if not committed
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::FILE* handle() { return file_; }
    // Another program (e.g. gnuplot) may write the temporary by this name instead of
    // handle(); commit() then syncs and renames whatever it wrote.
    const std::string& temp_path() const { return temp_path_; }
    void write(const std::string& text);
    void write(const char* data, size_t size);
    void commit();  // flush, fsync, rename; throws std::runtime_error on failure
    const std::string& path() const { return path_; }

private:
    std::string path_;
    std::string temp_path_;
    std::FILE* file_ = nullptr;
    bool committed_ = false;
};

// Writes `text` to `path` atomically ("-" = standard output).
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace host
}  // namespace battsim
