#include "host/batch/inputs.h"

#include <glob.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>
#include <system_error>

#include "host/io/atomic_file.h"

namespace battsim {
namespace host {

namespace fs = std::filesystem;

bool natural_less(const std::string& a, const std::string& b) {
    size_t i = 0, j = 0;
    auto digit = [](char c) { return c >= '0' && c <= '9'; };
    while (i < a.size() && j < b.size()) {
        if (digit(a[i]) && digit(b[j])) {
            size_t ie = i, je = j;
            while (ie < a.size() && digit(a[ie])) ++ie;
            while (je < b.size() && digit(b[je])) ++je;
            size_t is = i, js = j;  // skip leading zeros for the numeric comparison
            while (is + 1 < ie && a[is] == '0') ++is;
            while (js + 1 < je && b[js] == '0') ++js;
            if (ie - is != je - js) return ie - is < je - js;
            const int c = a.compare(is, ie - is, b, js, je - js);
            if (c != 0) return c < 0;
            i = ie;
            j = je;
        } else {
            if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
            ++i;
            ++j;
        }
    }
    if ((i < a.size()) != (j < b.size())) return j < b.size();
    return a < b;
}

namespace {

// A summary, table or truth file battsim writes (`batch --out` beside its logs had read its
// own 29.json as a log on the second run, and renamed the real summaries).
bool is_battsim_output_name(const std::string& name) {
    auto ends_with = [&](const char* end) {
        const std::string e(end);
        if (name.size() < e.size()) return false;
        for (size_t k = 0; k < e.size(); ++k)
            if (std::tolower(static_cast<unsigned char>(name[name.size() - e.size() + k])) != e[k]) return false;
        return true;
    };
    // ... or a temporary of one that a killed run left (SIGKILL, a power cut): the next
    // nightly run had read `3.json.tmp.15663.2` as a log and failed it.
    return ends_with(".json") || ends_with(".md") || is_temporary_name(name);
}

// Regular (or symlinked-to-regular) files directly in `dir`, hidden ones skipped, sorted.
// `why` is set when the directory cannot be listed: one the user may not read had read as
// "holds no log files", as if the fleet's logs were not there.
std::vector<std::string> list_directory(const std::string& dir, std::string& why) {
    std::vector<std::string> names;
    std::error_code ec;
    fs::directory_iterator it(dir, ec);
    for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.empty() || name[0] == '.') continue;
        std::error_code sec;
        if (!fs::is_regular_file(it->path(), sec)) continue;
        if (is_battsim_output_name(name)) continue;
        names.push_back(name);
    }
    if (ec) {
        why = "cannot read the directory: " + ec.message();
        return {};
    }
    std::sort(names.begin(), names.end(), natural_less);
    std::vector<std::string> out;
    out.reserve(names.size());
    for (const std::string& n : names) out.push_back((fs::path(dir) / n).string());
    return out;
}

bool is_directory(const std::string& p) {
    std::error_code ec;
    return fs::is_directory(p, ec);
}

bool exists(const std::string& p) {
    std::error_code ec;
    return fs::exists(p, ec);
}

// Directories glob(3) could not read while matching, with why; glob's error callback takes
// no context, and inputs are expanded on one thread.
thread_local std::vector<std::string>* g_glob_unreadable = nullptr;

extern "C" int note_glob_error(const char* path, int err) {
    if (g_glob_unreadable) g_glob_unreadable->push_back(std::string(path) + ": cannot read the directory: " + std::strerror(err));
    return 0;  // go on with the rest of the pattern
}

std::vector<std::string> glob_paths(const std::string& pattern, std::vector<std::string>& unreadable) {
    glob_t g{};
    std::vector<std::string> out;
    g_glob_unreadable = &unreadable;
    // GLOB_NOSORT: glob(3) sorts by the locale's collation; we sort locale-free below.
    const int rc = ::glob(pattern.c_str(), GLOB_NOSORT, note_glob_error, &g);
    g_glob_unreadable = nullptr;
    if (rc == 0) {
        for (size_t i = 0; i < g.gl_pathc; ++i) out.emplace_back(g.gl_pathv[i]);
    }
    globfree(&g);
    std::sort(out.begin(), out.end(), natural_less);
    return out;
}

}  // namespace

bool is_glob_pattern(const std::string& s) { return s.find_first_of("*?[") != std::string::npos; }

std::string log_file_key(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) return "i" + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(path, ec);
    return "p" + (ec ? fs::path(path).lexically_normal() : resolved).string();
}

std::string listed_twice(const ExpandedPath& again, const ExpandedPath& first, const std::string& where) {
    const auto named = [](const ExpandedPath& e) {
        const std::string path = "\"" + e.path + "\"";
        return e.argument == e.path ? path : path + " (from \"" + e.argument + "\")";
    };
    return named(again) + " names the same log as " + named(first) + (where.empty() ? "" : " " + where) +
           "; list each log once (twice, it would count twice in the per-pack and per-monitor tables)";
}

