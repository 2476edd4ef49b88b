// The current sensor against the charger's count, on hand-made summaries.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "host/report/brief.h"
#include "host/report/charger_check.h"

using battsim::host::charger_check;
using battsim::host::ChargerCheckOptions;
using nlohmann::json;

namespace {
json summary(double consumed_ah, double initial_mah, json warnings = json::array()) {
    return json{{"consumed", {{"ah", consumed_ah}, {"wh", 0.0}}},
                {"initial_state", {{"consumed_mah", initial_mah}}},
                {"warnings", warnings}};
}
}  // namespace

TEST_CASE("Charger check: the count over the charger's, the suggested gain, the bar", "[report][charger]") {
    ChargerCheckOptions o;
    o.charged_ah = 1.0;
    // 1.1 Ah counted from a start 10 mAh short of full: 1.09 Ah over the log, 9 % high.
    json c = charger_check(summary(1.1, 10.0), o);
    CHECK(c["counted_ah"].get<double>() == Approx(1.09));
    CHECK(c["ratio"].get<double>() == Approx(1.09));
    CHECK(c["fault"] == true);
    CHECK(c["suggested_current_gain"].get<double>() == Approx(1.0 / 1.09).epsilon(1e-5));
    CHECK(c["notes"].empty());
    // A config already correcting by 0.95: the suggestion multiplies it.
    o.current_gain = 0.95;
    c = charger_check(summary(1.1, 10.0), o);
    CHECK(c["suggested_current_gain"].get<double>() == Approx(0.95 / 1.09).epsilon(1e-5));
    // 2 % off is within the default 3 %; not within 1 %.
    o.current_gain = 1.0;
    CHECK(charger_check(summary(1.02, 0.0), o)["fault"] == false);
    o.tolerance = 0.01;
    CHECK(charger_check(summary(1.02, 0.0), o)["fault"] == true);
}

TEST_CASE("Charger check: notes on a pack not full at the start and on an in-flight sensor fault; bad input", "[report][charger]") {
    ChargerCheckOptions o;
    o.charged_ah = 1.0;
    // 100 mAh missing at the start (over 5 % of the charge put back): no verdict.
    json c = charger_check(summary(1.2, 100.0, json::array({json{{"name", "sensor_fault"}}})), o);
    REQUIRE(c["notes"].size() == 2);
    CHECK(c["notes"][0].get<std::string>().find("100 mAh missing at the start") != std::string::npos);
    CHECK(c["notes"][1].get<std::string>().find("offset") != std::string::npos);
    CHECK(c["ratio"].get<double>() == Approx(1.1));
    CHECK(c["fault"].is_null());
    CHECK(c["suggested_current_gain"].is_null());
    // Full at the start but a sensor fault in flight: the verdict stands, no gain suggested.
    c = charger_check(summary(1.2, 10.0, json::array({json{{"name", "sensor_fault"}}})), o);
    CHECK(c["fault"] == true);
    CHECK(c["suggested_current_gain"].is_null());
    // 50 mAh of 1 Ah is on the bar: still judged.
    CHECK(charger_check(summary(1.05, 50.0), o)["fault"] == false);
    o.charged_ah = 0.0;
    CHECK_THROWS_AS(charger_check(summary(1.0, 0.0), o), std::invalid_argument);
    o.charged_ah = 1.0;
    CHECK_THROWS_WITH(charger_check(summary(0.01, 10.0), o), Catch::Contains("no charge drawn"));
    o.tolerance = -1;
    CHECK_THROWS_AS(charger_check(summary(1.0, 0.0), o), std::invalid_argument);
    // A log without a valid sample: the summary's consumed and initial state are null.
    o.tolerance = 0.03;
    const json empty = {{"consumed", nullptr}, {"initial_state", nullptr}, {"warnings", json::array()}};
    CHECK_THROWS_WITH(charger_check(empty, o), Catch::Contains("no valid sample"));
    // No initial state read (the monitor never settled one): nothing is taken off.
    const json unsettled = {{"consumed", {{"ah", 1.0}}}, {"initial_state", nullptr}, {"warnings", json::array()}};
    CHECK(charger_check(unsettled, o)["counted_ah"].get<double>() == Approx(1.0));
}

