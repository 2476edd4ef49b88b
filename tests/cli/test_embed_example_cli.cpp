// docs/embedding.md's example (tests/embed/embed_example.cpp: the core alone, fed one
// Sample per reading by its own reader, configured by an exported header) against `battsim
// replay` of the same log and config: the same numbers in every row, the same warnings at
// the same times. Keeps the page's example and its claims from going stale.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"

using clitest::q;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;
const std::string kExample = BATTSIM_EMBED_EXAMPLE_BINARY;
const std::string kConfig = BATTSIM_EMBED_EXAMPLE_CONFIG;  // the JSON its header was exported from

std::vector<std::string> split(const std::string& text, char sep) {
    std::vector<std::string> out;
    std::string field;
    std::istringstream in(text);
    while (std::getline(in, field, sep)) out.push_back(field);
    if (!text.empty() && text.back() == sep) out.push_back("");  // a trailing empty field
    return out;
}

// Every column the example prints equals the series column of that name, row for row, as
// text (both write it with the same format: the same float, or both empty).
void require_same_columns(const std::string& series_csv, const std::string& example_csv) {
    const std::vector<std::string> series = split(series_csv, '\n');
    const std::vector<std::string> example = split(example_csv, '\n');
    REQUIRE(series.size() > 100);
    REQUIRE(example.size() == series.size());
    const std::vector<std::string> series_names = split(series[0], ',');
    const std::vector<std::string> example_names = split(example[0], ',');
    REQUIRE(example_names.size() == 9);
    std::vector<size_t> column;  // the series column of each example column
    for (const std::string& name : example_names) {
        size_t k = 0;
        while (k < series_names.size() && series_names[k] != name) ++k;
        INFO(name);
        REQUIRE(k < series_names.size());
        column.push_back(k);
    }
    size_t compared = 0;
    for (size_t row = 1; row < series.size(); ++row) {
        if (series[row].empty() && example[row].empty()) continue;
        const std::vector<std::string> s = split(series[row], ',');
        const std::vector<std::string> e = split(example[row], ',');
        REQUIRE(e.size() == example_names.size());
        for (size_t c = 0; c < e.size(); ++c) {
            if (e[c] == s[column[c]]) continue;
            INFO("row " << row << ", column " << example_names[c]);
            REQUIRE(e[c] == s[column[c]]);
        }
        ++compared;
    }
    CHECK(compared + 2 >= series.size());
}

std::string fixed3(double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f", x);
    return buf;
}

// The example's event lines on standard error against the summary's warnings: one
// "warning NAME raised at T s" per spell (the summary lists up to 16 of them, and counts all),
// the weak cell named as replay names it.
void require_same_warnings(const nlohmann::json& summary, const std::string& events) {
    for (const nlohmann::json& w : summary["warnings"]) {
        const std::string prefix = "warning " + w["name"].get<std::string>() + " raised at ";
        size_t lines = 0;
        for (size_t at = events.find(prefix); at != std::string::npos; at = events.find(prefix, at + 1)) ++lines;
        INFO(events);
        CHECK(lines == w["spell_count"].get<size_t>());
        for (const nlohmann::json& spell : w["spells"]) {
            std::string line = prefix + fixed3(spell["from_s"].get<double>()) + " s";
            if (w.contains("cell")) {
                line += " (cell " + std::to_string(w["cell"].get<int>()) + ", " +
                        (w["finding"] == "low_capacity" ? "low capacity" : "high resistance") + ")";
            }
            CHECK(events.find(line) != std::string::npos);
        }
    }
}

struct Runs {
    nlohmann::json summary;
    std::string series;
    clitest::Result example;
};

Runs run_both(const std::string& dir, const std::string& log) {
    Runs r;
    const clitest::Result replay = clitest::run("replay " + q(log) + " -c " + q(kConfig) +
                                                " --estimator joint --json --series " + q(dir + "/series.csv"));
    INFO(replay.err);
    REQUIRE(replay.exit_code == 0);
    r.summary = nlohmann::json::parse(replay.out);
    r.series = clitest::read_file(dir + "/series.csv");
    r.example = testsupport::run_program(kExample, q(log));
    INFO(r.example.err);
    REQUIRE(r.example.exit_code == 0);
    return r;
}
}  // namespace

TEST_CASE("the embedding example gives replay's numbers on the bundled flight, and its capacity at the landing",
          "[cli][embed]") {
    const std::string dir = clitest::temp_dir();
    const Runs r = run_both(dir, kSource + "/logs/example-4s.csv");
    require_same_columns(r.series, r.example.out);
    REQUIRE(r.summary["warnings"].empty());
    CHECK(r.example.err.find("warning") == std::string::npos);
    // What the README's quick start prints: 1.461 +/- 0.079 Ah at the landing.
    const nlohmann::json& cap = r.summary["flight"]["capacity_ah"];
    const std::string landed = "capacity " + fixed3(cap["final"].get<double>()) + " +/- " +
                               fixed3(cap["final_sigma"].get<double>()) + " Ah";
    INFO(r.example.err);
    CHECK(r.example.err.find("landed at ") != std::string::npos);
    CHECK(r.example.err.find(landed) != std::string::npos);
}

TEST_CASE("the embedding example warns as replay does: a weak cell named, a short flight, a loose balance lead",
          "[cli][embed]") {
    const std::string dir = clitest::temp_dir();
    struct Case {
        const char* scenario;
        const char* warning;  // one that must be among replay's
    };
    const Case cases[] = {{"4s-racing-weak-cell3-capacity-70", "cell_outlier"},
                          {"4s-racing-fault-loose-lead", "sensor_fault"}};
    for (const Case& c : cases) {
        INFO(c.scenario);
        const std::string log = dir + "/" + c.scenario + ".csv";
        const clitest::Result sim =
            clitest::run("simulate " + q(kSource + "/configs/scenarios/" + c.scenario + ".json") + " -o " + q(log));
        INFO(sim.err);
        REQUIRE(sim.exit_code == 0);
        const Runs r = run_both(dir, log);
        require_same_columns(r.series, r.example.out);
        bool found = false;
        for (const nlohmann::json& w : r.summary["warnings"]) found = found || w["name"] == c.warning;
        REQUIRE(found);
        require_same_warnings(r.summary, r.example.err);
    }
}
