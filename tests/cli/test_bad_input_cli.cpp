// What a whole-product audit (thirty-second session) broke from the outside, each now a clear
// refusal or a kept result: odd file names, hostile documents, typos in options and counts.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "cli_util.h"
#include "raw_logs.h"

using clitest::q;
using clitest::run;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kExample = kSource + "/logs/example-4s.csv";
const std::string kConfig = kSource + "/configs/sim-4s.json";

// sim-4s.json with `edit` applied.
std::string edited_config(const std::string& dir, const std::string& name, void (*edit)(nlohmann::json&)) {
    nlohmann::json c = nlohmann::json::parse(clitest::read_file(kConfig));
    edit(c);
    const std::string path = dir + "/" + name;
    clitest::write_file(path, c.dump(2));
    return path;
}
}  // namespace

TEST_CASE("a log whose name is not UTF-8 is replayed and tabled, its name's bad byte replaced", "[cli]") {
    const std::string dir = clitest::temp_dir();
    const std::string latin1 = dir + "/lat\xe9n.csv";  // "latén" in Latin-1
    clitest::write_file(latin1, clitest::read_file(kExample));
    const auto brief = run("replay " + q(latin1) + " -c " + q(kConfig));
    INFO(brief.err);
    CHECK(brief.exit_code == 0);
    CHECK_THAT(brief.out, Catch::Contains("3913 samples"));
    const auto j = clitest::run_json("replay " + q(latin1) + " -c " + q(kConfig) + " --json");
    CHECK(j["input"]["path"].get<std::string>().find("lat\xef\xbf\xbdn.csv") != std::string::npos);  // U+FFFD
    // A batch loses no row for it, in JSON either.
    const auto b = run("batch " + q(latin1) + " " + q(kExample) + " -c " + q(kConfig) +
                       " --no-progress --format json -o " + q(dir + "/t.json"));
    INFO(b.err);
    CHECK(b.exit_code == 0);
    const auto table = nlohmann::json::parse(clitest::read_file(dir + "/t.json"));
    REQUIRE(table["rows"].size() == 2);
    CHECK(table["rows"][0]["status"] == "ok");
    CHECK(table["rows"][0]["capacity_mean_ah"] == table["rows"][1]["capacity_mean_ah"]);
}

TEST_CASE("a value nested 100,000 deep is refused in a few words, not a crash", "[cli]") {
    const std::string dir = clitest::temp_dir();
    const int n = 100000;
    clitest::write_file(dir + "/deep.json", "{\"schema\":\"battsim.manifest\",\"version\":1,\"logs\":[{\"path\":\"a.csv\",\"test\":" +
                                                std::string(n, '[') + std::string(n, ']') + "}]}");
    const auto r = run("batch -m " + q(dir + "/deep.json") + " --no-progress");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("$.logs[0].test: expected a string or a whole number, found an array of 1 value"));
    CHECK(r.err.size() < 400);
}

TEST_CASE("a voltage column in millivolts with a plain name is asked about, not read as a radio's 0.1 V steps", "[cli]") {
    // A helper's walkthrough: "voltage" holding mV read as 16,500 V "in 0.1 V steps, as a
    // radio's telemetry", with nothing said of the unit.
    const std::string dir = clitest::temp_dir();
    std::string log = "time_s,voltage,current_a\n";
    for (int k = 0; k < 100; ++k) log += std::to_string(0.1 * k) + "," + std::to_string(16500 - k) + ",0.3\n";
    clitest::write_file(dir + "/mv.csv", log);
    auto r = run("replay " + q(dir + "/mv.csv") + " --voltage-col voltage");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("100 pack_voltage_high (sensor.max_pack_voltage_v); a voltage in mV read as volts "
                                      "(name the column voltage_mv, or \"voltage (mV)\")?"));
    CHECK_THAT(r.err, !Catch::Contains("0.1 V steps"));
    CHECK_THAT(r.err, Catch::Contains("the pack rests at 16500.00 V, 4125.000 V per cell for the config's 4 cells in series, "
                                      "outside any lithium cell's resting range (2.9-4.45 V): a voltage in mV read as volts?"));
    CHECK_THAT(r.err, !Catch::Contains("make-config --from-log"));
    // A pack resting at volts of another cell count is not asked about millivolts: a
    // Matrice 100's 24.22 V on the built-in 4S config had been.
    std::string six = "time_s,voltage,current_a\n";
    for (int k = 0; k < 100; ++k) six += std::to_string(0.1 * k) + ",24.2,0.3\n";
    clitest::write_file(dir + "/six.csv", six);
    const auto r6 = run("replay " + q(dir + "/six.csv") + " --voltage-col voltage");
    CHECK(r6.exit_code == 1);
    CHECK_THAT(r6.err, Catch::Contains("100 pack_voltage_high (sensor.max_pack_voltage_v); does the config match this pack?"));
    CHECK_THAT(r6.err, !Catch::Contains("in mV"));
    // Named so, it reads.
    std::string named = log;
    named.replace(0, named.find('\n'), "time_s,voltage_mv,current_a");
    clitest::write_file(dir + "/named.csv", named);
    r = run("replay " + q(dir + "/named.csv"));
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, !Catch::Contains("pack_voltage_high"));
}

