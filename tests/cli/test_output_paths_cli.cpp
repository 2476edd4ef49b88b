// Output safety as a user meets it: outputs through symlinks and to devices, an output
// naming an input or another output refused before any work, "-" as standard output, no
// temporaries after Ctrl-C.
#include <catch2/catch.hpp>
#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.h"
#include "raw_logs.h"

using clitest::q;
using clitest::read_file;
using clitest::run;

namespace fs = std::filesystem;

namespace {

const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kConfig = kSource + "/configs/reference-modified.json";
const std::string kScenario = kSource + "/configs/scenarios/3s-hover-healthy.json";

// The names in `dir` that look like AtomicFile's temporaries (<name>.tmp.<pid>.<n>).
std::vector<std::string> temporaries(const std::string& dir) {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename().string().find(".tmp.") != std::string::npos) found.push_back(e.path().string());
    return found;
}

// A command that must be refused before any work: exit 2, the message naming both options,
// and every file in `kept` byte for byte as before.
void require_refused(const std::string& args, const std::string& message, const std::vector<std::string>& kept) {
    std::vector<std::string> before;
    for (const std::string& f : kept) before.push_back(read_file(f));
    const clitest::Result r = run(args);
    INFO(args);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains(message));
    for (size_t k = 0; k < kept.size(); ++k) CHECK(read_file(kept[k]) == before[k]);
}

}  // namespace

TEST_CASE("an output through a symlink replaces the file it points to and keeps the link", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));
    fs::create_directory(dir + "/real");
    clitest::write_file(dir + "/real/summary.json", "old\n");
    fs::create_symlink("real/summary.json", dir + "/summary.json");
    fs::create_symlink(dir + "/real/table.md", dir + "/table.md");  // dangling: its target is made
    const clitest::Result r = run("replay " + q(dir + "/log.csv") + " -c " + q(kConfig) + " --summary " + q(dir + "/summary.json"));
    REQUIRE(r.exit_code == 0);
    CHECK(fs::is_symlink(dir + "/summary.json"));
    CHECK(nlohmann::json::parse(read_file(dir + "/real/summary.json"))["schema"] == "battsim.summary");
    REQUIRE(run("batch " + q(dir + "/log.csv") + " -o " + q(dir + "/table.md")).exit_code == 0);
    CHECK(fs::is_symlink(dir + "/table.md"));
    CHECK_THAT(read_file(dir + "/real/table.md"), Catch::Contains("log"));
    CHECK(temporaries(dir).empty());
    CHECK(temporaries(dir + "/real").empty());
}

TEST_CASE("outputs to devices are written straight: /dev/null, /dev/stdout, /dev/full", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));
    const std::string log = q(dir + "/log.csv");
    const std::vector<std::string> dev_before = temporaries("/dev");
    const clitest::Result null = run("batch " + log + " -o /dev/null");
    CHECK(null.exit_code == 0);
    CHECK(null.out.empty());
    CHECK(run("replay " + log + " --series /dev/null --summary /dev/null").exit_code == 0);
    CHECK(temporaries("/dev") == dev_before);
    CHECK(fs::is_character_file("/dev/null"));
    // Standard output is a pipe here: the table comes through it.
    const clitest::Result out = run("batch " + log + " --format json -o /dev/stdout");
    REQUIRE(out.exit_code == 0);
    CHECK(nlohmann::json::parse(out.out)["rows"].size() == 1);
    CHECK(fs::is_symlink("/dev/stdout"));
    const clitest::Result full = run("replay " + log + " --summary /dev/full");
    CHECK(full.exit_code == 5);
    CHECK_THAT(full.err, Catch::Contains("/dev/full: write failed"));
    // Standard output on a full disk is a failed output too, whichever command wrote it.
    for (const std::string& args : {"replay " + log + " --json", "replay " + log, "batch " + log + " -o -",
                                    std::string("make-config --cells 4 --capacity-mah 1500")}) {
        const clitest::Result r = run(args + " > /dev/full");
        INFO(args);
        CHECK(r.exit_code == 5);
        CHECK_THAT(r.err, Catch::Contains("writing to standard output failed"));
    }
}

