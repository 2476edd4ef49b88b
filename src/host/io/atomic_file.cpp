#include "host/io/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <stdexcept>

namespace battsim {
namespace host {

namespace {
std::string temp_name(const std::string& path) {
    // Unique per process and per call, so parallel writers never share a temporary.
    static std::atomic<unsigned> counter{0};
    return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}
}  // namespace

AtomicFile::AtomicFile(const std::string& path) : path_(path), temp_path_(temp_name(path)) {
    file_ = std::fopen(temp_path_.c_str(), "wb");
    if (!file_) throw std::runtime_error(path + ": cannot create output (" + std::strerror(errno) + ")");
}

AtomicFile::~AtomicFile() {
    if (file_) std::fclose(file_);
    if (!committed_) std::remove(temp_path_.c_str());
}

void AtomicFile::write(const std::string& text) { write(text.data(), text.size()); }

void AtomicFile::write(const char* data, size_t size) {
    if (size && std::fwrite(data, 1, size, file_) != size)
        throw std::runtime_error(path_ + ": write failed (" + std::strerror(errno) + ")");
}

void AtomicFile::commit() {
    if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0) {
        throw std::runtime_error(path_ + ": write failed (" + std::strerror(errno) + ")");
    }
    std::fclose(file_);
    file_ = nullptr;
    if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
        throw std::runtime_error(path_ + ": cannot move output into place (" + std::strerror(errno) + ")");
    }
    committed_ = true;
}

void write_file_atomic(const std::string& path, const std::string& text) {
    if (path == "-") {
        std::cout << text;
        std::cout.flush();
        return;
    }
    AtomicFile f(path);
    f.write(text);
    f.commit();
}

}  // namespace host
}  // namespace battsim