TEST_CASE("a JSON document with a NUL byte is refused where it is (the parser had read it as the end)", "[cli]") {
    // A helper's sweep: a config padded with NULs after its object read as whole, and one of
    // NULs alone said "unexpected end of input" at 1:1.
    const std::string dir = clitest::temp_dir();
    const std::string text = clitest::read_file(kConfig);
    clitest::write_file(dir + "/padded.json", text + std::string(64, '\0'));
    auto r = run("replay " + q(kExample) + " -c " + q(dir + "/padded.json"));
    CHECK(r.exit_code == 4);
    const long lines = static_cast<long>(std::count(text.begin(), text.end(), '\n'));
    CHECK_THAT(r.err, Catch::Contains("padded.json:" + std::to_string(lines + 1) + ":1: not valid JSON: a NUL byte at byte offset " +
                                      std::to_string(text.size()) + ": a JSON document is text and holds none"));
    clitest::write_file(dir + "/m.json", std::string(16, '\0'));
    r = run("batch -m " + q(dir + "/m.json"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("m.json:1:1: not valid JSON: a NUL byte at byte offset 0"));
}

TEST_CASE("a config's duplicate key, fractional count or crossed voltages are refused by name", "[cli]") {
    const std::string dir = clitest::temp_dir();
    // The last of two keys had won silently: 9 Ah read for a 1.55 Ah pack.
    std::string text = clitest::read_file(kConfig);
    const std::string key = "\"capacity_ah\": ";
    const auto at = text.find(key);
    REQUIRE(at != std::string::npos);
    text.insert(at, "\"capacity_ah\": 9.0, ");
    clitest::write_file(dir + "/dup.json", text);
    auto r = run("replay " + q(kExample) + " -c " + q(dir + "/dup.json"));
    CHECK(r.exit_code == 4);
    CHECK_THAT(r.err, Catch::Contains("$.battery.capacity_ah: the key is given twice in its object"));
    CHECK_THAT(r.err, Catch::Contains("dup.json:"));

    const std::string frac = edited_config(dir, "frac.json", [](nlohmann::json& c) { c["battery"]["cells_in_series"] = 2.5; });
    r = run("replay " + q(kExample) + " -c " + q(frac));
    CHECK(r.exit_code == 4);
    CHECK_THAT(r.err, Catch::Contains("$.battery.cells_in_series: expected a whole number, found 2.5"));

    const std::string crossed = edited_config(dir, "crossed.json", [](nlohmann::json& c) { c["battery"]["min_voltage_v"] = 17.0; });
    r = run("replay " + q(kExample) + " -c " + q(crossed));
    CHECK(r.exit_code == 4);
    CHECK_THAT(r.err, Catch::Contains("$.battery.min_voltage_v: must be below max_voltage_v"));
}

TEST_CASE("a charger count or tolerance that is no positive number is refused before the replay", "[cli]") {
    // They had been checked after the whole replay, with --series already written.
    const std::string dir = clitest::temp_dir();
    const std::string series = dir + "/cm.csv";
    for (const char* bad : {"--charged-mah 0", "--charged-mah nan", "--charged-mah inf",
                            "--charged-mah 1500 --charger-tolerance -1", "--charged-mah 1500 --charger-tolerance 0"}) {
        INFO(bad);
        const auto r = run("replay " + q(kExample) + " -c " + q(kConfig) + " " + bad + " --series " + q(series));
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains(std::string(bad).find("tolerance") != std::string::npos ? "--charger-tolerance"
                                                                                               : "--charged-mah"));
        CHECK_FALSE(std::filesystem::exists(series));
    }
}