TEST_CASE("an output naming an input or another output is refused before any work", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/log.csv", b = dir + "/b.csv", cfg = dir + "/pack.json", scenario = dir + "/s.json";
    clitest::write_file(log, testsupport::raw_flight(12, 0.001));
    clitest::write_file(b, testsupport::raw_flight(14, 0.002));
    clitest::write_file(cfg, read_file(kConfig));
    nlohmann::json sj = nlohmann::json::parse(read_file(kScenario));
    sj["monitor_config"] = kSource + "/configs/generic-3s.json";  // absolute: the copy lives elsewhere
    clitest::write_file(scenario, sj.dump(2));
    clitest::write_file(dir + "/m.csv", "path\nlog.csv\nb.csv\n");
    clitest::write_file(dir + "/F", "kept\n");

    require_refused("replay " + q(log) + " --series " + q(log), "battsim replay: --series and the log name the same file: " + log, {log});
    // The same file by other names: through a symlinked directory, a hard link.
    fs::create_directory_symlink(dir, dir + "/again");
    fs::create_hard_link(log, dir + "/hard.csv");
    require_refused("replay " + q(log) + " --series " + q(dir + "/again/./log.csv"), "--series and the log name the same file", {log});
    require_refused("replay " + q(dir + "/hard.csv") + " --summary " + q(log), "--summary and the log name the same file", {log});
    require_refused("replay " + q(log) + " -c " + q(cfg) + " --summary " + q(cfg),
                    "battsim replay: --summary and -c/--config name the same file: " + cfg, {log, cfg});
    require_refused("replay " + q(log) + " --series " + q(dir + "/F") + " --summary " + q(dir + "/F"),
                    "--summary and --series name the same file", {log, dir + "/F"});
    require_refused("simulate " + q(scenario) + " -o " + q(scenario), "battsim simulate: -o/--output and a scenario name the same file",
                    {scenario});
    require_refused("simulate " + q(scenario) + " -o " + q(dir + "/same.csv") + " --truth " + q(dir + "/same.csv"),
                    "--truth and -o/--output name the same file", {scenario});
    CHECK_FALSE(fs::exists(dir + "/same.csv"));
    require_refused("batch -m " + q(dir + "/m.csv") + " -o " + q(dir + "/m.csv"), "battsim batch: -o/--output and -m/--manifest name the same file",
                    {dir + "/m.csv", log, b});
    require_refused("batch " + q(log) + " " + q(b) + " -o " + q(log), "battsim batch: -o/--output and a log name the same file", {log, b});
    require_refused("batch " + q(log) + " -o " + q(dir + "/T") + " --packs " + q(dir + "/T") + " --monitors " + q(dir + "/T"),
                    "--packs and -o/--output name the same file", {log});
    CHECK_FALSE(fs::exists(dir + "/T"));
    // A log named like a summary in the --out directory, and --out over the goldens.
    clitest::write_file(dir + "/out/log.json", read_file(log));
    require_refused("batch " + q(dir + "/out/log.json") + " --out " + q(dir + "/out"), "--out's log.json and a log name the same file",
                    {dir + "/out/log.json"});
    clitest::write_file(dir + "/golden/log.json", "{}\n");
    require_refused("batch " + q(log) + " --out " + q(dir + "/golden") + " --compare " + q(dir + "/golden"),
                    "--out's log.json and --compare's log.json name the same file", {dir + "/golden/log.json"});
    require_refused("discharge " + q(log) + " --table " + q(dir + "/t.csv") + " --curve " + q(dir + "/t.csv"),
                    "battsim discharge: --curve and --table name the same file", {log});
    require_refused("fit " + q(log) + " -c " + q(cfg) + " -o " + q(dir + "/f.json") + " --report " + q(dir + "/f.json"),
                    "battsim fit: --report and -o/--output name the same file", {log, cfg});
    require_refused("fit " + q(log) + " -c " + q(cfg) + " --report " + q(log), "--report and a log name the same file", {log, cfg});
    require_refused("residual " + q(log) + " -c " + q(cfg) + " --report " + q(cfg), "--report and -c/--config name the same file", {log, cfg});
    require_refused("fit-ocv " + q(log) + " -c " + q(cfg) + " --report " + q(log), "--report and a log name the same file", {log, cfg});
    require_refused("calibrate " + q(log) + " -c " + q(cfg) + " -o " + q(log), "-o/--output and a log name the same file", {log, cfg});
    require_refused("merge " + q(dir + "/m.csv") + " -o " + q(dir + "/m.csv"), "battsim merge: -o/--output and a table name the same file",
                    {dir + "/m.csv"});
    require_refused("make-config --from-log " + q(log) + " -o " + q(log), "-o/--output and --from-log name the same file", {log});
    require_refused("export-config --firmware " + q(cfg) + " -o " + q(cfg), "-o/--output and --firmware name the same file", {cfg});
    require_refused("score " + q(scenario) + " -o " + q(scenario), "battsim score: -o/--output and a scenario name the same file", {scenario});
    CHECK(temporaries(dir).empty());
}

