// battsim batch and merge run as programs: error rows and exit codes, summaries kept,
// byte-identical tables for any --jobs, shards merged back into the single run's table,
// --compare against goldens, clear manifest errors.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.h"
#include "raw_logs.h"

using clitest::q;
using clitest::read_file;
using clitest::run;

namespace {

const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kData = BATTSIM_DATA_DIR;
const std::string kConfig = kSource + "/configs/reference-modified.json";

bool exists(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0;
}

using clitest::temp_dir;
using testsupport::raw_flight;

// A directory with `good` distinct flights g1..gN and, if asked, one unreadable log.
std::string fleet_dir(int good, bool with_bad) {
    const std::string dir = temp_dir();
    for (int k = 1; k <= good; ++k)
        clitest::write_file(dir + "/g" + std::to_string(k) + ".csv", raw_flight(12 + 3 * k, 0.0006 * k));
    if (with_bad) clitest::write_file(dir + "/bad.csv", "627,16.57,4.14,4.14,4.14,4.16,47.99,0.39,\n628,oops,4.1,4.1,4.1,4.1,1,1,\n");
    return dir;
}

}  // namespace

TEST_CASE("batch: a bad log becomes an error row, the rest are replayed and kept", "[cli][batch]") {
    const std::string dir = fleet_dir(2, true);
    const std::string out = dir + "/summaries";
    auto r = run("batch " + q(dir) + " -c " + q(kConfig) + " --out " + q(out) + " --format json --jobs 2");
    INFO(r.err);
    CHECK(r.exit_code == 1);
    const auto table = nlohmann::json::parse(r.out);
    REQUIRE(table["rows"].size() == 3);
    // Directory order: natural sort of the names.
    CHECK(table["rows"][0]["test"] == "bad");
    CHECK(table["rows"][0]["status"] == "error");
    CHECK(table["rows"][0]["error"].get<std::string>().find(dir + "/bad.csv:2:2: ") == 0);
    CHECK(table["rows"][1]["test"] == "g1");
    CHECK(table["rows"][1]["status"] == "ok");
    CHECK(table["rows"][2]["status"] == "ok");
    CHECK(r.err.find("battsim batch: failed: " + dir + "/bad.csv:2:2:") != std::string::npos);
    CHECK(r.err.find("1 of 3 logs failed") != std::string::npos);
    // The good logs' summaries are written, in the replay's own format; no summary for the bad one.
    for (const char* stem : {"g1", "g2"}) {
        const auto s = nlohmann::json::parse(read_file(out + "/" + stem + ".json"));
        CHECK(s["schema"] == "battsim.summary");
        CHECK(s["input"]["path"] == dir + "/" + stem + ".csv");
    }
    CHECK_FALSE(exists(out + "/bad.json"));
    // An earlier run's summary of the bad log that cannot be removed (here a directory with a
    // file in it) is said, exit 5: it had stayed without a word and read as this run's.
    std::filesystem::create_directories(out + "/bad.json");
    clitest::write_file(out + "/bad.json/x", "x");
    auto stuck = run("batch " + q(dir) + " -c " + q(kConfig) + " --out " + q(out) + " --format json");
    CHECK(stuck.exit_code == 5);
    CHECK_THAT(stuck.err, Catch::Contains(dir + "/bad.csv: an earlier run's summary " + out + "/bad.json could not be removed"));
    std::filesystem::remove_all(out + "/bad.json");
    // Identical to what `battsim replay --summary` writes for the same log.
    auto rep = run("replay " + q(dir + "/g2.csv") + " -c " + q(kConfig) + " --summary " + q(dir + "/rep.json"));
    REQUIRE(rep.exit_code == 0);
    CHECK(read_file(dir + "/rep.json") == read_file(out + "/g2.json"));

    // Markdown: the failure is spelt out in the status column.
    auto md = run("batch " + q(dir) + " -c " + q(kConfig));
    CHECK(md.exit_code == 1);
    CHECK(md.out.find("| bad | bad.csv | – | – |") != std::string::npos);
    CHECK(md.out.find("| error: " + dir + "/bad.csv:2:2: ") != std::string::npos);

    // The estimator is chosen for all logs from the command line and shows in the rows.
    auto joint = run("batch " + q(dir + "/g1.csv") + " -c " + q(kConfig) + " --estimator joint --format json");
    CHECK(joint.exit_code == 0);
    CHECK(nlohmann::json::parse(joint.out)["rows"][0]["estimator"] == "joint");

    // All good: exit 0.
    auto ok = run("batch " + q(dir + "/g*.csv") + " -c " + q(kConfig) + " --format csv");
    CHECK(ok.exit_code == 0);
    CHECK(ok.out.rfind("index,test,log,pack,monitor,config,estimator,status,", 0) == 0);

    // A log that fails on a rerun leaves no summary of the earlier run behind to be taken for this one's.
    clitest::write_file(dir + "/g2.csv", "627,16.57,4.14,4.14,4.14,4.16,47.99,0.39,\n628,oops,4.1,4.1,4.1,4.1,1,1,\n");
    CHECK(run("batch " + q(dir + "/g*.csv") + " -c " + q(kConfig) + " --out " + q(out)).exit_code == 1);
    CHECK(exists(out + "/g1.json"));
    CHECK_FALSE(exists(out + "/g2.json"));
}

