#include "host/io/output_paths.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "host/io/atomic_file.h"

namespace battsim {
namespace host {

namespace fs = std::filesystem;

namespace {
// One key per file: device and inode for an existing file (what std::filesystem::equivalent
// compares), the resolved path for one to be created; "" = not compared. Keys let a batch
// of thousands of logs be checked in one pass instead of pair by pair.
std::string file_key(const std::string& path) {
    if (path.empty() || path == "-") return "";
    const auto identity = [](const struct stat& st) {
        return S_ISREG(st.st_mode) ? "i" + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino) : std::string();
    };
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) return identity(st);
    // Not there (yet): by the name the write would use, made canonical, so "x/../a.csv",
    // a symlinked directory or a dangling link name the file they lead to.
    std::string resolved;
    try {
        resolved = resolve_output_path(path);
    } catch (const std::runtime_error&) {
        return "";  // a loop of links: the writer reports it
    }
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(resolved, ec);
    if (ec) return "p" + resolved;
    if (::stat(canonical.c_str(), &st) == 0) return identity(st);
    return "p" + canonical.string();
}
}  // namespace

bool names_standard_output(const std::string& path) {
    if (path.empty()) return false;
    if (path == "-") return true;
    struct stat named {}, out {};
    if (::stat(path.c_str(), &named) != 0 || ::fstat(STDOUT_FILENO, &out) != 0 || named.st_dev != out.st_dev ||
        named.st_ino != out.st_ino)
        return false;
    // Two writers lose data on a file (the atomic rename replaces what the shell opened) and
    // interleave on a pipe or a terminal; /dev/null with standard output sent there too is fine.
    return S_ISREG(out.st_mode) || S_ISFIFO(out.st_mode) || S_ISSOCK(out.st_mode) || ::isatty(STDOUT_FILENO);
}

void check_output_paths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
    const NamedPath* to_stdout = nullptr;
    for (const NamedPath& out : outputs) {
        if (out.path == "-" && out.dash == Dash::Refused)
            throw std::invalid_argument(out.what + ": expected a path, found \"-\" (this output cannot go to standard output)");
        if (!names_standard_output(out.path)) continue;
        if (to_stdout) {
            const auto named = [](const NamedPath& o) { return o.what + (o.path == "-" ? "" : " (" + o.path + ")"); };
            throw std::invalid_argument(named(out) + " and " + named(*to_stdout) +
                                        " would both write to standard output; at most one output may go there");
        }
        to_stdout = &out;
    }
    std::map<std::string, const NamedPath*> read, written;
    for (const NamedPath& in : inputs) {
        const std::string key = file_key(in.path);
        if (!key.empty()) read.emplace(key, &in);
    }
    for (const NamedPath& out : outputs) {
        const std::string key = file_key(out.path);
        if (key.empty()) continue;
        auto w = written.find(key);
        if (w != written.end())
            throw std::invalid_argument(out.what + " and " + w->second->what + " name the same file: " + out.path);
        auto r = read.find(key);
        if (r != read.end() && !(out.config && r->second->config))
            throw std::invalid_argument(out.what + " and " + r->second->what + " name the same file: " + out.path);
        written.emplace(key, &out);
    }
}

std::string unwritable_reason(const std::string& path) {
    if (path.empty() || path == "-") return "";
    std::string resolved;
    try {
        resolved = resolve_output_path(path);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    struct stat st {};
    if (::stat(resolved.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) return resolved + " is a directory";
        if (!S_ISREG(st.st_mode)) return "";  // written straight: /dev/null, a FIFO
    }
    const fs::path parent = fs::path(resolved).parent_path();
    const std::string dir = parent.empty() ? "." : parent.string();
    if (::stat(dir.c_str(), &st) != 0) return "the directory " + dir + " does not exist";
    if (!S_ISDIR(st.st_mode)) return dir + " is not a directory";
    // The temporary beside the file is created there, then renamed over it.
    if (::access(dir.c_str(), W_OK | X_OK) != 0) return "no permission to write in " + dir;
    // A name the filesystem cannot hold fails only at the rename, after the work (the
    // temporary's own name is cut to fit): a whole fleet's batch had been lost to it.
    const std::string name = fs::path(resolved).filename().string();
    const long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
    if (name_max > 0 && static_cast<long>(name.size()) > name_max)
        return "the file name is " + std::to_string(name.size()) + " bytes, longer than the " + std::to_string(name_max) +
               " its directory's filesystem allows";
    return "";
}

std::string unwritable_directory_reason(const std::string& path) {
    if (path.empty()) return "";
    struct stat st {};
    fs::path p(path);
    if (::stat(p.c_str(), &st) == 0) {
        if (!S_ISDIR(st.st_mode)) return path + " is not a directory";
        if (::access(p.c_str(), W_OK | X_OK) != 0) return "no permission to write in " + path;
        return "";
    }
    // Made with its parents: the nearest one there must be a directory to write in.
    for (p = p.lexically_normal().parent_path(); !p.empty(); p = p.parent_path()) {
        if (::stat(p.c_str(), &st) != 0) {
            if (p == p.root_path()) break;
            continue;
        }
        if (!S_ISDIR(st.st_mode)) return p.string() + " is not a directory";
        if (::access(p.c_str(), W_OK | X_OK) != 0) return "no permission to write in " + p.string();
        return "";
    }
    return ::access(".", W_OK | X_OK) == 0 ? "" : "no permission to write in the current directory";
}

std::string first_unwritable_output(const std::vector<NamedPath>& outputs, std::string* what, std::string* path) {
    // "d/" and "d" name one directory: the trailing separator goes.
    const auto dir_form = [](const std::string& p) {
        fs::path n = fs::path(p).lexically_normal();
        return n.has_filename() || n == n.root_path() ? n : n.parent_path();
    };
    std::vector<fs::path> dirs;
    for (const NamedPath& out : outputs)
        if (out.directory && !out.path.empty()) dirs.push_back(dir_form(out.path));
    for (const NamedPath& out : outputs) {
        if (out.path.empty() || out.path == "-") continue;
        std::string why;
        if (out.directory) {
            why = unwritable_directory_reason(dir_form(out.path).string());
        } else if (out.appended) {
            // Opened in place to append: the file, not its directory, must be writable.
            struct stat st {};
            if (::stat(out.path.c_str(), &st) == 0 && S_ISREG(st.st_mode))
                why = ::access(out.path.c_str(), W_OK) == 0 ? "" : "no permission to write " + out.path;
            else
                why = unwritable_reason(out.path);
        } else {
            const fs::path parent = fs::path(out.path).lexically_normal().parent_path();
            if (std::find(dirs.begin(), dirs.end(), parent) != dirs.end()) continue;  // its directory's check covers it
            why = unwritable_reason(out.path);
        }
        if (!why.empty()) {
            *what = out.what;
            *path = out.path;
            return why;
        }
    }
    return "";
}

bool same_output_file(const std::string& a, const std::string& b) {
    const std::string ka = file_key(a);
    return !ka.empty() && ka == file_key(b);
}

}  // namespace host
}  // namespace battsim