std::vector<ExpandedPath> expand_inputs(const std::vector<std::string>& arguments, const std::vector<std::string>& outputs) {
    std::vector<ExpandedPath> out;
    std::map<std::string, size_t> seen;  // file key -> its entry in `out`
    std::set<std::string> written;       // the command's outputs, by file key
    for (const std::string& o : outputs)
        if (!o.empty() && o != "-") written.insert(log_file_key(o));
    const auto not_written = [&](const std::vector<std::string>& files) {
        std::vector<std::string> kept;
        for (const std::string& f : files)
            if (!written.count(log_file_key(f))) kept.push_back(f);
        return kept;
    };
    auto add = [&](const std::string& path, const std::string& arg) {
        const ExpandedPath e{path, arg, ""};
        const auto [it, fresh] = seen.emplace(log_file_key(path), out.size());
        if (!fresh) throw std::invalid_argument(listed_twice(e, out[it->second]));
        out.push_back(e);
    };
    for (const std::string& arg : arguments) {
        if (is_directory(arg)) {
            std::string why;
            const std::vector<std::string> files = not_written(list_directory(arg, why));
            if (!why.empty()) out.push_back({arg, arg, why});
            else if (files.empty()) out.push_back({arg, arg, "directory holds no log files"});
            for (const std::string& f : files) add(f, arg);
        } else if (is_glob_pattern(arg) && !exists(arg)) {
            std::vector<std::string> files;
            std::vector<std::string> unreadable;  // directories the pattern passes that could not be listed
            for (const std::string& m : glob_paths(arg, unreadable)) {
                if (is_directory(m)) {
                    std::string why;
                    for (const std::string& f : list_directory(m, why)) files.push_back(f);
                    if (!why.empty()) unreadable.push_back(m + ": " + why);
                } else if (!is_battsim_output_name(m) || is_battsim_output_name(arg)) {  // "d/*" as "d"; "d/*.json" asks
                    files.push_back(m);
                }
            }
            for (const std::string& u : unreadable) out.push_back({arg, arg, u});
            files = not_written(files);
            if (files.empty() && unreadable.empty()) out.push_back({arg, arg, "pattern matches no file"});
            for (const std::string& f : files) add(f, arg);
        } else {
            // Kept even if missing: the replay reports it as an unreadable log.
            add(arg, arg);
        }
    }
    return out;
}

ShardSpec parse_shard(const std::string& text) {
    const size_t slash = text.find('/');
    auto number = [&](const std::string& s) -> size_t {
        if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos)
            throw std::invalid_argument("--shard: expected K/N with whole numbers 1 <= K <= N <= 999999999, found \"" +
                                        text + "\"");
        return static_cast<size_t>(std::stoul(s));
    };
    if (slash == std::string::npos)
        throw std::invalid_argument("--shard: expected K/N (e.g. 2/8), found \"" + text + "\"");
    ShardSpec s;
    s.index = number(text.substr(0, slash));
    s.count = number(text.substr(slash + 1));
    if (s.count == 0 || s.index == 0 || s.index > s.count)
        throw std::invalid_argument("--shard: expected K/N with 1 <= K <= N, found \"" + text + "\"");
    return s;
}

std::string to_string(const ShardSpec& s) {
    return s.active() ? std::to_string(s.index) + "/" + std::to_string(s.count) : std::string();
}

std::string path_stem(const std::string& path) { return fs::path(path).stem().string(); }

std::string expand_variables(const std::string& text) {
    std::string out;
    size_t i = 0;
    while (i < text.size()) {
        if (text.compare(i, 2, "${") != 0) {
            out += text[i++];
            continue;
        }
        const size_t close = text.find('}', i + 2);
        if (close == std::string::npos)
            throw std::invalid_argument("\"" + text + "\": expected '}' after \"${\"");
        const std::string inner = text.substr(i + 2, close - i - 2);
        const size_t dflt = inner.find(":-");
        const std::string name = inner.substr(0, dflt);
        if (name.empty() || name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_") !=
                                std::string::npos)
            throw std::invalid_argument("\"" + text + "\": expected a variable name inside ${...}, found \"" + name + "\"");
        const char* value = std::getenv(name.c_str());
        if (value && *value) {
            // A relative directory in the environment means what it means to the shell that set
            // it, the working directory (BATTSIM_DATA_DIR=../shared/data had been read against
            // the manifest's directory, and every log was missing).
            const bool leads = i == 0 && fs::path(value).is_relative();
            out += leads ? fs::absolute(value).lexically_normal().string() : std::string(value);
        } else if (dflt != std::string::npos) {
            out += inner.substr(dflt + 2);
        } else {
            throw std::invalid_argument("\"" + text + "\": environment variable " + name +
                                        " is not set (write ${" + name + ":-default} to give a fallback)");
        }
        i = close + 1;
    }
    return out;
}

}  // namespace host
}  // namespace battsim
