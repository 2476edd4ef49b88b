// `battsim simulate` and `battsim score` from the outside: files written, exit codes,
// messages, and a simulated log that `battsim replay` takes.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "../cli/cli_util.h"

using clitest::q;
using clitest::run;

namespace {

struct Dir {
    std::string path = clitest::temp_dir();
    std::string at(const std::string& name) const { return path + "/" + name; }
};

std::string scenario_json(const std::string& name, int seed, const std::string& extra = "") {
    return R"({"schema": "battsim.scenario", "version": 1, "name": ")" + name + R"(", "seed": )" + std::to_string(seed) +
           R"(, "monitor_config": ")" + std::string(BATTSIM_SOURCE_DIR) + R"(/configs/reference-modified.json",
  "profile": {"kind": "racing", "idle_before_s": 15, "armed_s": 2, "flight_s": 50, "idle_after_s": 5, "mean_power_w": 450})" +
           extra + "}";
}

}  // namespace

TEST_CASE("battsim simulate writes a log and its truth; replay reads the log", "[cli][sim]") {
    Dir d;
    clitest::write_file(d.at("a.json"), scenario_json("a", 1));
    const auto r = run("simulate " + q(d.at("a.json")) + " -o " + q(d.at("a.csv")));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.find("a: ") == 0);
    const nlohmann::json truth = nlohmann::json::parse(clitest::read_file(d.at("a.truth.json")));
    CHECK(truth["schema"] == "battsim.truth");
    CHECK(truth["flight"]["total_flight_time_s"].get<double>() > 50.0);
    CHECK(truth["series"]["time_s"].size() == truth["series"]["remaining_flight_time_s"].size());
    const std::string log = clitest::read_file(d.at("a.csv"));
    CHECK(log.size() > 30000);
    // Same scenario, same seed: byte-identical log.
    REQUIRE(run("simulate " + q(d.at("a.json")) + " -o " + q(d.at("b.csv")) + " --truth " + q(d.at("b.json"))).exit_code == 0);
    CHECK(clitest::read_file(d.at("b.csv")) == log);
    // A different seed from the command line changes it.
    REQUIRE(run("simulate " + q(d.at("a.json")) + " --seed 99 -o " + q(d.at("c.csv"))).exit_code == 0);
    CHECK(clitest::read_file(d.at("c.csv")) != log);

    const nlohmann::json summary = clitest::run_json("replay " + q(d.at("a.csv")) + " -c " + q(std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json") + " --json");
    CHECK(summary["input"]["format"] == "raw");
    CHECK_FALSE(summary["flight"].is_null());
}

TEST_CASE("battsim simulate: usage and scenario errors", "[cli][sim]") {
    Dir d;
    clitest::write_file(d.at("a.json"), scenario_json("a", 1));
    clitest::write_file(d.at("b.json"), scenario_json("b", 2, R"(, "pack": {"capacity_factor": 0.8})"));
    CHECK(run("simulate " + q(d.at("a.json"))).exit_code == 2);  // neither -o nor --out-dir
    CHECK(run("simulate " + q(d.path) + " -o " + q(d.at("x.csv"))).exit_code == 2);  // two scenarios, one file
    const auto xml = run("simulate " + q(d.at("a.json")) + " -o " + q(d.at("x.csv")) + " --format xml");
    CHECK(xml.exit_code == 2);
    CHECK(xml.err == "battsim simulate: --format: " + d.at("a.json") +
                         ": expected \"auto\", \"raw\", \"csv\", \"edgetx\", \"dataflash\" or \"ulog\", found \"xml\"\n");
    const auto missing = run("simulate " + q(d.at("none.json")) + " -o " + q(d.at("x.csv")));
    CHECK(missing.exit_code == 4);
    CHECK(missing.err.find(d.at("none.json") + ": no such scenario file or directory") != std::string::npos);
    clitest::write_file(d.at("bad.txt"), R"({"schema": "battsim.scenario", "version": 1, "name": "bad", "monitor_config": "x.json", "sede": 3})");
    const auto bad = run("simulate " + q(d.at("bad.txt")) + " -o " + q(d.at("x.csv")));
    CHECK(bad.exit_code == 4);
    CHECK(bad.err.find(d.at("bad.txt") + ":1:89: $.sede: unknown key") != std::string::npos);
    const auto unwritable = run("simulate " + q(d.at("a.json")) + " -o " + q(d.at("no/such/dir/x.csv")));
    CHECK(unwritable.exit_code == 5);

    Dir out;
    const auto all = run("simulate " + q(d.at("a.json")) + " " + q(d.at("b.json")) + " --out-dir " + q(out.path));
    INFO(all.err);
    REQUIRE(all.exit_code == 0);
    for (const char* f : {"a.csv", "a.truth.json", "b.csv", "b.truth.json"}) CHECK_FALSE(clitest::read_file(out.at(f)).empty());
}

TEST_CASE("battsim simulate --format dataflash|ulog writes an autopilot's log that replay and score --logs read", "[cli][sim]") {
    Dir d, out;
    clitest::write_file(d.at("a.json"), scenario_json("a", 1));
    for (const char* format : {"dataflash", "ulog"}) {
        const std::string f = format;
        const std::string ext = f == "dataflash" ? ".bin" : ".ulg";
        INFO(f);
        const auto r = run("simulate " + q(d.at("a.json")) + " --format " + f + " --out-dir " + q(out.path));
        INFO(r.err);
        REQUIRE(r.exit_code == 0);
        CHECK(r.out.find("-> " + out.at("a" + ext)) != std::string::npos);
        const nlohmann::json truth = nlohmann::json::parse(clitest::read_file(out.at("a.truth.json")));
        CHECK(truth["log"]["format"] == f);
        const nlohmann::json summary = clitest::run_json("replay " + q(out.at("a" + ext)) + " -c " +
                                                         q(std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json") + " --json");
        CHECK(summary["input"]["format"] == (f == "dataflash" ? "dataflash-bin" : "ulog"));
        CHECK(summary["input"]["cells"] == 4);
        CHECK(summary["input"]["has_temperature"] == true);
        CHECK(summary["input"]["notes"].empty());
        CHECK(summary["samples"]["total"] == truth["log"]["rows"]);
        // score --logs finds NAME.bin / NAME.ulg and flies the same flight as in memory.
        const nlohmann::json from_file = clitest::run_json("score " + q(d.at("a.json")) + " --log-format " + f + " --logs " +
                                                           q(out.path) + " --columns joint --json");
        const nlohmann::json in_memory = clitest::run_json("score " + q(d.at("a.json")) + " --log-format " + f + " --columns joint --json");
        CHECK(from_file["flights"][0]["estimators"] == in_memory["flights"][0]["estimators"]);
        CHECK(from_file["flights"][0]["notes"] == in_memory["flights"][0]["notes"]);  // no "differs from" note
    }
    const auto missing = run("score " + q(d.at("a.json")) + " --log-format ulog --logs " + q(d.path));
    CHECK(missing.exit_code == 3);
    CHECK(missing.err.find(d.at("a.ulg") + ": cannot open file") != std::string::npos);
}

TEST_CASE("battsim score --logs refuses a log its scenario does not simulate now", "[cli][score]") {
    Dir d, out;
    clitest::write_file(d.at("a.json"), scenario_json("a", 1));
    // Another seed's log had been graded against this seed's truth with only a note.
    REQUIRE(run("simulate " + q(d.at("a.json")) + " --seed 777 --out-dir " + q(out.path)).exit_code == 0);
    const auto other = run("score " + q(d.at("a.json")) + " --logs " + q(out.path) + " --columns oracle --json");
    CHECK(other.exit_code == 3);
    // No scoreboard: standard output holds the error object (--json) and nothing else.
    CHECK(nlohmann::json::parse(other.out)["schema"] == "battsim.error");
    CHECK_THAT(other.err, Catch::Contains(out.at("a.csv") + ": not the log scenario a (" + d.at("a.json") +
                                          ") simulates as it is now"));
    CHECK_THAT(other.err, Catch::Contains("re-simulate it"));
    // Re-simulated from the scenario as it is: scored, as in memory.
    REQUIRE(run("simulate " + q(d.at("a.json")) + " --out-dir " + q(out.path)).exit_code == 0);
    const auto same = run("score " + q(d.at("a.json")) + " --logs " + q(out.path) + " --columns oracle --json");
    INFO(same.err);
    CHECK(same.exit_code == 0);
}

TEST_CASE("battsim score prints a table or JSON and checks its arguments", "[cli][score]") {
    Dir d;
    clitest::write_file(d.at("a.json"), scenario_json("a", 1));
    clitest::write_file(d.at("b.json"), scenario_json("b", 2, R"(, "pack": {"capacity_factor": 0.7})"));
    const nlohmann::json j = clitest::run_json("score " + q(d.path) + " --json -j 2");
    CHECK(j["flights"].size() == 2);
    CHECK(j["flights"][0]["name"] == "a");
    CHECK(j["flights"][1]["short_flight"] == true);
    // The diagnostic column runs only when named, and then beside the others.
    CHECK_FALSE(j["flights"][0]["estimators"].contains("solve-truth"));
    const nlohmann::json dj = clitest::run_json("score " + q(d.at("a.json")) + " --json --columns oracle,solve-truth");
    REQUIRE(dj["flights"][0]["estimators"].contains("solve-truth"));
    CHECK(dj["flights"][0]["estimators"]["solve-truth"]["remaining_energy_error_20_pct"].is_number());
    CHECK_FALSE(dj["flights"][0]["estimators"].contains("joint"));
    const auto table = run("score " + q(d.path) + " --columns reference,oracle -o " + q(d.at("score.txt")));
    REQUIRE(table.exit_code == 0);
    const std::string text = clitest::read_file(d.at("score.txt"));
    CHECK(text.find("2 flights") != std::string::npos);
    CHECK(text.find("reference") != std::string::npos);
    CHECK(text.find("baseline") == std::string::npos);
    const nlohmann::json cj = clitest::run_json("score " + q(d.path) + " --columns oracle --copies 2 --json -j 2");
    REQUIRE(cj["flights"].size() == 4);
    CHECK(cj["flights"][2]["name"] == "a@1");
    CHECK(cj["flights"][2]["copy"] == 1);
    CHECK(cj["summary_by_copy"].size() == 2);
    CHECK(cj["summary"]["early_warnings"]["oracle"]["of"] == 2);  // b and b@1 are short
    const auto with_logs = run("score " + q(d.path) + " --copies 2 --logs " + q(d.path));
    CHECK(with_logs.exit_code == 2);
    CHECK(with_logs.err.find("--copies simulates its flights; it cannot read them from a --logs directory") != std::string::npos);
    CHECK(run("score " + q(d.path) + " --copies 0").exit_code == 2);
    const auto cols = run("score " + q(d.path) + " --columns reference,nonesuch");
    CHECK(cols.exit_code == 2);
    CHECK(cols.err.find("unknown estimator \"nonesuch\"") != std::string::npos);
    clitest::write_file(d.at("c.json"), "{\"schema\": \"battsim.scenario\"");
    const auto broken = run("score " + q(d.path));
    CHECK(broken.exit_code == 4);
    CHECK(broken.err.find(d.at("c.json") + ":1:") != std::string::npos);
}