TEST_CASE("batch: a config for another pack than the logs' is said, not only counted", "[cli][batch]") {
    // A 6S flight replayed with the 4S reference config: every row said "ok", and the note
    // that `replay` prints reached only the table's notes column (then a count). Its limits
    // keep every sample out: the row is no_valid_samples (it had read "ok"), the notes said.
    const std::string dir = clitest::temp_dir();
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/6s-hover-healthy.json") + " -o " + q(dir + "/six.csv"))
                .exit_code == 0);
    const auto r = run("batch " + q(dir + "/six.csv") + " -c " + q(kConfig) + " --no-progress --format json");
    INFO(r.err);
    REQUIRE(r.exit_code == 1);
    CHECK(nlohmann::json::parse(r.out)["rows"][0]["status"] == "no_valid_samples");
    CHECK_THAT(r.err, Catch::Contains("battsim batch: note: " + dir + "/six.csv: the pack rests at") &&
                          Catch::Contains(": battsim make-config --from-log " + dir + "/six.csv writes one for it (with --capacity-mah"));
    // With its own config, no such note.
    const auto own = run("batch " + q(dir + "/six.csv") + " -c " + q(kSource + "/configs/generic-6s.json") +
                         " --no-progress --format json");
    CHECK(own.exit_code == 0);
    CHECK_THAT(own.err, !Catch::Contains("does the config match"));
    // A 3S flight on the 4S config keeps its samples: its Markdown row had read a plain "ok"
    // next to figures of another pack.
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/3s-hover-healthy.json") + " -o " + q(dir + "/three.csv")).exit_code == 0);
    const auto three = run("batch " + q(dir + "/three.csv") + " -c " + q(kConfig) + " --no-progress");
    CHECK(three.exit_code == 0);
    CHECK_THAT(three.out, Catch::Contains("| ok (config for another pack: see notes) |"));
    const auto three_own = run("batch " + q(dir + "/three.csv") + " -c " + q(kSource + "/configs/generic-3s.json") + " --no-progress");
    CHECK_THAT(three_own.out, Catch::Contains("| ok |"));
}

TEST_CASE("batch: a log's notes are the table's notes column and said on stderr, as replay says them", "[cli][batch]") {
    // A truncated log: its row said "ok", the note that the file ends inside a message was
    // only in --out's summary, and the table's notes column held a count (1).
    const std::string dir = clitest::temp_dir();
    const std::string whole = dir + "/whole.bin", cut = dir + "/cut.bin";
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/3s-hover-healthy.json") + " --format dataflash -o " + q(whole))
                .exit_code == 0);
    const std::string bytes = read_file(whole);
    clitest::write_file(cut, bytes.substr(0, bytes.size() - 5));
    const std::string config = " -c " + q(kSource + "/configs/generic-3s.json");
    const auto r = run("batch " + q(cut) + config + " --no-progress --format json");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const nlohmann::json row = nlohmann::json::parse(r.out)["rows"][0];
    CHECK(row["status"] == "ok");
    REQUIRE(row["notes"].is_array());
    REQUIRE(row["notes"].size() == 1);
    CHECK_THAT(row["notes"][0].get<std::string>(), Catch::Contains("file ends inside a message of type BCL"));
    // What replay says of the log, batch says too, each line naming the log.
    const auto replay = run("replay " + q(cut) + config);
    REQUIRE(replay.exit_code == 0);
    CHECK_THAT(replay.err, Catch::Contains("battsim replay: note: byte "));
    CHECK_THAT(r.err, Catch::Contains("battsim batch: note: " + cut + ": " + row["notes"][0].get<std::string>() + "\n"));

    // With the 4S reference config it gains the config's notes of this log: in CSV, "; " apart.
    const auto csv = run("batch " + q(cut) + " -c " + q(kConfig) + " --no-progress --format csv");
    REQUIRE(csv.exit_code == 0);
    CHECK_THAT(csv.out, Catch::Contains("the partial message is ignored; the log has 3 cell voltages but the config 4"));
    // A shard's JSON merges back into the same CSV (merge reads the notes as text).
    REQUIRE(run("batch " + q(cut) + " -c " + q(kConfig) + " --no-progress --format json -o " + q(dir + "/s.json")).exit_code == 0);
    const auto merged = run("merge " + q(dir + "/s.json") + " --format csv");
    CHECK(merged.exit_code == 0);
    CHECK(merged.out == csv.out);
    // A whole log has none.
    const auto clean = run("batch " + q(whole) + config + " --no-progress --format json");
    CHECK(nlohmann::json::parse(clean.out)["rows"][0]["notes"] == nlohmann::json::array());
    CHECK(clean.err.find("note:") == std::string::npos);
}

TEST_CASE("batch: an empty directory's error row names it in the Markdown table, however it was written", "[cli][batch]") {
    // Given as "DIR/" (a shell's completion) with a manifest's test label, the row's log cell
    // had been empty and nothing in the row named the directory.
    const std::string dir = temp_dir();
    REQUIRE(::mkdir((dir + "/spring").c_str(), 0755) == 0);
    clitest::write_file(dir + "/m.json", R"({"schema": "battsim.manifest", "version": 1, "logs": [{"path": "spring/", "test": "T7"}]})");
    const auto r = run("batch -m " + q(dir + "/m.json") + " -c " + q(kConfig) + " --no-progress");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.out, Catch::Contains("| T7 | spring | – |") && Catch::Contains("error: directory holds no log files"));
}