TEST_CASE("Charger check: a gap between samples on the ground holds no gain back; one in flight and an offset do", "[report][charger]") {
    ChargerCheckOptions o;
    o.charged_ah = 1.0;
    const auto fault = [](const char* cause, json flight_time_s) {
        return json::array({json{{"name", "sensor_fault"}, {"cause", json::array({cause})}, {"flight_time_s", flight_time_s}}});
    };
    // log171.bin's one 2.1 s gap before the take-off had been reported as "raised in flight".
    json c = charger_check(summary(1.1, 10.0, fault("sample_gap", nullptr)), o);
    CHECK(c["suggested_current_gain"].get<double>() == Approx(1.0 / 1.09).epsilon(1e-5));
    CHECK(c["notes"].empty());
    c = charger_check(summary(1.1, 10.0, fault("sample_gap", 12.5)), o);
    CHECK(c["suggested_current_gain"].is_null());
    REQUIRE(c["notes"].size() == 1);
    CHECK(c["notes"][0].get<std::string>().rfind("a sensor fault was raised (sample_gap;", 0) == 0);
    c = charger_check(summary(1.1, 10.0, fault("current_offset", nullptr)), o);
    CHECK(c["suggested_current_gain"].is_null());
    CHECK(c["notes"][0].get<std::string>().rfind("a sensor fault was raised (current_offset;", 0) == 0);
    // The start's deficit is judged against the charger's count, and the note says so.
    c = charger_check(summary(1.2, 100.0), o);
    CHECK(c["notes"][0].get<std::string>().find("100 mAh missing at the start, over 5 % of the charger's 1000 mAh") !=
          std::string::npos);
}

TEST_CASE("The charger check's line for people says the verdict and the gain", "[charger]") {
    nlohmann::json c = {{"counted_ah", 1.4}, {"charged_ah", 1.5}, {"ratio", 0.9333333}, {"fault", true},
                        {"suggested_current_gain", 1.0714286}};
    std::ostringstream fault;
    battsim::host::print_charger_check(c, fault);
    CHECK(fault.str() == "  charger check: counted 1.400 Ah against 1.500 Ah charged (x0.9333): current sensor fault; "
                         "suggested extensions.current_sensor.gain 1.0714\n");
    c["fault"] = false;
    std::ostringstream fine;
    battsim::host::print_charger_check(c, fine);
    CHECK(fine.str() == "  charger check: counted 1.400 Ah against 1.500 Ah charged (x0.9333): within tolerance; "
                        "no change needed (the gain it implies: 1.0714)\n");
    c["fault"] = nullptr;
    c["suggested_current_gain"] = nullptr;
    std::ostringstream none;
    battsim::host::print_charger_check(c, none);
    CHECK(none.str() == "  charger check: counted 1.400 Ah against 1.500 Ah charged (x0.9333): no verdict\n");
}

TEST_CASE("brief: a battery state that began on the landing sample says so", "[brief]") {
    // Flight 29's summary (the committed joint golden) with LOW put on its landing sample:
    // "145.1 s into the flight" of a 145.1 s flight had read as a state flown in.
    std::ifstream in(std::string(BATTSIM_SOURCE_DIR) + "/tests/golden/predictive-bms-joint/29.json");
    REQUIRE(in.good());
    json s = json::parse(in);
    s["flight"]["remaining_time_s"]["low_from_s"] = s["flight"]["end_s"];
    s["flight"]["remaining_time_s"]["low_spells"] = 1;
    std::ostringstream out;
    battsim::host::print_brief(s, out);
    const double end_s = s["flight"]["end_s"].get<double>();
    char expected[64];
    std::snprintf(expected, sizeof expected, "LOW from %.1f s (at the landing)", end_s);
    CHECK_THAT(out.str(), Catch::Contains(expected));
    // One sample earlier it is a state flown in.
    s["flight"]["remaining_time_s"]["low_from_s"] = end_s - 0.5;
    std::ostringstream before;
    battsim::host::print_brief(s, before);
    CHECK_THAT(before.str(), Catch::Contains("s into the flight)") && !Catch::Contains("(at the landing)"));
}