TEST_CASE("option values found by a sweep of every command's options: refused before the work", "[cli]") {
    const std::string dir = clitest::temp_dir();
    // An empty value (an unset shell variable) had read as the option not given: the output
    // went unwritten with exit 0 (--series, -o) or failed after the work with exit 5.
    for (const std::string& args : {"replay " + q(kExample) + " --series ''", "replay " + q(kExample) + " -c ''",
                                    std::string("replay ''"), "batch " + q(kExample) + " -o ''", std::string("score -o ''"),
                                    "export-config -c " + q(kConfig) + " -o ''"}) {
        INFO(args);
        const auto r = run(args);
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains("expected a value, found an empty string"));
    }
    // A whole number written as a float reads as that number (`--max-points 1e5` had been "not
    // in range 20 to 100000000"); a fraction or a word is said to be no whole number (a word
    // had been "not in range" too).
    auto whole = run("fit " + q(kExample) + " -c " + q(kConfig) + " --params none --max-points 1e5 -j 2.0");
    CHECK(whole.exit_code == 0);
    whole = run("fit " + q(kExample) + " -c " + q(kConfig) + " --starts ''");  // still said to be empty
    CHECK_THAT(whole.err, Catch::Contains("--starts: expected a value, found an empty string"));
    for (const std::string& bad : {std::string("--starts 2.5"), std::string("--max-iterations abc")}) {
        INFO(bad);
        whole = run("fit " + q(kExample) + " -c " + q(kConfig) + " " + bad);
        CHECK(whole.exit_code == 2);
        CHECK_THAT(whole.err, Catch::Contains(": expected a whole number, found " + bad.substr(bad.find(' ') + 1)));
    }
    // `--summary=` with nothing after it (`--summary=$OUT`, OUT unset) had taken the next
    // argument, the log, as the summary's path.
    const std::string kept = clitest::read_file(kExample);
    auto eq = run("replay --summary= " + q(kExample) + " -c " + q(kConfig));
    CHECK(eq.exit_code == 2);
    CHECK_THAT(eq.err, Catch::Contains("--summary: expected a value, found an empty string"));
    CHECK(clitest::read_file(kExample) == kept);
    // A comma-separated list: `--params ,` had read as no value and taken the next argument, -c.
    for (const std::string& bad : {std::string("--params ,"), std::string("--params e0,,r"), std::string("--params= "),
                                   std::string("--cell-cols ,")}) {
        INFO(bad);
        const auto r = run("fit " + q(kExample) + " " + bad + " -c " + q(kConfig));
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains(bad.find('=') != std::string::npos
                                              ? "--params: expected a value, found an empty string"
                                              : "expected a comma-separated list, found an empty item in"));
    }
    // Each occurrence takes one list; repeated, the lists join ("e0, r" read as e0 and r).
    auto list = run("fit " + q(kExample) + " --params 'e0, r' --params kappa --max-iterations 1 --json -c " + q(kConfig));
    CHECK(list.exit_code == 0);
    nlohmann::json fitted = nlohmann::json::parse(list.out);
    std::vector<std::string> names;
    for (const auto& p : fitted.at("parameters")) names.push_back(p.at("name").get<std::string>());
    CHECK(names == std::vector<std::string>{"e0", "r", "kappa", "initial"});  // and the per-log initial charge
    // A share that is no number is said per item.
    list = run("calibrate " + q(kExample) + " --shares 0.2,x -c " + q(kConfig));
    CHECK(list.exit_code == 2);
    CHECK_THAT(list.err, Catch::Contains("--shares: expected a number in [0, 1], found x"));
    // -o over a config a scenario names (score, simulate) replaced it with a table or a log.
    const std::string suite = dir + "/suite";
    std::filesystem::create_directories(suite);
    clitest::write_file(dir + "/pack.json", clitest::read_file(kConfig));
    nlohmann::json sc = nlohmann::json::parse(clitest::read_file(kSource + "/configs/scenarios/4s-racing-healthy-a.json"));
    sc["monitor_config"] = "../pack.json";
    clitest::write_file(suite + "/sc.json", sc.dump());
    for (const std::string& args : {"score " + q(suite + "/sc.json") + " -j1 -o " + q(dir + "/pack.json"),
                                    "simulate " + q(suite + "/sc.json") + " -o " + q(dir + "/pack.json"),
                                    "simulate " + q(suite + "/sc.json") + " -o " + q(dir + "/s.csv") + " --truth " +
                                        q(dir + "/pack.json")}) {
        INFO(args);
        const auto r = run(args);
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains("the monitor config of"));
        CHECK(clitest::read_file(dir + "/pack.json") == clitest::read_file(kConfig));
    }
    // fit --add values outside the config reader's ranges had written a config nothing loads.
    for (const char* add : {"thermal:-300", "temperature:1e300", "rc:1e-300", "hysteresis:5"}) {
        INFO(add);
        const auto r = run("fit " + q(kExample) + " -c " + q(kConfig) + " --add " + add + " -o " + q(dir + "/f.json"));
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains(std::string("--add ") + add + ": "));
        CHECK_FALSE(std::filesystem::exists(dir + "/f.json"));
    }
    // bench --passes -1 had wrapped to 2^64 - 1 passes (a hang); log --max-wait 0 had meant
    // "wait for ever"; --charged-mah below 1 mAh had printed LONG_MIN percent.
    const std::pair<std::string, std::string> refused[] = {
        {"bench monitor " + q(kExample) + " --passes -1", "--passes: Value -1 not in range 1 to 100000000"},
        {"log --port /nonexistent --out " + q(dir + "/l.csv") + " --max-wait 0", "--max-wait: expected a number in (0, "},
        {"replay " + q(kExample) + " --charged-mah 1e-300", "--charged-mah: expected a number in [1, "},
        // Options that act only with another had been dropped alone; a name given twice, kept twice.
        {"batch " + q(kExample) + " --tolerance 0.1 -o " + q(dir + "/t.md"), "--tolerance requires --compare"},
        {"make-config --format ulog --cells 4 --capacity-mah 1500 -o " + q(dir + "/m.json"), "--format requires --from-log"},
        {"score --columns joint,joint -j1 " + q(kSource + "/configs/scenarios/4s-racing-healthy-a.json"),
         "--columns: \"joint\" given twice"},
        {"residual " + q(kExample) + " --fixed q,q", "--fixed: parameter \"q\" given twice"},
        {"fit " + q(kExample) + " --params abc", "--params: unknown parameter \"abc\"; expected one of e0, r, kappa"},
        {"fit " + q(kExample) + " --per-log rr", "--per-log: unknown parameter \"rr\"; expected one of e0, r, kappa"},
        {"discharge " + q(kExample) + " -c " + q(kConfig) + " --decimate 5000",
         "--decimate 5000 averages the discharge's 3913 samples into 1 point; expected at most 1956"},
        {"batch " + q(kExample) + " -j -1 -o " + q(dir + "/t.md"), "--jobs: Value -1 not in range 0 to 1024"}};
    for (const auto& [args, said] : refused) {
        INFO(args);
        const auto r = run(args);
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains(said));
        // Before any log is read (a helper's walkthrough: a misspelt name came after minutes of reading).
        CHECK_THAT(r.err, !Catch::Contains(": reading "));
    }
    // A missing log is said as such before the default config's missing OCV table (exit 1).
    const auto cal = run("calibrate " + q(dir + "/nonexistent.csv"));
    CHECK(cal.exit_code == 3);
    CHECK_THAT(cal.err, Catch::Contains("nonexistent.csv: cannot open file: No such file or directory"));
}

TEST_CASE("a charger count far from the monitor's suggests no gain and writes no config", "[cli]") {
    // 2,000,000 mAh for a 1.55 Ah flight (Ah typed as mAh): the gain it implied was out of
    // the range the config reader accepts, so --config-out had left an unloadable config.
    const std::string dir = clitest::temp_dir();
    const std::string pack = dir + "/pack.json";
    clitest::write_file(pack, clitest::read_file(kConfig));
    const auto r = run("replay " + q(kExample) + " -c " + q(pack) + " --charged-mah 2000000 --config-out " + q(pack));
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("check that count (--charged-mah, or a manifest's charged_mah: in mAh)"));
    CHECK(clitest::read_file(pack) == clitest::read_file(kConfig));
    const auto j = clitest::run_json("replay " + q(kExample) + " -c " + q(pack) + " --charged-mah 2000000 --json");
    CHECK(j["charger_check"]["suggested_current_gain"].is_null());
    CHECK(j["charger_check"]["fault"].is_null());
    // mAh given as Ah: the typo is said alone (the start's deficit, measured against the
    // count, had been said first: "the pack was not charged full").
    const auto typo = clitest::run_json("replay " + q(kExample) + " -c " + q(pack) + " --charged-mah 1.5 --json");
    REQUIRE(typo["charger_check"]["notes"].size() == 1);
    CHECK_THAT(typo["charger_check"]["notes"][0].get<std::string>(), Catch::Contains("check that count (--charged-mah, or a manifest's charged_mah: in mAh)"));
    // Within tolerance the brief says no change is needed, not "suggested gain".
    const double counted_mah = j["charger_check"]["counted_ah"].get<double>() * 1000.0;
    const auto fine = run("replay " + q(kExample) + " -c " + q(pack) + " --charged-mah " + std::to_string(counted_mah));
    CHECK_THAT(fine.out, Catch::Contains("within tolerance; no change needed (the gain it implies: 1.0000)"));
}