TEST_CASE("batch: logs of one stem get summaries named by their paths, the same for any order and --jobs",
          "[cli][batch]") {
    // ArduPilot writes 00000001.BIN on every card: one folder per drone had refused the run (exit 2).
    const std::string dir = fleet_dir(0, false);
    for (const char* drone : {"quad-a", "quad-b"}) {
        REQUIRE(::mkdir((dir + "/" + drone).c_str(), 0755) == 0);
        clitest::write_file(dir + "/" + drone + "/00000001.csv", raw_flight(15, drone[5] == 'a' ? 0.0006 : 0.0012));
    }
    clitest::write_file(dir + "/quad-b/00000002.csv", raw_flight(18, 0.0009));
    const std::string a = q(dir + "/quad-a/00000001.csv"), b = q(dir + "/quad-b/00000001.csv"),
                      c = q(dir + "/quad-b/00000002.csv"), opts = " -c " + q(kConfig) + " --no-progress";
    auto r = run("batch " + a + " " + b + " " + c + opts + " --out " + q(dir + "/out") + " --jobs 2");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim batch: note: stem shared, summary named by its path: " + dir +
                                      "/quad-a/00000001.csv: quad-a__00000001.csv.json"));
    // Each is the replay's own summary of that log; a stem of its own keeps its name.
    for (const auto& [log, name] : std::vector<std::pair<std::string, std::string>>{
             {"quad-a/00000001.csv", "quad-a__00000001.csv"}, {"quad-b/00000001.csv", "quad-b__00000001.csv"},
             {"quad-b/00000002.csv", "00000002"}}) {
        INFO(log);
        REQUIRE(run("replay " + q(dir + "/" + log) + " -c " + q(kConfig) + " --summary " + q(dir + "/rep.json")).exit_code == 0);
        CHECK(read_file(dir + "/out/" + name + ".json") == read_file(dir + "/rep.json"));
    }
    // Another order, one job, the directories given instead: the same names, the same bytes.
    const std::string first = read_file(dir + "/out/quad-b__00000001.csv.json");
    r = run("batch " + q(dir + "/quad-b") + " " + q(dir + "/quad-a") + opts + " --out " + q(dir + "/out2") + " --jobs 1");
    REQUIRE(r.exit_code == 0);
    for (const char* name : {"quad-a__00000001.csv", "quad-b__00000001.csv", "00000002"})
        CHECK(read_file(dir + "/out2/" + name + ".json") == read_file(dir + "/out/" + name + ".json"));
    CHECK(std::distance(std::filesystem::directory_iterator(dir + "/out2"), std::filesystem::directory_iterator()) == 3);
    // --compare finds each golden by the same name.
    r = run("batch " + a + " " + b + " " + c + opts + " --compare " + q(dir + "/out"));
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("compare: 3 compared, 0 changed"));
    // A shard names them as the whole run does.
    r = run("batch " + a + " " + b + " " + c + opts + " --shard 2/2 --out " + q(dir + "/out3"));
    CHECK(r.exit_code == 0);
    CHECK(read_file(dir + "/out3/quad-b__00000001.csv.json") == first);
}

TEST_CASE("batch: logs no name can part are refused naming only the options given", "[cli][batch]") {
    // "a__b/x.csv" and "a/b/x.csv" are both a__b__x.csv: the one clash left, and its remedy.
    const std::string dir = fleet_dir(0, false);
    std::filesystem::create_directories(dir + "/a__b");
    std::filesystem::create_directories(dir + "/a/b");
    clitest::write_file(dir + "/a__b/x.csv", raw_flight(15, 0.0006));
    clitest::write_file(dir + "/a/b/x.csv", raw_flight(15, 0.0006));
    const std::string logs = q(dir + "/a__b/x.csv") + " " + q(dir + "/a/b/x.csv") + " -c " + q(kConfig) + " --no-progress";
    const std::string said = " summaries <log stem>.json (logs of one stem: <path below their common directory, / as __>.json), "
                             "but these logs would share one:\n  a__b__x.csv: " + dir + "/a__b/x.csv, " + dir + "/a/b/x.csv\n"
                             "battsim batch: rename one of the files (or its directory)\n";
    auto r = run("batch " + logs + " --out " + q(dir + "/out"));
    CHECK(r.exit_code == 2);
    // It had said "--out and --compare name summaries" without a --compare.
    CHECK(r.err == "battsim batch: --out names" + said);
    r = run("batch " + logs + " --compare " + q(dir));
    CHECK(r.exit_code == 2);
    CHECK(r.err == "battsim batch: --compare names" + said);
    r = run("batch " + logs + " --out " + q(dir + "/out") + " --compare " + q(dir));
    CHECK(r.exit_code == 2);
    CHECK(r.err == "battsim batch: --out and --compare name" + said);
    CHECK_FALSE(exists(dir + "/out"));
    // Without --out or --compare no summary is named: the table is made.
    CHECK(run("batch " + logs).exit_code == 0);
}

TEST_CASE("batch: a log the config keeps wholly out is a failed row, not ok, its summary kept", "[cli][batch]") {
    const std::string dir = fleet_dir(2, false);
    nlohmann::json cfg = nlohmann::json::parse(read_file(kConfig));
    cfg["sensor"]["max_pack_voltage_v"] = 10.0;  // below every reading of these 4S logs
    clitest::write_file(dir + "/low.json", cfg.dump());
    const std::string manifest = dir + "/m.csv";
    clitest::write_file(manifest, "path,pack,config\ng1.csv,P,low.json\ng2.csv,P," + kConfig + "\n");
    auto r = run("batch -m " + q(manifest) + " --no-progress --format json --out " + q(dir + "/out"));
    INFO(r.err);
    CHECK(r.exit_code == 1);
    const auto table = nlohmann::json::parse(r.out);
    CHECK(table["schema_version"] == 3);
    CHECK(table["version"] == 3);
    const auto& row = table["rows"][0];
    CHECK(row["status"] == "no_valid_samples");
    const std::string why = "the config's sensor limits kept out all " + row["samples"].dump() + " samples: " +
                            row["samples"].dump() + " pack_voltage_high (sensor.max_pack_voltage_v); does the config match this pack?";
    CHECK(row["error"] == why);
    CHECK(row["samples"].get<int>() > 0);
    CHECK(row["sensor_fault_samples"] == row["samples"]);
    CHECK(row["flight"] == false);
    CHECK(table["rows"][1]["status"] == "ok");
    CHECK(table["packs"][0]["failed"] == 1);  // counted in the summaries as failed
    CHECK_THAT(r.err, Catch::Contains("battsim batch: failed: " + dir + "/g1.csv: no valid samples: " + why + "\n") &&
                          Catch::Contains("1 of 2 logs failed"));
    // The summary computed is kept, as replay writes it; replay itself exits 1 on it.
    REQUIRE(exists(dir + "/out/g1.json"));
    CHECK(nlohmann::json::parse(read_file(dir + "/out/g1.json"))["samples"]["valid"] == 0);
    const auto rep = run("replay " + q(dir + "/g1.csv") + " -c " + q(dir + "/low.json") + " --summary " + q(dir + "/rep.json"));
    CHECK(rep.exit_code == 1);
    CHECK(read_file(dir + "/rep.json") == read_file(dir + "/out/g1.json"));
    // Markdown names it in the status column; merge takes such rows and fails as the run does.
    auto md = run("batch -m " + q(manifest) + " --no-progress");
    CHECK(md.exit_code == 1);
    CHECK_THAT(md.out, Catch::Contains("| no valid samples: " + why + " |"));
    for (const char* k : {"1", "2"})
        REQUIRE(run("batch -m " + q(manifest) + " --no-progress --format json --shard " + k + "/2 -o " + q(dir + "/s" + k + ".json"))
                    .exit_code == (k[0] == '1' ? 1 : 0));
    const auto merged = run("merge " + q(dir + "/s1.json") + " " + q(dir + "/s2.json") + " --format json");
    CHECK(merged.exit_code == 1);
    CHECK(nlohmann::json::parse(merged.out) == table);
}