TEST_CASE("a config may still be written back over itself (--config-out, calibrate -o)", "[cli][paths][truth]") {
    const std::string dir = clitest::temp_dir();
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/4s-racing-fault-current-gain.json") + " -o " + q(dir + "/g.csv")).exit_code == 0);
    const auto truth = nlohmann::json::parse(read_file(dir + "/g.truth.json"));
    const double charged_mah = truth["flight"]["log_charge_ah"].get<double>() * 1000.0;
    const std::string pack = dir + "/pack.json";
    clitest::write_file(pack, read_file(kSource + "/configs/sim-4s.json"));
    const clitest::Result r = run("replay " + q(dir + "/g.csv") + " -c " + q(pack) + " --estimator joint --charged-mah " +
                                  std::to_string(charged_mah) + " --config-out " + q(pack));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const auto fixed = nlohmann::json::parse(read_file(pack));
    CHECK(fixed["battery"]["extensions"]["current_sensor"]["gain"].get<double>() == Approx(1.0 / 1.08).epsilon(0.003));
    // calibrate's in-place update passes the check, and keeps what the replay wrote (its rest
    // after the landing keeps the configured 0.2 share).
    const clitest::Result c = run("calibrate " + q(dir + "/g.csv") + " -c " + q(pack) + " -o " + q(pack));
    INFO(c.err);
    CHECK(c.exit_code == 0);
    CHECK(c.err.find("name the same file") == std::string::npos);
    const auto calibrated = nlohmann::json::parse(read_file(pack));
    CHECK(calibrated["battery"]["extensions"]["current_sensor"]["gain"].get<double>() == Approx(1.0 / 1.08).epsilon(0.003));
    CHECK(calibrated["joint"]["health_filter"]["polarisation_slow_share"].get<double>() == Approx(0.2));
}

TEST_CASE("Ctrl-C during a replay leaves no temporary file", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));  // 37 s of log
    // timeout sends SIGINT after 1 s; --preserve-status passes on how battsim ended.
    const std::string cmd = "timeout --preserve-status -s INT 1 " + q(BATTSIM_BINARY) + " replay " + q(dir + "/log.csv") +
                            " --realtime --series " + q(dir + "/rt.csv") + " --summary " + q(dir + "/rt.json") + " 2>/dev/null";
    const int status = std::system(cmd.c_str());
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 128 + 2);  // died of SIGINT, as a shell expects
    CHECK(temporaries(dir).empty());
    CHECK_FALSE(fs::exists(dir + "/rt.csv"));
    CHECK_FALSE(fs::exists(dir + "/rt.json"));
}

