// A failed run asked for --json writes its reason to standard output as JSON (schema
// battsim.error), as well as the same text to standard error; without --json, or with output
// already written, standard output is left as it was.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <string>

#include "cli_util.h"

using clitest::q;
using clitest::run;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;

nlohmann::json error_object(const clitest::Result& r) {
    INFO(r.out);
    INFO(r.err);
    REQUIRE_FALSE(r.out.empty());
    const nlohmann::json j = nlohmann::json::parse(r.out);
    CHECK(j["schema"] == "battsim.error");
    CHECK(j["schema_version"] == 1);
    CHECK(j["exit_code"] == r.exit_code);
    // Standard error still says it, line for line (a byte that is not UTF-8 is U+FFFD here).
    for (const auto& line : j["stderr"])
        if (line.get<std::string>().find("\xef\xbf\xbd") == std::string::npos) CHECK(r.err.find(line.get<std::string>()) != std::string::npos);
    return j;
}
}  // namespace

TEST_CASE("--json: a missing or malformed log, a bad config and a bad option each answer in JSON", "[cli][json]") {
    const std::string dir = clitest::temp_dir();
    const auto missing = run("replay " + q(dir + "/nope.csv") + " --json");
    CHECK(missing.exit_code == 3);
    const auto m = error_object(missing);
    CHECK(m["command"] == "replay");
    CHECK_THAT(m["message"].get<std::string>(), Catch::Contains("nope.csv") && Catch::Contains("cannot open"));

    clitest::write_file(dir + "/bad.csv", "time_s,voltage_v,current_a\n0,16.8,1\n1,abc,1\n");
    const auto bad = run("replay " + q(dir + "/bad.csv") + " --json");
    CHECK(bad.exit_code == 3);
    CHECK_THAT(error_object(bad)["message"].get<std::string>(), Catch::Contains("bad.csv:3:2") && Catch::Contains("abc"));

    clitest::write_file(dir + "/cfg.json", "{\"schema\": \"battsim.config\", \"version\": 1, \"battery\": {\"cells\": \"four\"}}");
    const auto config = run("replay " + q(kSource + "/logs/example-4s.csv") + " -c " + q(dir + "/cfg.json") + " --json");
    CHECK(config.exit_code == 4);
    CHECK_THAT(error_object(config)["message"].get<std::string>(), Catch::Contains("cfg.json"));

    // A usage error: the reason, not the help hint printed after it.
    const auto usage = run("score --json --copies 0");
    CHECK(usage.exit_code == 2);
    const auto u = error_object(usage);
    CHECK(u["command"] == "score");
    CHECK_THAT(u["message"].get<std::string>(), Catch::Contains("--copies"));
    CHECK(u["stderr"].size() == 2);
}

TEST_CASE("--json: success, failure without --json, and a word after -- leave standard output as before", "[cli][json]") {
    const std::string dir = clitest::temp_dir();
    const auto plain = run("replay " + q(dir + "/nope.csv"));
    CHECK(plain.exit_code == 3);
    CHECK(plain.out.empty());
    const auto after = run("replay -- --json");
    CHECK(after.exit_code == 3);  // a log named "--json"
    CHECK(after.out.empty());
    const auto ok = clitest::run_json("replay " + q(kSource + "/logs/example-4s.csv") + " -c " + q(kSource + "/configs/sim-4s.json") +
                                      " --json");
    CHECK(ok["schema"] == "battsim.summary");
}

TEST_CASE("batch --format json: a manifest that cannot be read answers in JSON; a bad row keeps its table", "[cli][json][batch]") {
    const std::string dir = clitest::temp_dir();
    const auto missing = run("batch -m " + q(dir + "/none.csv") + " --format json");
    CHECK(missing.exit_code != 0);
    CHECK(error_object(missing)["command"] == "batch");
    // A row that fails is the table's business (exit 1): the table is what standard output holds.
    clitest::write_file(dir + "/fleet.csv", "path\n" + dir + "/absent.csv\n" + kSource + "/logs/example-4s.csv\n");
    const auto rows = run("batch -m " + q(dir + "/fleet.csv") + " -c " + q(kSource + "/configs/sim-4s.json") + " --format json");
    CHECK(rows.exit_code == 1);
    const nlohmann::json t = nlohmann::json::parse(rows.out);
    CHECK(t.contains("rows"));
    CHECK_FALSE(t.value("schema", std::string()) == "battsim.error");
}

TEST_CASE("--json: a file name that is not UTF-8, calibrate's nothing-to-read and a full disk each give their object",
          "[cli][json][data]") {
    const std::string dir = clitest::temp_dir();
    // A helper's walkthrough: the object's printing had thrown on the byte, exit 134.
    const auto latin1 = run("replay " + q(dir + "/caf\xe9.csv") + " --json");
    CHECK(latin1.exit_code == 3);
    CHECK_THAT(error_object(latin1)["message"].get<std::string>(), Catch::Contains("caf\xef\xbf\xbd.csv"));
    // calibrate's exit 1 writes nothing: the reason comes as the object.
    const std::string flights = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/";
    const auto none = run("calibrate " + q(flights + "29.csv") + " " + q(flights + "30.csv") + " --json");
    CHECK(none.exit_code == 1);
    CHECK_THAT(error_object(none)["message"].get<std::string>(), Catch::Contains("no OCV table"));
    // batch's table to a full disk: the write is the reason, not the tally or compare's lines.
    const auto full = run("batch " + q(flights + "30.csv") + " " + q(flights + "32.csv") + " --format json -o /dev/full");
    CHECK(full.exit_code == 5);
    const auto f = error_object(full);
    CHECK(f["command"] == "batch");
    CHECK_THAT(f["message"].get<std::string>(), Catch::Contains("/dev/full") && Catch::Contains("write failed"));
}