TEST_CASE("batch: a Matrice 100 flight read with the default 4S config is no valid samples, not ok", "[cli][batch][data]") {
    // The 6S flight's every sample breaks the 4S config's sensor limits: it had read "ok".
    const auto r = run("batch " + q(kData + "/cmu-m100/flights/1.csv") + " --no-progress --format json");
    INFO(r.err);
    CHECK(r.exit_code == 1);
    const auto row = nlohmann::json::parse(r.out)["rows"][0];
    CHECK(row["status"] == "no_valid_samples");
    CHECK(row["sensor_fault_samples"] == row["samples"]);
    CHECK_THAT(row["error"].get<std::string>(), Catch::StartsWith("the config's sensor limits kept out all "));
}

TEST_CASE("batch: an output that cannot be written is said before the run; one that fails spares the others",
          "[cli][batch]") {
    const std::string dir = fleet_dir(2, false);
    auto r = run("batch " + q(dir) + " -c " + q(kConfig) + " -o " + q(dir + "/none/x.md") + " --packs " + q(dir + "/p.md"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("battsim batch: -o/--output: cannot write " + dir + "/none/x.md: the directory " +
                                      dir + "/none does not exist"));
    CHECK_FALSE(exists(dir + "/p.md"));
    // A name longer than the filesystem holds had failed only at the rename, after the run.
    const std::string long_name = dir + "/" + std::string(252, 't') + ".csv";
    r = run("batch " + q(dir) + " -c " + q(kConfig) + " -o " + q(long_name));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("cannot write " + long_name + ": the file name is 256 bytes, longer than the 255"));
    // Known only when written (a full disk): the others are still written.
    r = run("batch " + q(dir) + " -c " + q(kConfig) + " -o /dev/full --packs " + q(dir + "/p.md"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains("/dev/full: write failed"));
    CHECK(exists(dir + "/p.md"));
}

TEST_CASE("batch: output is byte-identical for any --jobs", "[cli][batch]") {
    const std::string dir = fleet_dir(7, true);
    for (const char* format : {"md", "csv", "json"}) {
        auto one = run("batch " + q(dir) + " -c " + q(kConfig) + " --jobs 1 --format " + format);
        auto two = run("batch " + q(dir) + " -c " + q(kConfig) + " --jobs 2 --format " + format);
        auto four = run("batch " + q(dir) + " -c " + q(kConfig) + " --jobs 4 --format " + format +
                        " --output " + q(dir + "/t4." + format));
        CHECK(one.exit_code == 1);
        CHECK(two.exit_code == 1);
        CHECK(four.exit_code == 1);
        CHECK_FALSE(one.out.empty());
        CHECK(one.out == two.out);
        CHECK(read_file(dir + "/t4." + format) == one.out);
        CHECK(four.out.empty());
    }
}

TEST_CASE("batch: a killed run's temporaries in the log directory are not read as logs; -j0 is every core",
          "[cli][batch]") {
    const std::string dir = fleet_dir(2, false);
    const std::string args = "batch " + q(dir) + " -c " + q(kConfig) + " --no-progress --out " + q(dir) + " --format csv";
    const auto first = run(args + " -o " + q(dir + "/table.csv"));
    REQUIRE(first.exit_code == 0);
    const std::string table = read_file(dir + "/table.csv");
    // What SIGKILL leaves mid-write: a summary's and a copy of a log's temporaries (the PIDs
    // are no process's), which the next nightly run had read as two more logs and failed.
    clitest::write_file(dir + "/g1.json.tmp.999999.0", read_file(dir + "/g1.json"));
    clitest::write_file(dir + "/g3.csv.tmp.999998.4", read_file(dir + "/g1.csv"));
    const auto second = run(args + " -j0 -o " + q(dir + "/table.csv"));
    INFO(second.err);
    CHECK(second.exit_code == 0);
    CHECK(second.err.find("tmp.99999") == std::string::npos);
    CHECK(read_file(dir + "/table.csv") == table);
}

TEST_CASE("batch: shards merged give exactly the single run's table", "[cli][batch]") {
    const std::string dir = fleet_dir(7, true);
    // Pack ids so the per-pack table is exercised too.
    std::string manifest = "path,pack\n";
    for (int k = 1; k <= 7; ++k) manifest += "g" + std::to_string(k) + ".csv," + (k % 3 ? "A" : "B") + "\n";
    manifest += "bad.csv,A\n";
    clitest::write_file(dir + "/fleet.csv", manifest);
    const std::string common = " --manifest " + q(dir + "/fleet.csv") + " -c " + q(kConfig);
    std::string shards;
    for (int k = 1; k <= 3; ++k) {
        const std::string p = dir + "/shard" + std::to_string(k) + ".json";
        auto r = run("batch" + common + " --format json --shard " + std::to_string(k) + "/3 --output " + q(p));
        CHECK(r.exit_code == (k == 2 ? 1 : 0));  // bad.csv is input 7, 7 mod 3 = 1: shard 2
        shards += " " + q(p);
    }
    for (const char* format : {"md", "csv", "json"}) {
        auto single = run("batch" + common + " --format " + format + " --packs " + q(dir + "/packs-single." + format));
        auto merged = run("merge" + shards + " --format " + format + " --packs " + q(dir + "/packs-merged." + format));
        INFO(merged.err);
        CHECK(single.exit_code == 1);
        CHECK(merged.exit_code == 1);
        CHECK_FALSE(single.out.empty());
        CHECK(merged.out == single.out);
        CHECK(read_file(dir + "/packs-merged." + format) == read_file(dir + "/packs-single." + format));
    }
    auto md = run("batch" + common);
    CHECK(md.out.find("| A | 6 | 1 |") != std::string::npos);  // g1 g2 g4 g5 g7 + bad
    CHECK(md.out.find("| B | 2 | 0 |") != std::string::npos);

    // A missing shard, a shard given twice, a shard of another run: refused, exit 3.
    const std::string s1 = dir + "/shard1.json", s2 = dir + "/shard2.json";
    auto missing = run("merge " + q(s1) + " " + q(s2));
    CHECK(missing.exit_code == 3);
    CHECK(missing.err.find("2 of 8 inputs are in none of the given tables (index 2, 5)") != std::string::npos);
    auto twice = run("merge " + q(s1) + " " + q(s1));
    CHECK(twice.exit_code == 3);
    auto other = run("batch " + q(dir + "/g1.csv") + " -c " + q(kConfig) + " --format json --shard 1/3 --output " +
                     q(dir + "/other.json"));
    REQUIRE(other.exit_code == 0);
    auto foreign = run("merge" + shards + " " + q(dir + "/other.json"));
    CHECK(foreign.exit_code == 3);
    CHECK(foreign.err.find("comes from a different input list") != std::string::npos);
}

TEST_CASE("batch --compare: passes on identical summaries, lists a changed field", "[cli][batch]") {
    const std::string dir = fleet_dir(3, false);
    const std::string golden = dir + "/golden";
    auto make = run("batch " + q(dir) + " -c " + q(kConfig) + " --out " + q(golden));
    REQUIRE(make.exit_code == 0);
    // Same logs reached by another path spelling: input.path differs and is ignored.
    auto same = run("batch " + q(dir + "/./") + " -c " + q(kConfig) + " --compare " + q(golden));
    INFO(same.err);
    CHECK(same.exit_code == 0);
    CHECK(same.err.find("compare: 3 compared, 0 changed, 0 without golden, 0 not replayed") != std::string::npos);

    // Change one field of one golden beyond the tolerance.
    auto g = nlohmann::json::parse(read_file(golden + "/g2.json"));
    const double mean = g["flight"]["capacity_ah"]["mean"].get<double>();
    g["flight"]["capacity_ah"]["mean"] = mean * 1.01;
    clitest::write_file(golden + "/g2.json", g.dump(2) + "\n");
    auto changed = run("batch " + q(dir) + " -c " + q(kConfig) + " --compare " + q(golden));
    CHECK(changed.exit_code == 1);
    CHECK(changed.err.find("compare: " + golden + "/g2.json: /flight/capacity_ah/mean: golden ") != std::string::npos);
    CHECK(changed.err.find("1 changed") != std::string::npos);
    // ... and a tolerance wide enough accepts it.
    auto loose = run("batch " + q(dir) + " -c " + q(kConfig) + " --compare " + q(golden) + " --tolerance 0.02");
    CHECK(loose.exit_code == 0);

    // A summary without a golden is a failure too (the golden set must cover the batch).
    std::remove((golden + "/g1.json").c_str());
    auto missing = run("batch " + q(dir) + " -c " + q(kConfig) + " --compare " + q(golden) + " --tolerance 0.02");
    CHECK(missing.exit_code == 1);
    CHECK(missing.err.find("no golden summary " + golden + "/g1.json") != std::string::npos);
}

TEST_CASE("batch: manifest and option errors are clear and exit non-zero", "[cli][batch]") {
    const std::string dir = fleet_dir(1, false);
    clitest::write_file(dir + "/m.json", "{\n  \"schema\": \"battsim.manifest\",\n  \"logs\": [\n    {\"path\": \"g1.csv\", \"pakc\": \"A\"}\n  ]\n}\n");
    auto r = run("batch --manifest " + q(dir + "/m.json"));
    CHECK(r.exit_code == 3);
    CHECK(r.err == "battsim batch: " + dir + "/m.json:4:24: $.logs[0].pakc: unknown key; expected one of average_ms, charged_mah, columns, config, "
                                               "current_source, estimator, format, monitor, no_temperature, pack, path, test\n");
    clitest::write_file(dir + "/m.csv", "path,pack\ng1.csv,A,extra\n");
    r = run("batch --manifest " + q(dir + "/m.csv"));
    CHECK(r.exit_code == 3);
    CHECK(r.err == "battsim batch: " + dir + "/m.csv:2:3: expected 2 fields as in the header, found 3\n");
    clitest::write_file(dir + "/c.json", "{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"g1.csv\", \"config\": \"nope.json\"}]}");
    // A manifest's config that cannot be read fails its logs' rows (the rest would still run).
    r = run("batch --manifest " + q(dir + "/c.json"));
    CHECK(r.exit_code == 1);
    CHECK(r.err.find("battsim batch: failed: " + dir + "/g1.csv: config: " + dir + "/nope.json: cannot open config file") !=
          std::string::npos);
    // ... and says which manifest row named it (a helper's sweep: the fleet's file had to be searched).
    CHECK_THAT(r.err, Catch::Contains("cannot open config file: no such file (named on " + dir + "/c.json:1:41)"));
    // The command line's is one mistake for the whole run.
    r = run("batch " + q(dir + "/g1.csv") + " -c " + q(dir + "/nope.json"));
    CHECK(r.exit_code == 4);
    CHECK(r.err.find(dir + "/nope.json: cannot open config file") != std::string::npos);
    r = run("batch --manifest " + q(dir + "/none.json"));
    CHECK(r.exit_code == 3);
    CHECK(r.err == "battsim batch: " + dir + "/none.json: cannot open manifest: no such file\n");

    CHECK(run("batch").exit_code == 2);
    CHECK(run("batch " + q(dir) + " --shard 0/2").exit_code == 2);
    CHECK(run("batch " + q(dir) + " --format xml").exit_code == 2);
    CHECK(run("batch " + q(dir) + " --time-unit hours").exit_code == 2);
    CHECK(run("batch " + q(dir) + " --estimator fancy").exit_code == 2);
    // Two logs with one stem are both written to --out, each named by its path.
    const std::string other = fleet_dir(1, false);
    r = run("batch " + q(dir + "/g1.csv") + " " + q(other + "/g1.csv") + " -c " + q(kConfig) + " --out " + q(dir + "/o"));
    CHECK(r.exit_code == 0);
    CHECK(std::distance(std::filesystem::directory_iterator(dir + "/o"), std::filesystem::directory_iterator()) == 2);
    // Outputs that cannot be written: exit 5, and no half-written file.
    clitest::write_file(dir + "/plain", "x");
    r = run("batch " + q(dir + "/g1.csv") + " --out " + q(dir + "/plain/sub"));
    CHECK(r.exit_code == 5);
    // Said before any log is replayed.
    CHECK(r.err.find("--out: cannot write " + dir + "/plain/sub: " + dir + "/plain is not a directory") != std::string::npos);
    r = run("batch " + q(dir + "/g1.csv") + " -o " + q(dir + "/missing-dir/table.md"));
    CHECK(r.exit_code == 5);
    CHECK_FALSE(exists(dir + "/missing-dir"));
    // A pattern that matches nothing is an error row, not silence.
    r = run("batch " + q(dir + "/*.bin") + " --format csv");
    CHECK(r.exit_code == 1);
    CHECK(r.out.find(",error,pattern matches no file,") != std::string::npos);
}

TEST_CASE("batch on the shared dissertation flights matches the committed goldens", "[cli][batch][data]") {
    const std::string dir = temp_dir();
    // The manifest finds the data through BATTSIM_DATA_DIR (its fallback is ../shared/data
    // beside the repository); point it at the data this build was configured with.
    ::setenv("BATTSIM_DATA_DIR", kData.c_str(), 1);
    auto r = run("batch --manifest " + q(kSource + "/configs/manifests/predictive-bms.json") + " --compare " +
                 q(kSource + "/tests/golden/predictive-bms-modified") + " --format json --out " + q(dir));
    INFO(r.err);
    CHECK(r.exit_code == 0);
    const auto t = nlohmann::json::parse(r.out);
    REQUIRE(t["rows"].size() == 4);
    CHECK(t["rows"][1]["test"] == "2");
    CHECK(t["rows"][1]["pack"] == "5");
    CHECK(t["rows"][1]["log"].get<std::string>().find("predictive-bms/flights/30.csv") != std::string::npos);
    CHECK(t["packs"].size() == 4);
    // The same files under --out are the goldens except for the recorded input path.
    auto g = nlohmann::json::parse(read_file(kSource + "/tests/golden/predictive-bms-modified/34.json"));
    auto o = nlohmann::json::parse(read_file(dir + "/34.json"));
    g["input"].erase("path");
    o["input"].erase("path");
    CHECK(g == o);
}

TEST_CASE("batch: the pack table weighs the flights' final capacities against their standard errors", "[cli][batch]") {
    // Four simulated flights of one healthy 4S pack (four seeds) replayed with the joint
    // estimator: the pack row's median, spread (interquartile range / 1.349) and median σ
    // are those of the rows' own finals.
    const std::string dir = temp_dir();
    std::string manifest = "path,pack,config\n";
    for (int k = 1; k <= 4; ++k) {
        const std::string log = dir + "/f" + std::to_string(k) + ".csv";
        REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/4s-racing-healthy-a.json") + " -o " + q(log) +
                    " --seed " + std::to_string(k))
                    .exit_code == 0);
        manifest += "f" + std::to_string(k) + ".csv,A," + kSource + "/configs/sim-4s.json\n";
    }
    clitest::write_file(dir + "/fleet.csv", manifest);
    auto r = run("batch -m " + q(dir + "/fleet.csv") + " --estimator joint --format json");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const auto t = nlohmann::json::parse(r.out);
    std::vector<double> finals, sigmas;
    for (const auto& row : t["rows"]) {
        REQUIRE(row["capacity_final_ah"].is_number());
        REQUIRE(row["capacity_final_sigma_ah"].is_number());
        finals.push_back(row["capacity_final_ah"].get<double>());
        sigmas.push_back(row["capacity_final_sigma_ah"].get<double>());
    }
    REQUIRE(finals.size() == 4);
    std::sort(finals.begin(), finals.end());
    std::sort(sigmas.begin(), sigmas.end());
    // Quartiles at positions 1.25 and 3.75 of four.
    const double q1 = finals[0] + 0.25 * (finals[1] - finals[0]);
    const double q3 = finals[2] + 0.75 * (finals[3] - finals[2]);
    const double spread = (q3 - q1) / 1.349;
    CHECK(spread > 0.0);  // the flights differ: the checks below are not 0 = 0
    const double sigma = 0.5 * (sigmas[1] + sigmas[2]);
    REQUIRE(t["packs"].size() == 1);
    const auto& p = t["packs"][0];
    CHECK(p["capacity_final_median_ah"].get<double>() == Approx(0.5 * (finals[1] + finals[2])));
    CHECK(p["capacity_final_spread_ah"].get<double>() == Approx(spread).epsilon(1e-5));
    CHECK(p["capacity_final_sigma_median_ah"].get<double>() == Approx(sigma));
    CHECK(p["capacity_scatter_ratio"].get<double>() == Approx(spread / sigma).epsilon(1e-5));
    // The reference estimator reports no σ: no ratio.
    auto ref = run("batch -m " + q(dir + "/fleet.csv") + " --format json");
    REQUIRE(ref.exit_code == 0);
    const auto rt = nlohmann::json::parse(ref.out);
    CHECK(rt["rows"][0]["capacity_final_sigma_ah"].is_null());
    CHECK(rt["packs"][0]["capacity_scatter_ratio"].is_null());
}