TEST_CASE("\"-\" is standard output for a text output, one at a time; refused for the others", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/log.csv";
    clitest::write_file(log, testsupport::raw_flight(12, 0.001));
    // Run from `dir`, so that a file named "-" made by mistake would show there.
    const auto in_dir = [&](const std::string& args) {
        return testsupport::run_program("sh", "-c " + q("cd \"" + dir + "\" && \"" + BATTSIM_BINARY + "\" " + args));
    };
    clitest::Result r = in_dir("replay log.csv --series - --charged-mah 400");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.compare(0, 17, "time_s,voltage_v,") == 0);
    CHECK(r.out.find("charger check") == std::string::npos);  // the line for people goes to stderr
    CHECK_THAT(r.err, Catch::Contains("charger check: counted"));
    r = in_dir("replay log.csv --summary -");
    REQUIRE(r.exit_code == 0);
    CHECK(nlohmann::json::parse(r.out)["schema"] == "battsim.summary");
    r = in_dir("discharge log.csv --table -");
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.compare(0, 23, "voltage_v,consumed_mah,") == 0);
    CHECK(r.out.find("samples above") == std::string::npos);
    CHECK_THAT(r.err, Catch::Contains("samples above"));
    r = in_dir("batch log.csv --no-progress --format csv -o t.csv --packs -");
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.compare(0, 5, "pack,") == 0);
    CHECK_FALSE(fs::exists(dir + "/-"));

    const std::vector<std::string> kept{log};
    require_refused("replay " + q(log) + " --series - --json", "battsim replay: --series and --json would both write to standard output", kept);
    require_refused("replay " + q(log) + " --series - --summary -", "--summary and --series would both write to standard output", kept);
    require_refused("replay " + q(log) + " --tlog -", "battsim replay: --tlog: expected a path, found \"-\" (this output cannot go to standard output)", kept);
    require_refused("replay " + q(log) + " --mavlink -", "--mavlink: expected a path, found \"-\"", kept);
    require_refused("replay " + q(log) + " --plot -", "expected a name ending in .png or .svg", kept);
    require_refused("discharge " + q(log) + " --table - --curve -", "--curve and --table would both write to standard output", kept);
    require_refused("batch " + q(log) + " --packs -", "--packs and the table (standard output without -o) would both write", kept);
    require_refused("batch " + q(log) + " -o - --monitors -", "--monitors and -o/--output would both write", kept);
    require_refused("batch " + q(log) + " --out -", "--out: expected a path, found \"-\"", kept);
    require_refused("fit " + q(log) + " --output-dir -", "battsim fit: --output-dir: expected a path", kept);
    require_refused("fit " + q(log) + " --report - --json", "--report and --json would both write", kept);
    require_refused("residual " + q(log) + " -o - --json", "-o/--output and --json would both write", kept);
    require_refused("fit-ocv " + q(log) + " --report - -o -", "--report and -o/--output would both write", kept);
    require_refused("calibrate " + q(log) + " -o - --json", "-o/--output and --json would both write", kept);
    require_refused("simulate " + q(kScenario) + " -o -", "battsim simulate: -o/--output: expected a path", kept);
    require_refused("simulate " + q(kScenario) + " --out-dir -", "--out-dir: expected a path", kept);
    require_refused("log --port " + q(dir + "/none") + " --out -", "battsim log: --out: expected a path", kept);
    CHECK_FALSE(fs::exists(dir + "/-"));
}

