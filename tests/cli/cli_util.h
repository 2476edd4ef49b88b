// Runs the battsim binary from the outside, as a user or a script would.
#pragma once
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace clitest {

struct Result {
    int exit_code = -1;
    std::string out;  // standard output
    std::string err;  // standard error
};

inline std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline std::string temp_dir() {
    char tmpl[] = "/tmp/battsim-cli-XXXXXX";
    const char* d = mkdtemp(tmpl);
    return d ? d : "/tmp";
}

inline void write_file(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

// `args` is appended to the binary path as shell words; quote paths yourself.
inline Result run(const std::string& args) {
    static const std::string dir = temp_dir();
    const std::string err_path = dir + "/stderr.txt";
    const std::string cmd = std::string("'") + BATTSIM_BINARY + "' " + args + " 2>'" + err_path + "'";
    Result r;
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

inline std::string q(const std::string& s) { return "'" + s + "'"; }

}  // namespace clitest