TEST_CASE("batch: a manifest's charged_mah checks each log's current sensor as replay --charged-mah does", "[cli][batch]") {
    const std::string dir = temp_dir();
    const std::string config = kSource + "/configs/sim-4s.json";
    std::string manifest = "path,config,charged_mah\n";
    std::vector<std::string> charged;
    for (const char* name : {"4s-racing-fault-current-gain", "4s-racing-healthy-b"}) {
        const std::string log = dir + "/" + name + ".csv";
        REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/" + name + ".json") + " -o " + q(log)).exit_code == 0);
        const auto truth = nlohmann::json::parse(read_file(dir + "/" + name + ".truth.json"));
        charged.push_back(std::to_string(truth["flight"]["log_charge_ah"].get<double>() * 1000.0));
        manifest += log + "," + config + "," + charged.back() + "\n";
    }
    // A log that never flies: the check has no charge to compare, the row fails, the summary stays.
    std::string idle;
    for (int k = 0; k < 200; ++k) idle += std::to_string(630 + 67 * k) + ",16.50,4.12,4.13,4.12,4.13,0.00,0.26,\n";
    clitest::write_file(dir + "/idle.csv", idle);
    manifest += dir + "/idle.csv," + config + ",500\n";
    clitest::write_file(dir + "/fleet.csv", manifest);
    auto r = run("batch -m " + q(dir + "/fleet.csv") + " --estimator joint --format json --out " + q(dir + "/out"));
    INFO(r.err);
    CHECK(r.exit_code == 1);  // the idle log's row
    const auto t = nlohmann::json::parse(r.out);
    REQUIRE(t["rows"].size() == 3);
    CHECK(t["rows"][0]["charger_fault"] == true);
    CHECK(t["rows"][0]["charger_ratio"].get<double>() == Approx(1.08).epsilon(0.003));
    CHECK(t["rows"][1]["charger_fault"] == false);
    CHECK(t["rows"][2]["status"] == "error");
    CHECK_THAT(t["rows"][2]["error"].get<std::string>(), Catch::Contains("charger check: the log counts no charge drawn"));
    CHECK(exists(dir + "/out/idle.json"));
    // The summary batch wrote is the one replay writes with the same count.
    const std::string log = dir + "/4s-racing-fault-current-gain.csv";
    REQUIRE(run("replay " + q(log) + " -c " + q(config) + " --estimator joint --charged-mah " + charged[0] + " --summary " +
                q(dir + "/replay.json")).exit_code == 0);
    CHECK(read_file(dir + "/replay.json") == read_file(dir + "/out/4s-racing-fault-current-gain.json"));
}