TEST_CASE("fit --output-dir's per-log configs and a manifest's configs are checked like any output", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    const std::string a = dir + "/a.csv", b = dir + "/b/a.csv", cfg = dir + "/pack.json", other = dir + "/other.json";
    clitest::write_file(a, testsupport::raw_flight(12, 0.001));
    clitest::write_file(b, testsupport::raw_flight(14, 0.002));
    clitest::write_file(dir + "/fitted-a.json", clitest::read_file(a));  // a log named like a per-log config
    clitest::write_file(cfg, read_file(kConfig));
    clitest::write_file(other, read_file(kConfig));
    clitest::write_file(dir + "/x-a.json", read_file(kConfig));
    const std::vector<std::string> kept{a, b, dir + "/fitted-a.json", cfg, other, dir + "/x-a.json"};
    require_refused("fit " + q(a) + " " + q(dir + "/fitted-a.json") + " --output-dir " + q(dir),
                    "battsim fit: --output-dir's fitted-a.json (for " + a + ") and a log name the same file: " + dir + "/fitted-a.json",
                    kept);
    require_refused("fit " + q(a) + " -c " + q(dir + "/x-a.json") + " --name x --output-dir " + q(dir),
                    "--output-dir's x-a.json (for " + a + ") and -c/--config name the same file", kept);
    require_refused("fit " + q(a) + " " + q(b) + " --output-dir " + q(dir + "/out"),
                    "--output-dir's fitted-a.json (for " + b + ") and --output-dir's fitted-a.json (for " + a + ") name the same file",
                    kept);
    // A manifest's configs: no output may land on one; fit-ocv may write back over the one it fits.
    clitest::write_file(dir + "/m.csv", "path,config\na.csv,pack.json\nb/a.csv,other.json\n");
    require_refused("batch -m " + q(dir + "/m.csv") + " --no-progress -o " + q(other),
                    "battsim batch: -o/--output and the config of " + b + " name the same file: " + other, kept);
    require_refused("batch " + q(a) + " -c " + q(cfg) + " --no-progress --packs " + q(cfg),
                    "--packs and the config of " + a + " name the same file", kept);
    require_refused("fit-ocv -m " + q(dir + "/m.csv") + " -o " + q(other),
                    "battsim fit-ocv: -o/--output and the config of " + b + " name the same file: " + other, kept);
    const clitest::Result back = run("fit-ocv -m " + q(dir + "/m.csv") + " -o " + q(cfg));
    INFO(back.err);
    CHECK(back.err.find("name the same file") == std::string::npos);
    CHECK(back.exit_code == 0);
}

namespace {
// Runs battsim with `args` (no shell) and `env` added, its output to /dev/null; sends it
// `sig` once `ready` exists (or after 20 s); returns the signal it died of, 0 if none.
int signalled_when_ready(const std::vector<std::string>& args, const std::vector<std::string>& env, const std::string& ready,
                         int sig) {
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        for (const std::string& e : env) ::putenv(const_cast<char*>(e.c_str()));
        const int null = ::open("/dev/null", O_WRONLY);
        ::dup2(null, 1);
        ::dup2(null, 2);
        std::vector<char*> argv{const_cast<char*>(BATTSIM_BINARY)};
        for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        ::execv(BATTSIM_BINARY, argv.data());
        ::_exit(127);
    }
    for (int k = 0; k < 400 && !fs::exists(ready); ++k) ::usleep(50000);
    ::kill(pid, sig);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFSIGNALED(status) ? WTERMSIG(status) : 0;
}
}  // namespace

TEST_CASE("Ctrl-C while gnuplot draws leaves neither its message file nor the plot's temporary", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));
    fs::create_directories(dir + "/bin");
    fs::create_directories(dir + "/tmp");
    // A gnuplot that notes where its messages go, then hangs (deaf to the signal) until its
    // input closes and a little longer.
    clitest::write_file(dir + "/bin/gnuplot", "#!/bin/sh\ntrap '' INT TERM\nmessages=$(readlink /proc/$$/fd/1)\necho \"$messages\" > " +
                                                  q(dir + "/where.tmp") + "\nmv " + q(dir + "/where.tmp") + " " + q(dir + "/where") +
                                                  "\ncat > /dev/null\nsleep 3\n");
    fs::permissions(dir + "/bin/gnuplot", fs::perms::owner_all);
    const std::string path = std::string("PATH=") + dir + "/bin:" + std::getenv("PATH");
    const std::string tmpdir = "TMPDIR=" + dir + "/tmp";
    for (int sig : {SIGINT, SIGTERM}) {
        fs::remove(dir + "/where");
        CHECK(signalled_when_ready({"replay", dir + "/log.csv", "--plot", dir + "/p.png"}, {path, tmpdir}, dir + "/where", sig) == sig);
        REQUIRE(fs::exists(dir + "/where"));
        std::string messages = read_file(dir + "/where");
        messages = messages.substr(0, messages.find('\n'));
        CHECK(messages.rfind(dir + "/tmp/battsim-gnuplot-", 0) == 0);  // it was there...
        CHECK_FALSE(fs::exists(messages));                             // ...and is gone
        CHECK(fs::is_empty(dir + "/tmp"));
        CHECK(temporaries(dir).empty());
        CHECK_FALSE(fs::exists(dir + "/p.png"));
    }
}

