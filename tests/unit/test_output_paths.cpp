// The output-path check (an output naming an input or another output) and AtomicFile on
// symlinks and devices.
#include <catch2/catch.hpp>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <climits>
#include <csignal>
#include <filesystem>
#include <fstream>
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

TEST_CASE("AtomicFile removes the temporaries a killed writer left beside its target, and nothing else", "[output_paths]") {
    // SIGKILL runs no handler: its temporary stays, and the next write to the target takes it.
    testsupport::TempDir d("stale");
    // A PID no process can have: above the kernel's pid_max (at most 2^22).
    long pid_max = 4194304;
    std::ifstream("/proc/sys/kernel/pid_max") >> pid_max;
    REQUIRE(pid_max < INT_MAX);
    const std::string never = std::to_string(pid_max + 1);
    // A PID that was a process's and is gone: a child reaped.
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) ::_exit(0);
    REQUIRE(::waitpid(child, nullptr, 0) == child);
    const std::string reaped = std::to_string(child);
    const std::string self = std::to_string(::getpid());
    // And one dead but not reaped: kill() still finds a zombie (`timeout -s KILL` kills
    // itself too, and its child waits for an init to reap it).
    const pid_t unreaped = ::fork();
    REQUIRE(unreaped >= 0);
    if (unreaped == 0) ::_exit(0);
    siginfo_t exited {};
    REQUIRE(::waitid(P_PID, static_cast<id_t>(unreaped), &exited, WEXITED | WNOWAIT) == 0);  // a zombie now
    const std::string zombie = std::to_string(unreaped);

    const std::string target = d.write("out.csv", "old\n");
    const std::vector<std::string> stale = {"out.csv.tmp." + never + ".0", "out.csv.tmp." + reaped + ".17",
                                            "out.csv.tmp." + zombie + ".4"};
    const std::vector<std::string> kept = {
        "out.csv.tmp." + self + ".999",      // this process's, alive
        "out.csv.tmp.1.0",                   // init's, alive (EPERM or not)
        "other.csv.tmp." + never + ".0",     // another target's
        "xout.csv.tmp." + never + ".0",
        "out.csv.tmp." + never + ".0.bak",   // not the pattern exactly
        "out.csv.tmp." + never,
        "out.csv.tmp." + never + ".x",
        "out.csv.tmp.0" + never + ".0",      // a leading zero: not std::to_string's
        "out.csv.tmp.0.0",                   // PID 0: kill() would ask about the process group
        "out.csv.tmp.-" + never + ".0",
        "out.csv.tmp..0",
        "out.csv.tmp." + never + ".",
        "out.csv.tmp.99999999999.0",         // beyond any pid_t
        "out.csv.bak",
        "notes.txt",
    };
    for (const auto& n : stale) d.write(n, "stale");
    for (const auto& n : kept) d.write(n, "keep");
    // A directory and a symlink by a stale name: not regular files of ours.
    fs::create_directory(d.path("out.csv.tmp." + never + ".1"));
    fs::create_symlink("notes.txt", d.path("out.csv.tmp." + never + ".2"));
    // A dead-looking PID whose temporary is locked: a writer alive in another PID namespace
    // (or on another host), which every writer's flock() tells.
    const std::string locked = d.write("out.csv.tmp." + never + ".3", "writing");
    const int lock_fd = ::open(locked.c_str(), O_RDONLY | O_CLOEXEC);
    REQUIRE(lock_fd >= 0);
    REQUIRE(::flock(lock_fd, LOCK_EX | LOCK_NB) == 0);

    write_file_atomic(target, "new\n");
    REQUIRE(::waitpid(unreaped, nullptr, 0) == unreaped);
    CHECK(testsupport::read_file(target) == "new\n");
    for (const auto& n : stale) CHECK_FALSE(fs::exists(d.path(n)));
    for (const auto& n : kept) CHECK(testsupport::read_file(d.path(n)) == "keep");
    CHECK(fs::is_directory(d.path("out.csv.tmp." + never + ".1")));
    CHECK(fs::is_symlink(d.path("out.csv.tmp." + never + ".2")));
    CHECK(testsupport::read_file(d.path("notes.txt")) == "keep");
    CHECK(testsupport::read_file(locked) == "writing");
    // Unlocked (its writer gone), it goes with the next write.
    ::close(lock_fd);
    write_file_atomic(target, "again\n");
    CHECK_FALSE(fs::exists(locked));
    CHECK(testsupport::read_file(target) == "again\n");
    // Nothing of its own left behind, and the kept ones still there.
    size_t temporaries = 0;
    for (const auto& e : fs::directory_iterator(d.path()))
        temporaries += e.path().filename().string().rfind("out.csv.tmp." + self + ".", 0) == 0 ? 1 : 0;
    CHECK(temporaries == 1);  // the kept ".999"

    // A long target name: temp_name() cuts it so the temporary's name is 255 bytes; the cut
    // name of a dead writer's is found too, a cut name of another target's is not. (In a
    // directory of its own: a process lists each directory once, so a temporary left in one
    // it has listed goes with the next process's writes.)
    const std::string long_name(250, 'n');
    fs::create_directory(d.path("long"));
    const std::string long_target = d.write("long/" + long_name, "old\n");
    const std::string suffix = ".tmp." + never + ".5";
    const std::string cut = long_name.substr(0, 255 - suffix.size()) + suffix;
    d.write("long/" + cut, "stale");
    std::string other_cut = cut;
    other_cut[0] = 'm';
    d.write("long/" + other_cut, "keep");
    write_file_atomic(long_target, "new\n");
    CHECK_FALSE(fs::exists(d.path("long/" + cut)));
    CHECK(testsupport::read_file(d.path("long/" + other_cut)) == "keep");
}

TEST_CASE("AtomicFile holds a lock on its temporary until the commit", "[output_paths]") {
    testsupport::TempDir d("locked");
    AtomicFile f(d.path("out.txt"));
    f.write("x");
    // Another open file description cannot take it while the writer lives.
    const int fd = ::open(f.temp_path().c_str(), O_RDONLY | O_CLOEXEC);
    REQUIRE(fd >= 0);
    CHECK(::flock(fd, LOCK_EX | LOCK_NB) != 0);
    f.commit();
    CHECK(::flock(fd, LOCK_EX | LOCK_NB) == 0);  // the same inode, now the target, released
    ::close(fd);
    CHECK(testsupport::read_file(d.path("out.txt")) == "x");
}