TEST_CASE("batch keeps a log's numbers when its summary file cannot be written, and exits 5", "[cli]") {
    const std::string dir = clitest::temp_dir();
    std::filesystem::create_directories(dir + "/out/example-4s.json");  // a directory where the summary goes
    const auto r = run("batch " + q(kExample) + " -c " + q(kConfig) + " --no-progress --format json --out " + q(dir + "/out") +
                       " -o " + q(dir + "/t.json"));
    CHECK(r.exit_code == 5);
    CHECK_THAT(r.err, Catch::Contains(kExample + ": summary not written: "));
    const auto table = nlohmann::json::parse(clitest::read_file(dir + "/t.json"));
    REQUIRE(table["rows"].size() == 1);
    CHECK(table["rows"][0]["status"] == "ok");
    CHECK(table["rows"][0]["capacity_mean_ah"].is_number());
}

TEST_CASE("option typos are refused with the range in plain figures", "[cli]") {
    struct Case {
        std::string args, says;
    };
    const std::string scenario = q(kSource + "/configs/scenarios/4s-racing-healthy-a.json");
    const std::string dir = clitest::temp_dir();
    const Case cases[] = {
        {"bench monitor " + q(kExample) + " --min-time nan", "--min-time: expected a number in [0, 3600], found nan"},
        {"simulate " + scenario + " -o " + q(dir + "/s.csv") + " --seed -1", "--seed: expected a whole number from 0"},
        {"simulate " + scenario + " -o " + q(dir + "/s.csv") + " --seed 99999999999999999999", "--seed: expected a whole number"},
        {"replay " + q(kExample) + " --speed 2", "--speed requires --realtime"},
        {"replay " + q(kExample) + " --realtime --speed 1e-30", "--speed: expected a number in [0.001, 1e+06]"},
        {"make-config --cells 4 --capacity-mah 0", "--capacity-mah: expected a number in (0, 1e+06], found 0"},
        {"discharge " + q(kExample) + " -c " + q(kConfig) + " --max-voltage 100000", "--max-voltage: expected a number in (0, 200], found 100000"},
        {"discharge " + q(kExample) + " -c " + q(kConfig) + " --alpha nan", "--alpha: expected a number in (0, 1]"},
        {"discharge " + q(kExample) + " -c " + q(kConfig) + " --min-voltage nan", "--min-voltage: expected a number in (0, 200], found nan"},
        {"fit-ocv " + q(kExample) + " --prior-sigma nan", "--prior-sigma: expected a number in [1e-06, 1e+06]"},
        // The parser's own messages are named by the command, as every other one is.
        {"replay", "battsim replay: LOG is required\n(battsim replay --help)"},
        {"batch -j x", "battsim batch: --jobs: expected a whole number, found x"},
        {"", "battsim: A subcommand is required"},
        {"merge -", "battsim merge: the tables are read from files, not standard input"},
    };
    for (const Case& c : cases) {
        INFO(c.args);
        const auto r = run(c.args);
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains(c.says));
        CHECK(r.err.size() < 400);
    }
    CHECK_FALSE(std::filesystem::exists(dir + "/s.csv"));
}

TEST_CASE("export-config keeps a description that ends in a backslash inside its comment", "[cli]") {
    // A trailing backslash had spliced the next line, the #pragma once, into the comment.
    const std::string dir = clitest::temp_dir();
    const std::string cfg =
        edited_config(dir, "bs.json", [](nlohmann::json& c) { c["description"] = std::string("ends in a backslash \\\nand a NUL ") + '\0'; });
    const auto r = run("export-config --firmware " + q(cfg) + " -o " + q(dir + "/h.h"));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const std::string h = clitest::read_file(dir + "/h.h");
    CHECK(h.find('\0') == std::string::npos);
    CHECK(h.find("\\\n") == std::string::npos);
    CHECK_THAT(h, Catch::Contains("// ends in a backslash / and a NUL  \n#pragma once\n"));
}