TEST_CASE("--plot without a working gnuplot exits 5 with a message, never by SIGPIPE", "[cli][paths]") {
    // A missing gnuplot had ended a real-sized run by SIGPIPE (exit 141) without a word, and
    // the outputs still to be written (fit's --report, discharge's --config-out) were lost.
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.0001, 8000));  // a plot script past the pipe's 64 KiB
    fs::create_directories(dir + "/none");
    fs::create_directories(dir + "/bin");
    const auto run_with_path = [&](const std::string& bin, const std::string& args) {
        return testsupport::run_program("env", "PATH=" + q(bin) + " " + q(BATTSIM_BINARY) + " " + args);
    };
    const std::string log = q(dir + "/log.csv");
    // Not on PATH: said with the options, before anything is run or written.
    for (const char* command : {"replay", "residual", "fit"}) {
        INFO(command);
        const clitest::Result r = run_with_path(dir + "/none", std::string(command) + " " + log + " --plot " + q(dir + "/p.png") +
                                                             (std::string(command) == "replay" ? " --summary " : " --report ") +
                                                             q(dir + "/s.json"));
        CHECK(r.exit_code == 5);
        CHECK_THAT(r.err, Catch::Contains("gnuplot is not on PATH"));
        CHECK_FALSE(fs::exists(dir + "/s.json"));
    }
    // One that dies at once without reading its script: the write into the closed pipe fails,
    // and the run says so (the summary before the plot is kept).
    clitest::write_file(dir + "/bin/gnuplot", "#!/bin/sh\nexit 1\n");
    fs::permissions(dir + "/bin/gnuplot", fs::perms::owner_all);
    const clitest::Result r = run_with_path(dir + "/bin", "replay " + log + " --plot " + q(dir + "/p.png") + " --summary " + q(dir + "/s.json"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("gnuplot failed to write"));
    CHECK(fs::exists(dir + "/s.json"));
    CHECK_FALSE(fs::exists(dir + "/p.png"));
}

TEST_CASE("standard output by another name is standard output: /dev/stdout beside --json is refused", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));
    const std::string log = q(dir + "/log.csv");
    // Here standard output is a pipe: both would interleave in it.
    clitest::Result r = run("replay " + log + " --series /dev/stdout --json");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("--series (/dev/stdout) and --json would both write to standard output"));
    CHECK(clitest::is_error_object(r.out));  // no series, no summary: the reason, as JSON
    // Alone it is the one output there, and text for people goes to standard error, as with "-".
    r = run("replay " + log + " --series /dev/stdout --said");
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.rfind("time_s,", 0) == 0);
    CHECK(r.out.find("said") == std::string::npos);
    CHECK_THAT(r.err, Catch::Contains("said"));
    // Redirected to a file, the atomic write would replace the file the shell opened and the
    // JSON written to the old one would be lost; refused the same way.
    const std::string shell = "cd " + q(dir) + " && " + q(BATTSIM_BINARY) + " replay log.csv --series /dev/stdout --json > out.txt 2> err.txt; echo $? > rc.txt";
    REQUIRE(std::system(shell.c_str()) == 0);
    CHECK(read_file(dir + "/rc.txt") == "2\n");
    CHECK_THAT(read_file(dir + "/err.txt"), Catch::Contains("would both write to standard output"));
}

