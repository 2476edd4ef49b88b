// Golden replays ("change indication"): the shared dissertation flights through the
// monitor must give the committed summaries. A change here is either a bug or an
// intended change of the numbers, regenerated with scripts/update-goldens.sh.
#include <catch2/catch.hpp>

#include <fstream>

#include "host/replay.h"
#include "host/report/json_compare.h"

using namespace battsim::host;

TEST_CASE("Golden summaries of the predictive-bms flights", "[golden][data]") {
    const std::string data = BATTSIM_DATA_DIR;
    for (const char* set : {"modified", "original"}) {
        ReplayOptions opt;
        opt.config = load_config_file(std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-" + set + ".json");
        for (const char* flight : {"29", "30", "32", "34"}) {
            const std::string golden_path =
                std::string(BATTSIM_SOURCE_DIR) + "/tests/golden/predictive-bms-" + set + "/" + flight + ".json";
            std::ifstream in(golden_path);
            REQUIRE(in.good());
            const nlohmann::json golden = nlohmann::json::parse(in);
            const nlohmann::json actual =
                replay_log(data + "/predictive-bms/flights/" + flight + ".csv", opt);
            CompareOptions co;
            co.relative_tolerance = 1e-5;  // 6-significant-digit rounding may flip a last digit
            co.ignore = {"/input/path", "/battsim_version"};
            const auto diffs = compare_json(golden, actual, co);
            std::string report;
            for (const auto& d : diffs) report += "  " + d.path + ": golden " + d.expected + ", now " + d.actual + "\n";
            INFO(set << " flight " << flight << " changed:\n" << report);
            CHECK(diffs.empty());
        }
    }
}

TEST_CASE("Replay is deterministic", "[golden][data]") {
    const std::string log = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/34.csv";
    ReplayOptions opt;
    opt.config = default_config();
    CHECK(replay_log(log, opt).dump() == replay_log(log, opt).dump());
}

TEST_CASE("json_compare reports changed, missing and extra fields", "[golden]") {
    using nlohmann::json;
    json a = {{"x", 1.0}, {"o", {{"y", "s"}, {"z", json::array({1, 2})}}}};
    json b = a;
    CHECK(compare_json(a, b, {}).empty());
    b["x"] = 1.0 + 1e-9;
    CHECK(compare_json(a, b, {}).empty());
    b["x"] = 1.01;
    b["o"]["z"][1] = 3;
    b["extra"] = true;
    b["o"].erase("y");
    auto d = compare_json(a, b, {});
    REQUIRE(d.size() == 4);
    CompareOptions ig;
    ig.ignore = {"/x", "/extra", "/o/y", "/o/z"};
    CHECK(compare_json(a, b, ig).empty());
}