TEST_CASE("merge refuses a shard row whose value is not of the type batch writes", "[cli]") {
    const std::string dir = clitest::temp_dir();
    const std::string example2 = dir + "/example2.csv";
    clitest::write_file(example2, clitest::read_file(kExample));
    const std::string logs = q(kExample) + " " + q(example2) + " -c " + q(kConfig) + " --no-progress --format json";
    REQUIRE(run("batch " + logs + " --shard 1/2 -o " + q(dir + "/s1.json")).exit_code == 0);
    REQUIRE(run("batch " + logs + " --shard 2/2 -o " + q(dir + "/s2.json")).exit_code == 0);
    CHECK(run("merge " + q(dir + "/s1.json") + " " + q(dir + "/s2.json") + " --format csv -o " + q(dir + "/m.csv")).exit_code == 0);
    nlohmann::json bad = nlohmann::json::parse(clitest::read_file(dir + "/s1.json"));
    bad["rows"][0]["capacity_mean_ah"] = "x";
    clitest::write_file(dir + "/bad.json", bad.dump());
    auto r = run("merge " + q(dir + "/bad.json") + " " + q(dir + "/s2.json") + " --format csv -o " + q(dir + "/m2.csv"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("bad.json: rows[0].capacity_mean_ah: expected a number or null, found \"x\""));
    bad = nlohmann::json::parse(clitest::read_file(dir + "/s1.json"));
    bad["rows"][0]["extra"] = 1;
    clitest::write_file(dir + "/bad.json", bad.dump());
    r = run("merge " + q(dir + "/bad.json") + " " + q(dir + "/s2.json") + " --format csv -o " + q(dir + "/m2.csv"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("rows[0].extra: not a key batch writes"));
    CHECK_FALSE(std::filesystem::exists(dir + "/m2.csv"));
}

TEST_CASE("bench batch refuses logs that do not replay instead of timing them", "[cli]") {
    const auto r = run("bench batch " + q(kExample) + " /nonexistent/x.csv --min-time 0 --min-runs 1");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("/nonexistent/x.csv: cannot open file"));
    // No run is no figure: it had printed "runs: 0" and rates of 0.0 with exit 0.
    for (const char* kind : {"replay", "batch"}) {
        const auto none = run(std::string("bench ") + kind + " " + q(kExample) + " --min-time 0 --min-runs 0");
        CHECK(none.exit_code == 2);
        CHECK_THAT(none.err, Catch::Contains("--min-runs: Value 0 not in range 1"));
    }
}

TEST_CASE("averaging into minute-long windows is not taken for a time column in milliseconds", "[cli]") {
    const auto r = run("replay " + q(kExample) + " -c " + q(kConfig) + " --average-ms 60000");
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, !Catch::Contains("--time-unit ms"));
    CHECK_THAT(r.err, Catch::Contains("samples averaged over 60000 ms windows: 3913 read into"));  // it did average
}

TEST_CASE("small typos that read on unseen: a weak cell twice, a misspelt --fixed, an upper-case plot name", "[cli]") {
    const std::string dir = clitest::temp_dir();
    nlohmann::json sc = nlohmann::json::parse(clitest::read_file(kSource + "/configs/scenarios/4s-racing-healthy-a.json"));
    sc["monitor_config"] = kConfig;
    sc["pack"]["weak_cells"] = {{{"cell", 2}, {"capacity_factor", 0.8}}, {{"cell", 2}, {"capacity_factor", 0.5}}};
    clitest::write_file(dir + "/twice.json", sc.dump(2));
    auto r = run("simulate " + q(dir + "/twice.json") + " -o " + q(dir + "/t.csv"));
    CHECK(r.exit_code == 4);
    CHECK_THAT(r.err, Catch::Contains("$.pack.weak_cells[1].cell: cell 2 is given twice"));
    r = run("residual " + q(kExample) + " -c " + q(kConfig) + " --fixed foo");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("--fixed: unknown parameter \"foo\""));
    CHECK_THAT(r.err, !Catch::Contains("residual: residual:"));
    // An effect's name from the other command: fit --add's short names in residual and
    // residual's names in fit --add (both had been refused); an unknown one lists them.
    r = run("residual " + q(kExample) + " -c " + q(kConfig) + " --candidates thermal --max-effects 1");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("effect 1 of at most 1: trying self_heating"));
    r = run("residual " + q(kExample) + " -c " + q(kConfig) + " --candidates rc_polarization");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("unknown candidate \"rc_polarization\"; expected rc_polarisation, temperature"));
    CHECK_THAT(r.err, !Catch::Contains("residual: reading "));
    r = run("fit " + q(kExample) + " -c " + q(kConfig) + " --add self_heating --params none --json");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    r = run("fit " + q(kExample) + " -c " + q(kConfig) + " --add heating");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("--add: unknown extension \"heating\"; expected rc, temperature, thermal"));
    // Checked before the replay: an upper-case extension is a PNG as well.
    r = run("replay " + q(kExample) + " -c " + q(kConfig) + " --plot " + q(dir + "/p.TXT"));
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("expected a name ending in .png or .svg"));
    r = run("replay " + q(kExample) + " -c " + q(kConfig) + " --plot " + q(dir + "/p.SVG"));
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(std::filesystem::file_size(dir + "/p.SVG") > 1000);
}

TEST_CASE("simulate --out-dir makes the directory; make-config writes clean decimals", "[cli]") {
    const std::string dir = clitest::temp_dir();
    const auto r = run("simulate " + q(kSource + "/configs/scenarios/4s-racing-healthy-a.json") + " --out-dir " + q(dir + "/new/sub"));
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(std::filesystem::exists(dir + "/new/sub/4s-racing-healthy-a.csv"));
    const auto m = run("make-config --cells 4 --capacity-mah 1760 -o -");
    REQUIRE(m.exit_code == 0);
    const auto j = nlohmann::json::parse(m.out);
    CHECK(j["battery"]["exponential_voltage_v"].dump() == "15.26");
    CHECK(m.out.find("00000000") == std::string::npos);
}

