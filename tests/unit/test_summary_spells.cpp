// The summary's record of when each warning was on (src/host/report/summary.*), on statuses
// made by hand: a verdict that clears and holds again, its causes per spell, the time on,
// and a flickering warning's spells counted past the ones kept.
#include <catch2/catch.hpp>

#include "core/estimate/joint_estimator.h"
#include "host/report/summary.h"

using namespace battsim;
using nlohmann::json;

namespace {

// A status as a flying monitor's, initialised and with a valid sample.
core::MonitorStatus flying_status() {
    core::MonitorStatus s;
    s.initialised = true;
    s.sample_valid = true;
    s.flying = true;
    return s;
}

const json* warning(const json& summary, const char* name) {
    for (const json& w : summary["warnings"])
        if (w["name"] == name) return &w;
    return nullptr;
}

}  // namespace

TEST_CASE("Summary: a short flight that clears and holds again has two spells, each with its causes", "[summary]") {
    host::SummaryAccumulator acc;
    core::MonitorStatus s = flying_status();
    constexpr uint8_t kShort = 1u << core::kWarnShortFlight;
    for (int k = 0; k <= 100; ++k) {  // one sample a second, 0 … 100 s
        s.time_us = 1000000ull * static_cast<uint64_t>(k);
        s.warnings = 0;
        s.short_flight_cause = 0;
        if (k >= 10 && k < 30) {  // resistance first, capacity joining at 20 s
            s.warnings = kShort;
            s.short_flight_cause = core::JointEstimator::kCauseResistance;
            if (k >= 20) s.short_flight_cause |= core::JointEstimator::kCauseCapacity;
        }
        if (k >= 70) {  // again from 70 s to the end, capacity alone
            s.warnings = kShort;
            s.short_flight_cause = core::JointEstimator::kCauseCapacity;
        }
        if (s.warnings) {
            if (!s.warnings_raised) s.warning_time_us[core::kWarnShortFlight] = s.time_us;
            s.warnings_raised |= s.warnings;
        }
        acc.add(s);
    }
    const json j = acc.to_json(4);
    const json* w = warning(j, "short_flight");
    REQUIRE(w != nullptr);
    CHECK((*w)["cause"] == json::array({"resistance"}));  // at the first raise
    CHECK((*w)["spell_count"] == 2);
    REQUIRE((*w)["spells"].size() == 2);
    CHECK((*w)["spells"][0] == json{{"from_s", 10.0}, {"to_s", 30.0}, {"cause", json::array({"capacity", "resistance"})}});
    CHECK((*w)["spells"][1] == json{{"from_s", 70.0}, {"to_s", nullptr}, {"cause", json::array({"capacity"})}});
    CHECK((*w)["active_s"] == 19.0 + 30.0);  // 10 → 29 s, then 70 → 100 s, sample to sample
    CHECK((*w)["active_at_end"] == true);
}

TEST_CASE("Summary: a flickering warning keeps its first 16 spells and counts them all", "[summary]") {
    host::SummaryAccumulator acc;
    core::MonitorStatus s;
    s.initialised = true;
    s.sample_valid = true;
    constexpr uint8_t kFault = 1u << core::kWarnSensorFault;
    for (int k = 0; k < 100; ++k) {  // on at every odd second: 50 spells of 1 s each
        s.time_us = 1000000ull * static_cast<uint64_t>(k);
        s.warnings = (k % 2) ? kFault : 0;
        s.warnings_raised |= s.warnings;
        acc.add(s);
    }
    const json j = acc.to_json(4);
    const json* w = warning(j, "sensor_fault");
    REQUIRE(w != nullptr);
    CHECK((*w)["spell_count"] == 50);
    REQUIRE((*w)["spells"].size() == 16);
    CHECK((*w)["spells"][15] == json{{"from_s", 31.0}, {"to_s", 32.0}});
    CHECK((*w)["active_s"] == 0.0);  // never on for two samples in a row
    CHECK((*w)["active_at_end"] == true);
}

TEST_CASE("Summary: times stamped in Unix time keep their microseconds", "[summary]") {
    // A log stamped in Unix time (1.7e9 s) had its times rounded to 9 significant digits:
    // to 10 s, so a 3.3 s spell read as none and a warning's time up to 5 s off.
    host::SummaryAccumulator acc;
    core::MonitorStatus s = flying_status();
    constexpr uint64_t kEpochUs = 1700000000000000ull;
    constexpr uint8_t kShort = 1u << core::kWarnShortFlight;
    for (int k = 0; k <= 600; ++k) {  // every 0.1 s plus 1 µs: 0 … 60 s
        s.time_us = kEpochUs + 100001ull * static_cast<uint64_t>(k);
        s.warnings = (k >= 100 && k < 133) ? kShort : 0;  // on from 10.0001 s, off at 13.300133 s
        if (s.warnings && !(s.warnings_raised & kShort)) s.warning_time_us[core::kWarnShortFlight] = s.time_us;
        s.warnings_raised |= s.warnings;
        acc.add(s);
    }
    const json j = acc.to_json(4);
    const json* w = warning(j, "short_flight");
    REQUIRE(w != nullptr);
    CHECK((*w)["first_time_s"].get<double>() == 1700000010.0001);
    REQUIRE((*w)["spells"].size() == 1);
    CHECK((*w)["spells"][0]["from_s"].get<double>() == 1700000010.0001);
    CHECK((*w)["spells"][0]["to_s"].get<double>() == 1700000013.300133);  // the first sample off
    CHECK(j["flight"]["start_s"].get<double>() == 1700000000.0);
    CHECK(j["flight"]["end_s"].get<double>() == 1700000060.0006);
    CHECK(j["flight"]["duration_s"].get<double>() == Approx(60.0006).margin(1e-6));
    // Below 1000 s the stamps print as before (9 significant digits were the microsecond).
    CHECK(host::time_s_of_us(141558000ull) == 141.558);
    CHECK(host::round_time_s(141.55800000000002) == 141.558);
}

TEST_CASE("fixed_text rounds a half of the printed decimal away from zero; round_sig prints its decimal", "[summary]") {
    using battsim::host::fixed_text;
    using battsim::host::round_sig;
    // 1.3175 is 1.31749999... as a double: it had printed as 1.317 beside 1.7515 as 1.752.
    CHECK(fixed_text(nlohmann::json(1.3175), 3) == "1.318");
    CHECK(fixed_text(nlohmann::json(1.7515), 3) == "1.752");
    CHECK(fixed_text(nlohmann::json(-0.2145), 3) == "-0.215");
    CHECK(fixed_text(nlohmann::json(55.9355), 3) == "55.936");
    CHECK(fixed_text(nlohmann::json(1.31749), 3) == "1.317");
    CHECK(fixed_text(nlohmann::json(-0.0001), 3) == "0.000");
    CHECK(fixed_text(nlohmann::json(nullptr), 3) == "–");
    // round_sig's value prints as the rounded decimal (6.799999999999999e-23 had printed for 6.8e-23).
    CHECK(nlohmann::json(round_sig(6.8e-23, 3)).dump() == "6.8e-23");
    CHECK(round_sig(2.6e-22 / 3.0, 3) == 8.67e-23);
    CHECK(round_sig(123456.7, 6) == 123457.0);
}