TEST_CASE("batch: a charger check's note (a charged_mah typed in Ah) is in the row's notes and on stderr", "[cli][batch]") {
    // A helper's sweep: charged_mah 1.5 for 1500 had been said only inside --out's summary.
    const std::string dir = temp_dir();
    const std::string log = dir + "/healthy.csv";
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/4s-racing-healthy-b.json") + " -o " + q(log)).exit_code == 0);
    clitest::write_file(dir + "/fleet.csv", "path,config,charged_mah\n" + log + "," + kSource + "/configs/sim-4s.json,1.5\n");
    auto r = run("batch -m " + q(dir + "/fleet.csv") + " --estimator joint --format json");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    const auto t = nlohmann::json::parse(r.out);
    REQUIRE(t["rows"].size() == 1);
    const std::string want = "charger check: the monitor counted ";
    bool in_row = false;
    for (const auto& n : t["rows"][0]["notes"]) in_row = in_row || n.get<std::string>().rfind(want, 0) == 0;
    CHECK(in_row);
    CHECK_THAT(r.err, Catch::Contains(log + ": " + want) && Catch::Contains("check that count (--charged-mah, or a manifest's charged_mah: in mAh)"));
}

TEST_CASE("batch: the monitor table pools a drone's charger checks into one gain, and compares it with the fleet", "[cli][batch]") {
    // Three monitors fly the same four packs (of several kinds): quad-A's current sensor
    // reads 8 % high (the suite's gain fault, on every flight), quad-B's and quad-C's are
    // clean. The charger's counts are the truth's, one of quad-B's 6 % short (a charge stopped
    // early), which that flight's own check flags and the pooled one outvotes.
    const std::string dir = temp_dir();
    const std::string config = kSource + "/configs/sim-4s.json";
    std::string manifest = "path,pack,monitor,config,charged_mah\n";
    const char* kinds[4] = {"4s-racing-healthy-b", "4s-racing-aged", "4s-hover-healthy", "4s-racing-capacity-75"};
    int seed = 0;
    for (int k = 0; k < 4; ++k) {
        for (const std::string monitor : {"quad-A", "quad-B", "quad-C"}) {
            auto s = nlohmann::json::parse(read_file(kSource + "/configs/scenarios/" + kinds[k] + ".json"));
            s["monitor_config"] = config;
            if (monitor == "quad-A") s["sensor"]["faults"]["current_gain_error"] = 0.08;
            const std::string tag = dir + "/" + monitor + "-" + std::to_string(k);
            clitest::write_file(tag + ".json", s.dump());
            REQUIRE(run("simulate " + q(tag + ".json") + " -o " + q(tag + ".csv") + " --seed " + std::to_string(++seed))
                        .exit_code == 0);
            const auto truth = nlohmann::json::parse(read_file(tag + ".truth.json"));
            double charged_mah = truth["flight"]["log_charge_ah"].get<double>() * 1000.0;
            if (monitor == "quad-B" && k == 1) charged_mah *= 0.94;
            manifest += tag + ".csv,pack-" + std::to_string(k) + "," + monitor + "," + config + "," +
                        std::to_string(charged_mah) + "\n";
        }
    }
    clitest::write_file(dir + "/fleet.csv", manifest);
    auto r = run("batch -m " + q(dir + "/fleet.csv") + " --estimator joint --format json --monitors " + q(dir + "/mon.json"));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const auto t = nlohmann::json::parse(r.out);
    REQUIRE(t["monitors"].size() == 3);
    const auto& a = t["monitors"][0];
    const auto& b = t["monitors"][1];
    const auto& c = t["monitors"][2];
    CHECK(a["monitor"] == "quad-A");
    CHECK(a["charger_pooled"] == 4);
    CHECK(a["charger_flagged"] == 4);
    CHECK(a["charger_fault"] == true);
    CHECK(a["charger_ratio_pooled"].get<double>() == Approx(1.08).epsilon(0.003));
    CHECK(a["suggested_current_gain"].get<double>() == Approx(1.0 / 1.08).epsilon(0.003));
    // quad-B: the short entry flags its own flight (1/0.94 = 1.064), not the monitor.
    CHECK(b["charger_flagged"] == 1);
    CHECK(b["charger_fault"] == false);
    CHECK(b["charger_ratio_pooled"].get<double>() == Approx(1.0).epsilon(0.003));
    // The pooled gain is the median of the rows' own suggestions.
    std::vector<double> s;
    for (const auto& row : t["rows"])
        if (row["monitor"] == "quad-A") s.push_back(row["charger_suggested_gain"].get<double>());
    std::sort(s.begin(), s.end());
    CHECK(a["suggested_current_gain"].get<double>() == Approx(0.5 * (s[1] + s[2])));
    // Without the charger: on the packs they share, quad-A reads capacities high and
    // resistances low against the other two, which read alike (+7.3 % when written).
    CHECK(a["fleet_flights"] == 4);
    CHECK(a["fleet_capacity_effect"].get<double>() > 0.03);
    CHECK(a["fleet_resistance_effect"].get<double>() < -0.03);
    CHECK(a["fleet_capacity_source"] == "after_rest");  // the suite's flights rest 60 s after landing
    // Within three of its own standard errors of the 8 % written (0.064 ± 0.007 since the
    // fifty-second session's simulator, 0.07–0.09 before: four flights' noise), and that
    // error small enough to tell 8 % from none.
    INFO(a.dump());
    const double gain_sigma = a["fleet_gain_error_sigma"].get<double>();
    CHECK(std::fabs(a["fleet_gain_error"].get<double>() - 0.08) < 3.0 * gain_sigma);
    CHECK(gain_sigma < 0.015);
    CHECK(a["fleet_gain_fault"] == true);
    CHECK(b["fleet_gain_fault"] == false);
    CHECK(c["fleet_gain_fault"] == false);
    // --monitors wrote the same table, in --format.
    CHECK(nlohmann::json::parse(read_file(dir + "/mon.json")) == t["monitors"]);
}