TEST_CASE("a CSV log with time_s and time_ms is refused until one is chosen (--time-col, a manifest's columns)", "[cli]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/two.csv";
    // time_ms is not time_s x 1000 here: which one was read had changed the flight's length.
    std::string text = "time_s,time_ms,voltage_v,current_a\n";
    for (int k = 0; k < 600; ++k)
        text += std::to_string(k) + "," + std::to_string(k * 500) + "," + std::to_string(16.6 - 0.001 * k) + "," + (k < 100 ? "0.3" : "12") + "\n";
    clitest::write_file(log, text);
    auto r = run("replay " + q(log) + " -c " + q(kConfig));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains(log + ":1:2: columns \"time_s\" (field 1) and \"time_ms\" (field 2) both give the time; "
                                            "expected one, or choose it with --time-col NAME (in a manifest, columns.time or time_col)"));
    const auto s = clitest::run_json("replay " + q(log) + " -c " + q(kConfig) + " --time-col time_ms --json");
    CHECK(s["duration_s"].get<double>() == Approx(299.5));
    clitest::write_file(dir + "/m.csv", "path,time_col\ntwo.csv,time_s\n");
    r = run("batch -m " + q(dir + "/m.csv") + " --no-progress --format json");
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const auto row = nlohmann::json::parse(r.out)["rows"][0];
    CHECK(row["status"] == "ok");
    // The manifest's column read, not only accepted: time_s's flight, not time_ms's.
    const auto by_s = clitest::run_json("replay " + q(log) + " -c " + q(kConfig) + " --time-col time_s --json");
    REQUIRE(by_s["flight"].is_object());
    CHECK(row["flight_duration_s"] == by_s["flight"]["duration_s"]);
    CHECK(row["flight_duration_s"] != s["flight"]["duration_s"]);
}

TEST_CASE("a log listed twice, in a manifest or on the command line, is refused naming both", "[cli]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/logs/a.csv", clitest::read_file(kExample));
    clitest::write_file(dir + "/logs/b.csv", clitest::read_file(kExample));
    clitest::write_file(dir + "/m.csv", "path,pack\nlogs/a.csv,P\nlogs/b.csv,P\nlogs/a.csv,P\n");
    auto r = run("batch -m " + q(dir + "/m.csv") + " -c " + q(kConfig) + " --no-progress");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains(dir + "/m.csv:4: \"" + dir + "/logs/a.csv\" names the same log as \"" + dir +
                                      "/logs/a.csv\" on line 2; list each log once"));
    CHECK(r.out.empty());
    r = run("batch " + q(dir + "/logs/a.csv") + " " + q(dir + "/logs/b.csv") + " " + q(dir + "/logs/./a.csv") + " -c " +
            q(kConfig) + " --no-progress");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("battsim batch: \"" + dir + "/logs/./a.csv\" names the same log as \"" + dir + "/logs/a.csv\""));
    // A directory and one of its files: the same log twice.
    r = run("batch " + q(dir + "/logs") + " " + q(dir + "/logs/b.csv") + " -c " + q(kConfig) + " --no-progress");
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("(from \"" + dir + "/logs\")"));
    r = run("fit-ocv -m " + q(dir + "/m.csv") + " -c " + q(kConfig));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("names the same log as"));
}

TEST_CASE("log --port names what it expected when the path is no serial device", "[cli]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/file", "x\n");
    std::filesystem::create_directory(dir + "/dir");
    for (const auto& [port, is] : {std::pair<std::string, std::string>{dir + "/file", "it is a regular file"},
                                   {dir + "/dir", "it is a directory"},
                                   {"/dev/null", "a character device that is no terminal"}}) {
        const auto r = run("log --port " + q(port) + " --out " + q(dir + "/out.csv") + " --max-wait 1");
        INFO(r.err);
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains("battsim log: --port " + port + ": not a serial device (tty): " + is +
                                          "; expected the serial port of the battsim firmware, e.g. /dev/ttyUSB0"));
        // No output is left behind: refused before it is made, or (a character device shows
        // itself only when opened) the empty file made for it removed.
        CHECK_FALSE(std::filesystem::exists(dir + "/out.csv"));
    }
    // A path not there yet is waited for (a device plugged in later), and said so; the output
    // made for it goes again when nothing came.
    const auto r = run("log --port " + q(dir + "/none") + " --out " + q(dir + "/n.csv") + " --max-wait 0.2");
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("waiting for " + dir + "/none to appear (a serial device, tty)"));
    CHECK_THAT(r.err, Catch::Contains("never appeared (expected a serial device, tty)"));
    CHECK_FALSE(std::filesystem::exists(dir + "/n.csv"));
    // An existing output, even an empty one, is the user's: kept.
    clitest::write_file(dir + "/kept.csv", "");
    CHECK(run("log --port /dev/null --out " + q(dir + "/kept.csv") + " --max-wait 1").exit_code == 2);
    CHECK(std::filesystem::exists(dir + "/kept.csv"));
}

namespace {
// The raw test flight with its clock put an hour ahead from row `from` on.
std::string jumped_at(const std::string& text, size_t from) {
    std::string jumped;
    size_t row = 0, start = 0;
    for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1, ++row) {
        std::string line = text.substr(start, end - start + 1);
        if (row >= from) {
            const size_t comma = line.find(',');
            line = std::to_string(std::stol(line.substr(0, comma)) + 3600000) + line.substr(comma);
        }
        jumped += line;
    }
    return jumped;
}
}  // namespace

