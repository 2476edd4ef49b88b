// The output-path check (an output naming an input or another output) and AtomicFile on
// symlinks and devices.
#include <catch2/catch.hpp>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "host/io/atomic_file.h"
#include "host/io/output_paths.h"
#include "test_files.h"

using battsim::host::AtomicFile;
using battsim::host::check_output_paths;
using battsim::host::Dash;
using battsim::host::same_output_file;
using battsim::host::write_file_atomic;

namespace fs = std::filesystem;

namespace {
// What check_output_paths says, "" when it accepts.
std::string refusal(const std::vector<battsim::host::NamedPath>& in, const std::vector<battsim::host::NamedPath>& out) {
    try {
        check_output_paths(in, out);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

size_t entries(const std::string& dir) {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir)) n += e.path().filename() != "" ? 1 : 0;
    return n;
}
}  // namespace

TEST_CASE("same_output_file: one file by any name, existing or not", "[output_paths]") {
    testsupport::TempDir d("paths");
    const std::string a = d.write("a.csv", "a\n");
    const std::string b = d.write("b.csv", "b\n");
    fs::create_directory(d.path("sub"));
    fs::create_symlink(a, d.path("link.csv"));
    fs::create_hard_link(a, d.path("hard.csv"));
    CHECK(same_output_file(a, a));
    CHECK(same_output_file(a, d.path("sub/../a.csv")));
    CHECK(same_output_file(a, d.path("link.csv")));
    CHECK(same_output_file(a, d.path("hard.csv")));
    CHECK_FALSE(same_output_file(a, b));
    // Files to be created: by their path, through a symlinked directory and a dangling link too.
    fs::create_directory_symlink(d.path("sub"), d.path("sublink"));
    CHECK(same_output_file(d.path("new.json"), d.path("sub/../new.json")));
    CHECK(same_output_file(d.path("sub/new.json"), d.path("sublink/new.json")));
    fs::create_symlink(d.path("later.json"), d.path("dangling.json"));
    CHECK(same_output_file(d.path("dangling.json"), d.path("later.json")));
    CHECK_FALSE(same_output_file(d.path("new.json"), d.path("other.json")));
    // Relative and absolute names of one file.
    const fs::path cwd = fs::current_path();
    fs::current_path(d.path());
    CHECK(same_output_file("a.csv", a));
    CHECK(same_output_file("./x/../new.json", d.path("new.json")));
    fs::current_path(cwd);
    // Never compared: standard output, nothing, devices.
    CHECK_FALSE(same_output_file("-", "-"));
    CHECK_FALSE(same_output_file("", ""));
    CHECK_FALSE(same_output_file("/dev/null", "/dev/null"));
}

TEST_CASE("check_output_paths names the two options; a config may be written back over itself", "[output_paths]") {
    testsupport::TempDir d("paths");
    const std::string log = d.write("log.csv", "x\n");
    const std::string cfg = d.write("pack.json", "{}\n");
    CHECK(refusal({{"the log", log}}, {{"--series", log}}) == "--series and the log name the same file: " + log);
    CHECK(refusal({{"the log", log}}, {{"--series", d.path("f.csv")}, {"--summary", d.path("f.csv")}}) ==
          "--summary and --series name the same file: " + d.path("f.csv"));
    CHECK(refusal({{"-c/--config", cfg, true}}, {{"--summary", cfg}}) == "--summary and -c/--config name the same file: " + cfg);
    CHECK(refusal({{"-c/--config", cfg, true}}, {{"--config-out", cfg, true}}).empty());
    // Only the config's own output: a second output naming it is still refused.
    CHECK(refusal({{"-c/--config", cfg, true}}, {{"--config-out", cfg, true}, {"--report", cfg}}) ==
          "--report and --config-out name the same file: " + cfg);
    // A config written over a log is no in-place update.
    CHECK_FALSE(refusal({{"the log", log}}, {{"--config-out", log, true}}).empty());
    CHECK(refusal({{"the log", log}, {"-c/--config", ""}}, {{"-o/--output", "-", false, Dash::StandardOutput}, {"--plot", ""}}).empty());
    // Inputs may repeat (a log listed twice); /dev/null twice as an output destroys nothing.
    CHECK(refusal({{"a log", log}, {"a log", log}}, {{"-o", "/dev/null"}, {"--packs", "/dev/null"}}).empty());
}

