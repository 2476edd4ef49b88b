// Temporary directories, files and program runs for the unit and CLI tests: one copy of
// what each test file used to write for itself.
#pragma once
#include <stdlib.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace testsupport {

// The whole file; "" if it cannot be opened.
inline std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Writes `content` byte for byte, creating the parent directories.
inline void write_file(const std::string& path, const std::string& content) {
    const std::filesystem::path p(path);
    if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
}

// A new directory /tmp/battsim-<tag>-XXXXXX (mkdtemp: unique across processes, so tests
// run in parallel never share one). Throws if it cannot be made.
inline std::string make_temp_dir(const std::string& tag) {
    std::string tmpl = (std::filesystem::temp_directory_path() / ("battsim-" + tag + "-XXXXXX")).string();
    if (!::mkdtemp(&tmpl[0])) throw std::runtime_error("cannot create a temporary directory " + tmpl);
    return tmpl;
}

// A fresh directory, removed with everything in it when the object goes.
class TempDir {
public:
    explicit TempDir(const std::string& tag = "test") : dir_(make_temp_dir(tag)) {}
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(dir_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    // The directory itself, or `name` inside it.
    std::string path(const std::string& name = "") const { return name.empty() ? dir_ : dir_ + "/" + name; }
    // Writes `content` to `name` inside (subdirectories made as needed); returns its path.
    std::string write(const std::string& name, const std::string& content) const {
        write_file(path(name), content);
        return path(name);
    }

private:
    std::string dir_;
};

// A fresh directory that lasts until the test program exits, then is removed: for helpers
// that hand out paths rather than keep an object alive.
inline std::string scratch_dir(const std::string& tag = "test") {
    struct Registry {
        std::mutex mutex;  // some tests run programs from a second thread
        std::vector<std::string> dirs;
        ~Registry() {
            std::error_code ec;
            for (const std::string& d : dirs) std::filesystem::remove_all(d, ec);
        }
    };
    static Registry registry;
    const std::string dir = make_temp_dir(tag);
    const std::lock_guard<std::mutex> lock(registry.mutex);
    registry.dirs.push_back(dir);
    return dir;
}

inline std::string shell_quoted(const std::string& s) { return "'" + s + "'"; }

struct RunResult {
    int exit_code = -1;  // -1: did not run or did not exit normally
    std::string out;     // standard output
    std::string err;     // standard error
};

// Runs `program args` through the shell (`args` are shell words: quote paths yourself);
// standard error is captured through a file.
inline RunResult run_program(const std::string& program, const std::string& args) {
    static const std::string dir = scratch_dir("run");
    const std::string err_path = dir + "/stderr.txt";
    const std::string cmd = shell_quoted(program) + " " + args + " 2>" + shell_quoted(err_path);
    RunResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
    const int status = pclose(p);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = read_file(err_path);
    return r;
}

}  // namespace testsupport