TEST_CASE("a log whose clock jumps is said, and --realtime does not wait the jump out", "[cli]") {
    // Two sessions in one file, an hour apart on the ground: the charge over the hour was
    // counted at the currents either side without a word (with the reference estimator),
    // and --realtime slept through the hour.
    const std::string dir = clitest::temp_dir();
    const std::string text = testsupport::raw_flight(12, 0.001);
    clitest::write_file(dir + "/two.csv", jumped_at(text, 100));
    auto r = run("replay " + q(dir + "/two.csv") + " -c " + q(kConfig) + " --json");
    REQUIRE(r.exit_code == 0);
    const nlohmann::json j = nlohmann::json::parse(r.out);
    bool said = false;
    for (const auto& note : j["input"]["notes"])
        said = said || note.get<std::string>().find("the log's clock jumps 3600 s at") == 0;
    CHECK(said);
    // Two jumps: the longest said, and how many (a lab file's 13 pulse sets had read as one).
    clitest::write_file(dir + "/three.csv", jumped_at(jumped_at(text, 100), 101));
    r = run("replay " + q(dir + "/three.csv") + " -c " + q(kConfig) + " --json");
    REQUIRE(r.exit_code == 0);
    const nlohmann::json twice = nlohmann::json::parse(r.out);
    said = false;
    for (const auto& note : twice["input"]["notes"])
        said = said || note.get<std::string>().find("; it is the longest of 2 jumps over 60 s, 7200 s in all") != std::string::npos;
    CHECK(said);
    // A stretch written once a minute (a lab file's rest), its intervals a few ms either side
    // of 60 s, is said as such: Panasonic's -10 degC file had read "clock jumps 60 s … the
    // longest of 46 jumps" for 119 rows a minute apart.
    std::string slow;
    {
        size_t row = 0, start = 0;
        long shift_ms = 0;
        for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1, ++row) {
            std::string line = text.substr(start, end - start + 1);
            if (row >= 100 && row < 110) shift_ms += 60000 + (row % 2 ? 7 : -7) - 67;  // 60 s apart, ±7 ms
            if (row >= 1) {
                const size_t comma = line.find(',');
                line = std::to_string(std::stol(line.substr(0, comma)) + shift_ms) + line.substr(comma);
            }
            slow += line;
        }
    }
    clitest::write_file(dir + "/slow.csv", slow);
    r = run("replay " + q(dir + "/slow.csv") + " -c " + q(kConfig) + " --json");
    REQUIRE(r.exit_code == 0);
    said = false;
    const nlohmann::json slow_summary = nlohmann::json::parse(r.out);
    for (const auto& note : slow_summary["input"]["notes"])
        said = said || note.get<std::string>().find("the log is written every 60 s (their mean) at 10 intervals in 1 stretch") == 0;
    CHECK(said);
    CHECK(r.out.find("clock jumps") == std::string::npos);
    // The unbroken log has no such note.
    clitest::write_file(dir + "/one.csv", text);
    r = run("replay " + q(dir + "/one.csv") + " -c " + q(kConfig) + " --json");
    CHECK(r.out.find("clock jumps") == std::string::npos);
    // 37 s of log at 10 x: about 4 s, plus at most 2 s for the jump (it had waited 360 s).
    const std::string cmd = "timeout 60 " + q(BATTSIM_BINARY) + " replay " + q(dir + "/two.csv") + " -c " + q(kConfig) +
                            " --realtime --speed 10 --series " + q(dir + "/s.csv") + " > /dev/null 2>&1";
    const int status = std::system(cmd.c_str());
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 0);  // 124: timeout stopped it
}

TEST_CASE("a clock step in flight is read as one, and the flight is the unbroken log's", "[cli]") {
    // At 12 A either side, an hour's jump would be 12 Ah on a 1.55 Ah pack: counted as a gap,
    // it had run the state of charge far below empty and read volts of model error.
    const std::string dir = clitest::temp_dir();
    const std::string text = testsupport::raw_flight(12, 0.001);
    clitest::write_file(dir + "/step.csv", jumped_at(text, 300));
    clitest::write_file(dir + "/one.csv", text);
    auto r = run("replay " + q(dir + "/step.csv") + " -c " + q(kConfig) + " --json");
    REQUIRE(r.exit_code == 0);
    nlohmann::json stepped = nlohmann::json::parse(r.out);
    r = run("replay " + q(dir + "/one.csv") + " -c " + q(kConfig) + " --json");
    REQUIRE(r.exit_code == 0);
    nlohmann::json one = nlohmann::json::parse(r.out);
    const std::vector<std::string> notes = stepped["input"]["notes"];
    REQUIRE(notes.size() == 1);
    CHECK_THAT(notes[0], Catch::StartsWith("the log's clock steps 3600.07 s ahead at 20.033 s into the log, with 12 A "
                                           "before and 12 A after"));
    CHECK_THAT(notes[0], Catch::EndsWith("the samples after it are read 3600 s earlier, to follow on"));
    // One usual interval (67 ms) across the step: the same samples at the same times.
    stepped.erase("input");
    one.erase("input");
    CHECK(stepped == one);
}

TEST_CASE("a log given twice is refused where it would count twice: fit, residual, fit-ocv, score", "[cli]") {
    // Twice, it had weighed double: fit's standard errors fell by √2, residual's test took
    // an effect one copy does not earn, fit-ocv fitted "2 flights", score scored 2.
    const std::string dir = clitest::temp_dir();
    std::filesystem::copy_file(kExample, dir + "/a.csv");
    std::filesystem::create_symlink(dir + "/a.csv", dir + "/link.csv");
    const std::string a = q(dir + "/a.csv"), other = q(dir + "/./link.csv");
    for (const std::string& args : {"fit " + a + " " + other + " -c " + q(kConfig) + " --params none",
                                    "fit " + a + " -c " + q(kConfig) + " --params none --test " + other,
                                    "residual " + a + " " + other + " -c " + q(kConfig),
                                    "fit-ocv " + a + " " + other + " -c " + q(kConfig) + " -o " + q(dir + "/t.json")}) {
        const auto r = run(args);
        INFO(args);
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.err, Catch::Contains("names the same file as a log \"" + dir + "/a.csv\"; give each once"));
    }
    const std::string scenario = kSource + "/configs/scenarios/3s-hover-healthy.json";
    const auto r = run("score " + q(kSource + "/configs/scenarios") + " " + q(scenario));
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("a scenario \"" + scenario + "\" names the same file as a scenario"));
}