TEST_CASE("batch: what a config makes unreliable is said once, with how many logs it touches", "[cli][batch]") {
    // Every row's notes repeat it, and a fleet replayed with the joint estimator and no OCV
    // table would otherwise read plausible nonsense without a word on the terminal.
    const std::string dir = clitest::temp_dir();
    for (const char* name : {"a.csv", "b.csv"}) clitest::write_file(dir + "/" + name, read_file(kSource + "/logs/example-4s.csv"));
    const std::string logs = q(dir + "/a.csv") + " " + q(dir + "/b.csv");
    clitest::Result r = run("batch " + logs + " -c " + q(kConfig) + " --estimator joint --no-progress -o " + q(dir + "/t.md"));
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("battsim batch: note (2 logs), config reference-4s-modified: the joint estimator has no OCV table"));
    CHECK(r.err.find("no OCV table") == r.err.rfind("no OCV table"));  // once, not per log
    r = run("batch " + logs + " -c " + q(kSource + "/configs/sim-4s.json") + " --estimator joint --no-progress -o " + q(dir + "/t.md"));
    CHECK(r.exit_code == 0);
    CHECK(r.err.find("note (") == std::string::npos);
    r = run("batch " + logs + " -c " + q(kConfig) + " --no-progress -o " + q(dir + "/t.md"));  // the reference needs none
    CHECK(r.err.find("note (") == std::string::npos);
}