TEST_CASE("\"-\": standard output for one text output, refused for the others", "[output_paths]") {
    const auto text = [](const std::string& what, const std::string& path) {
        return battsim::host::NamedPath{what, path, false, Dash::StandardOutput};
    };
    CHECK(refusal({}, {text("--json", ""), text("--series", "-"), {"--tlog", "t.tlog"}}).empty());
    CHECK(refusal({}, {text("--json", "-"), text("--series", "-")}) ==
          "--series and --json would both write to standard output; at most one output may go there");
    // Standard output by another name counts as "-" (here standard output is whatever the test
    // runner gave: a pipe, a file or a terminal, which all count).
    struct stat st {};
    if (::fstat(STDOUT_FILENO, &st) == 0 && (S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode) || ::isatty(STDOUT_FILENO))) {
        CHECK(battsim::host::names_standard_output("/dev/stdout"));
        CHECK(battsim::host::names_standard_output("/proc/self/fd/1"));
        CHECK(refusal({}, {text("--json", "-"), text("--series", "/dev/stdout")}) ==
              "--series (/dev/stdout) and --json would both write to standard output; at most one output may go there");
        CHECK(refusal({}, {text("--json", ""), {"--tlog", "/proc/self/fd/1"}}).empty());
    }
    CHECK_FALSE(battsim::host::names_standard_output(""));
    CHECK_FALSE(battsim::host::names_standard_output("/dev/null"));
    CHECK(refusal({}, {text("--series", ""), {"--tlog", "-"}}) ==
          "--tlog: expected a path, found \"-\" (this output cannot go to standard output)");
}

TEST_CASE("ScratchFile: an empty file of its own in the temporary directory, gone with the object", "[output_paths]") {
    std::string path;
    {
        const battsim::host::ScratchFile a("battsim-scratch-"), b("battsim-scratch-");
        path = a.path();
        CHECK(a.path() != b.path());
        CHECK(fs::equivalent(fs::path(path).parent_path(), fs::temp_directory_path()));
        CHECK(fs::path(path).filename().string().rfind("battsim-scratch-", 0) == 0);
        CHECK(fs::is_regular_file(path));
        CHECK(fs::file_size(path) == 0);
    }
    CHECK_FALSE(fs::exists(path));
}

TEST_CASE("AtomicFile writes through a symlink and keeps it; writes a device straight", "[output_paths]") {
    testsupport::TempDir d("paths");
    fs::create_directory(d.path("real"));
    const std::string target = d.write("real/out.json", "old\n");
    fs::create_symlink("real/out.json", d.path("link.json"));
    write_file_atomic(d.path("link.json"), "new\n");
    CHECK(fs::is_symlink(d.path("link.json")));
    CHECK(testsupport::read_file(target) == "new\n");
    CHECK(entries(d.path()) == 2);  // no temporary beside the link
    CHECK(entries(d.path("real")) == 1);
    // A dangling link: the file it names is created, the link kept.
    fs::create_symlink("real/made.json", d.path("dangling.json"));
    write_file_atomic(d.path("dangling.json"), "made\n");
    CHECK(fs::is_symlink(d.path("dangling.json")));
    CHECK(testsupport::read_file(d.path("real/made.json")) == "made\n");
    // A device is written as it is; an uncommitted one is not removed.
    write_file_atomic("/dev/null", "nothing\n");
    {
        AtomicFile f("/dev/null");
        CHECK(f.temp_path() == "/dev/null");
    }
    CHECK(fs::is_character_file("/dev/null"));
    CHECK_THROWS_WITH(write_file_atomic("/dev/full", "x"), Catch::Contains("write failed"));
    CHECK_THROWS_WITH(AtomicFile(d.path("real")), Catch::Contains("is a directory"));
    fs::create_symlink("loop-b", d.path("loop-a"));
    fs::create_symlink("loop-a", d.path("loop-b"));
    CHECK_THROWS_WITH(AtomicFile(d.path("loop-a")), Catch::Contains("too many levels of symbolic links"));
}