TEST_CASE("an output that cannot be written is said before the work, and no other output is replaced", "[cli][paths]") {
    // replay had written the series, then failed on the summary: the old series was gone and
    // the run failed anyway (fit, residual and fit-ocv the same, after their whole fit).
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));
    clitest::write_file(dir + "/s.csv", "old series\n");
    clitest::write_file(dir + "/cfg.json", "old config\n");
    clitest::Result r = run("replay " + q(dir + "/log.csv") + " -c " + q(kConfig) + " --series " + q(dir + "/s.csv") +
                            " --summary " + q(dir + "/nodir/s.json"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("--summary: cannot write " + dir + "/nodir/s.json: the directory " + dir +
                                      "/nodir does not exist"));
    CHECK(read_file(dir + "/s.csv") == "old series\n");
    r = run("residual " + q(dir + "/log.csv") + " -c " + q(kConfig) + " -o " + q(dir + "/cfg.json") + " --report " +
            q(dir + "/nodir/r.json"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("--report: cannot write"));
    CHECK_THAT(r.err, !Catch::Contains("analysing"));  // before the work
    CHECK(read_file(dir + "/cfg.json") == "old config\n");
    // A directory a command makes is made, with its parents (fit --output-dir had not been).
    r = run("fit " + q(dir + "/log.csv") + " -c " + q(kConfig) + " --params none --output-dir " + q(dir + "/made/deeper/"));
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(fs::exists(dir + "/made/deeper/fitted-log.json"));
    r = run("fit " + q(dir + "/log.csv") + " -c " + q(kConfig) + " --params none --output-dir " + q(dir + "/s.csv/sub"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("--output-dir: cannot write " + dir + "/s.csv/sub: " + dir + "/s.csv is not a directory"));
}

TEST_CASE("an output keeps the permissions of the file it replaces; a name near the limit is written", "[cli][paths]") {
    const std::string dir = clitest::temp_dir(), priv = dir + "/private.json";
    clitest::write_file(priv, "{}\n");
    fs::permissions(priv, fs::perms::owner_read | fs::perms::owner_write);
    clitest::Result r = run("make-config --cells 4 --capacity-mah 1500 -o " + q(priv));
    REQUIRE(r.exit_code == 0);
    CHECK(fs::status(priv).permissions() == (fs::perms::owner_read | fs::perms::owner_write));
    CHECK(read_file(priv).size() > 100);
    // 250 characters: the temporary beside it (".tmp.<pid>.<n>") had passed the 255 the file
    // system allows, and a name the user may create could not be written.
    const std::string long_name = dir + "/" + std::string(245, 'c') + ".json";
    r = run("make-config --cells 4 --capacity-mah 1500 -o " + q(long_name));
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(fs::exists(long_name));
    CHECK(temporaries(dir).empty());
}

TEST_CASE("a reader of standard output gone, or a hang-up, leaves no temporary file", "[cli][paths]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/log.csv", testsupport::raw_flight(12, 0.001));
    // `| head -1`: the series on standard output, the MAVLink stream into a file. The series
    // (about 160 KB) outgrows the pipe's buffer, so battsim writes on after head has gone.
    std::string cmd = q(BATTSIM_BINARY) + " replay " + q(dir + "/log.csv") + " -c " + q(kConfig) + " --mavlink " +
                      q(dir + "/m.bin") + " --series - 2>/dev/null | head -1 > /dev/null";
    std::system(cmd.c_str());
    CHECK(temporaries(dir).empty());
    for (const char* sig : {"HUP"}) {
        cmd = "timeout --preserve-status -s " + std::string(sig) + " 1 " + q(BATTSIM_BINARY) + " replay " + q(dir + "/log.csv") +
              " -c " + q(kConfig) + " --realtime --series " + q(dir + "/rt.csv") + " 2>/dev/null";
        std::system(cmd.c_str());
        INFO(sig);
        CHECK(temporaries(dir).empty());
        CHECK_FALSE(fs::exists(dir + "/rt.csv"));
    }
}