TEST_CASE("batch: a directory it may not read is said as such, not as one without logs", "[cli][batch]") {
    // An unreadable fleet folder had made the row "directory holds no log files", as if no
    // drone had flown. Root reads any directory, so as root the run drops that power (capsh).
    const std::string dir = fleet_dir(1, false);
    REQUIRE(::mkdir((dir + "/locked").c_str(), 0755) == 0);
    REQUIRE(::mkdir((dir + "/locked/sub").c_str(), 0755) == 0);
    clitest::write_file(dir + "/locked/sub/a.csv", raw_flight(12, 0.0006));
    REQUIRE(::chmod((dir + "/locked/sub").c_str(), 0) == 0);
    const std::string args = " batch \"" + dir + "/locked/sub\" \"" + dir + "/locked/*/*.csv\" \"" + dir +
                             "/g1.csv\" -c \"" + kConfig + "\" --format json --no-progress";
    clitest::Result r;
    if (::geteuid() != 0) {
        r = run(args);
    } else if (std::system("command -v capsh >/dev/null 2>&1") == 0) {
        r = testsupport::run_program("capsh", "--drop=cap_dac_override,cap_dac_read_search -- -c " +
                                                  q(std::string("\"") + BATTSIM_BINARY + "\"" + args));
    } else {
        ::chmod((dir + "/locked/sub").c_str(), 0755);
        WARN("running as root without capsh: the unreadable directory cannot be made; not checked");
        return;
    }
    ::chmod((dir + "/locked/sub").c_str(), 0755);  // so the scratch directory can be removed
    INFO(r.err);
    CHECK(r.exit_code == 1);
    const auto table = nlohmann::json::parse(r.out);
    REQUIRE(table["rows"].size() == 3);
    CHECK(table["rows"][0]["status"] == "error");
    CHECK(table["rows"][0]["error"] == "cannot read the directory: Permission denied");
    // A pattern that passes through it names the directory it could not read.
    CHECK(table["rows"][1]["status"] == "error");
    CHECK(table["rows"][1]["error"] == dir + "/locked/sub: cannot read the directory: Permission denied");
    CHECK(table["rows"][2]["status"] == "ok");
    CHECK_THAT(r.err, Catch::Contains("failed: " + dir + "/locked/sub: cannot read the directory: Permission denied"));
    CHECK(r.err.find("holds no log files") == std::string::npos);
}
