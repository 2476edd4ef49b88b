// `battsim make-config --list-keys`: the config reference docs/config-keys.md is its output,
// byte for byte (regenerate: build/battsim make-config --list-keys -o docs/config-keys.md).
#include <string>

#include "cli_util.h"

using nlohmann::json;

TEST_CASE("make-config --list-keys prints docs/config-keys.md, and --json the same keys", "[cli][keys]") {
    const clitest::Result md = clitest::run("make-config --list-keys");
    INFO(md.err);
    REQUIRE(md.exit_code == 0);
    CHECK(md.out == clitest::read_file(std::string(BATTSIM_SOURCE_DIR) + "/docs/config-keys.md"));
    const json j = clitest::run_json("make-config --list-keys --json");
    REQUIRE(j["keys"].is_array());
    CHECK(j["schema"] == "battsim.config_keys");
    CHECK(j["schema_version"] == 1);
    CHECK(j["config_schema"] == "battsim.config");
    // A key's default is what the reader sets when a file leaves it out.
    for (const json& k : j["keys"])
        if (k["key"] == "sensor.min_pack_voltage_v") CHECK(k["default"].get<double>() == Approx(8.0));
    size_t rows = 0;
    for (size_t at = md.out.find("\n| `"); at != std::string::npos; at = md.out.find("\n| `", at + 1)) ++rows;
    CHECK(rows == j["keys"].size());
    CHECK(j["keys"].size() > 150);
    for (const json& k : j["keys"]) {
        INFO(k.dump());
        CHECK(!k["about"].get<std::string>().empty());
        if (k["type"] == "number" || k["type"] == "integer") CHECK(k["range"].size() == 2);
    }
}

TEST_CASE("make-config --list-keys takes no pack options, and --json needs it", "[cli][keys]") {
    const clitest::Result both = clitest::run("make-config --list-keys --cells 4");
    CHECK(both.exit_code == 2);
    CHECK(both.err.find("--list-keys") != std::string::npos);
    const clitest::Result alone = clitest::run("make-config --cells 4 --capacity-mah 1500 --json");
    CHECK(alone.exit_code == 2);
    CHECK(alone.err.find("--json goes with --list-keys") != std::string::npos);
}

TEST_CASE("bench --json carries the schema fields every report carries", "[cli]") {
    const std::string example = clitest::q(std::string(BATTSIM_SOURCE_DIR) + "/logs/example-4s.csv");
    const json m = clitest::run_json("bench monitor " + example + " --json --passes 1 --min-time 0");
    CHECK(m["schema"] == "battsim.bench");
    CHECK(m["benchmark"] == "monitor");
    CHECK(m.contains("battsim_version"));
    CHECK(m["samples_per_pass"].get<int>() == 3913);
    // Timings vary run to run, so their rounding is not checked here (round_sig, unit-tested);
    // the sample count is exact.
    const json b = clitest::run_json("bench batch " + example + " --json --min-time 0 --min-runs 1 -j 1");
    CHECK(b["benchmark"] == "batch");
}