TEST_CASE("a spreadsheet's ';' CSV is named as such; a column name's raw bytes are escaped", "[cli]") {
    const std::string dir = clitest::temp_dir();
    clitest::write_file(dir + "/semi.csv", "time_s;voltage_v;current_a\n0;16,5;1\n");
    auto r = run("replay " + q(dir + "/semi.csv") + " -c " + q(kConfig));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("columns found: time_s;voltage_v;current_a (one column: the header is separated by ';'"));
    clitest::write_file(dir + "/latin1.csv", "time_s,volt\xe9,current_a\n0,16.5,1\n");
    r = run("replay " + q(dir + "/latin1.csv") + " -c " + q(kConfig));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("columns found: time_s, \"volt\\xE9\", current_a"));
    // A missing config, manifest or scenario says it is missing.
    r = run("replay " + q(kExample) + " -c " + q(dir + "/absent.json"));
    CHECK_THAT(r.err, Catch::Contains(dir + "/absent.json: cannot open config file: no such file"));
}

TEST_CASE("a time or current unit of the other quantity is refused, as a manifest's is", "[cli]") {
    // replay, fit and the other one-log commands had read "--current-unit us" as 1e-6 A and
    // "--time-unit A" as seconds, exit 0: a pipeline's typo gave quietly wrong numbers.
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/f.csv";
    std::string text = "t,v,i\n";
    for (int k = 0; k < 400; ++k)
        text += std::to_string(k * 100) + ",16.5," + std::to_string(k < 100 ? 200 : 15000) + "\n";
    clitest::write_file(log, text);
    const std::string cols = " --time-col t --voltage-col v --current-col i";
    struct Case {
        std::string units, says;
    };
    const Case cases[] = {
        {"--time-unit ms --current-unit us", "--current-unit: unknown current unit \"us\"; expected A or mA"},
        {"--time-unit ms --current-unit s", "--current-unit: unknown current unit \"s\"; expected A or mA"},
        {"--time-unit A --current-unit mA", "--time-unit: unknown time unit \"A\"; expected s, ms or us"},
        {"--time-unit mA --current-unit mA", "--time-unit: unknown time unit \"mA\"; expected s, ms or us"},
    };
    for (const char* command : {"replay", "fit"}) {
        for (const Case& c : cases) {
            INFO(command << " " << c.units);
            const auto r = run(std::string(command) + " " + q(log) + cols + " " + c.units + " --json");
            CHECK(r.exit_code == 2);
            CHECK_THAT(r.err, Catch::Contains(c.says));
            // --json: standard output holds the reason as JSON, and no summary.
            const nlohmann::json e = nlohmann::json::parse(r.out);
            CHECK(e["schema"] == "battsim.error");
            CHECK_THAT(e["message"].get<std::string>(), Catch::Contains(c.says));
        }
    }
    // The units of each quantity still read as they did.
    const auto ok = clitest::run_json("replay " + q(log) + cols + " --time-unit ms --current-unit mA --json");
    CHECK(ok["duration_s"] == 39.9);
}

TEST_CASE("the one-log commands refuse a bad reading option as batch does, named by the command", "[cli]") {
    // replay, fit and the others had read these options with their own copy of batch's
    // parsing, its messages prefixed "battsim: " and untested.
    struct Case {
        std::string option, says;
    };
    const Case cases[] = {
        {"--estimator nonesuch", "--estimator: unknown estimator \"nonesuch\"; expected reference or joint"},
        {"--current-source amps", "--current-source: unknown current source \"amps\"; expected auto, current or shunt"},
        {"--format nonesuch", "unknown log format \"nonesuch\"; expected one of auto, raw, csv, dataflash-text, dataflash-bin, ulog"},
    };
    for (const Case& c : cases) {
        for (const char* command : {"replay", "fit", "discharge"}) {
            INFO(command << " " << c.option);
            const auto r = run(std::string(command) + " " + q(kExample) + " " + c.option);
            CHECK(r.exit_code == 2);
            CHECK_THAT(r.err, Catch::StartsWith(std::string("battsim ") + command + ": " + c.says));
            CHECK(r.out.empty());
        }
        // batch spells the log's format --log-format; its message is the same.
        const std::string option = c.option.rfind("--format", 0) == 0 ? "--log-format nonesuch" : c.option;
        const auto b = run("batch " + q(kExample) + " " + option);
        INFO("batch " << option);
        CHECK(b.exit_code == 2);
        CHECK_THAT(b.err, Catch::StartsWith("battsim batch: " + c.says));
    }
    // Given well, they still choose what they did.
    const auto joint = clitest::run_json("replay " + q(kExample) + " -c " + q(kConfig) + " --estimator joint --json");
    CHECK(joint["estimator"] == "joint");
    const auto reference = clitest::run_json("replay " + q(kExample) + " -c " + q(kConfig) + " --estimator reference --json");
    CHECK(reference["estimator"] == "reference");
}

TEST_CASE("a log whose time never advances is refused, not replayed as a flight of no seconds", "[cli]") {
    // Every row at one time stamp (a frozen logger clock): 3802 samples had read as "0.3 s, no
    // flight", exit 0, with only a note. A few shared stamps are still kept.
    const std::string dir = clitest::temp_dir();
    std::string frozen = "time_s,voltage_v,current_a\n";
    int row = 0;
    for (; row < 40; ++row) frozen += "1000," + std::to_string(16.8 - 0.01 * row) + ",12.5\n";
    clitest::write_file(dir + "/frozen.csv", frozen);
    auto r = run("replay " + q(dir + "/frozen.csv"));
    CHECK(r.exit_code == 3);
    CHECK_THAT(r.err, Catch::Contains("frozen.csv:3: the time does not advance: 39 of 40 rows repeat the time stamp of the row "
                                      "before (the first here): a frozen clock, stamps coarser than the rows"));
    std::string some = "time_s,voltage_v,current_a\n";
    for (row = 0; row < 40; ++row) some += std::to_string(row / 2) + "," + std::to_string(16.8 - 0.01 * row) + ",12.5\n";
    clitest::write_file(dir + "/pairs.csv", some);  // half the rows share a stamp: kept, with a note
    r = run("replay " + q(dir + "/pairs.csv"));
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.err, Catch::Contains("20 rows repeat the time stamp of the row before (first on line 3); kept"));
}
