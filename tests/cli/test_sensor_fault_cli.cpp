// Why a sensor fault was raised, from the outside: the summary's sensor_fault entry names its
// cause and what it measured, the short human summary says it, and the pilot's text too. Each
// simulated fault is checked against the log's own bytes or the simulator's truth, not
// against the summary alone.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "cli_util.h"
#include "mavlink_decode.h"

using clitest::q;
using clitest::run;
using nlohmann::json;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;

struct FaultRun {
    json summary;
    json warning;  // the sensor_fault entry (null: none raised)
    std::string brief;
    std::vector<std::string> texts;  // STATUSTEXT sentences, in order
    std::string log;
};

FaultRun fly(const std::string& dir, const std::string& scenario) {
    FaultRun r;
    r.log = dir + "/" + scenario + ".csv";
    const clitest::Result sim = run("simulate " + q(kSource + "/configs/scenarios/" + scenario + ".json") + " -o " + q(r.log));
    INFO(sim.err);
    REQUIRE(sim.exit_code == 0);
    const std::string args = "replay " + q(r.log) + " -c " + q(kSource + "/configs/sim-4s.json") + " --estimator joint";
    const std::string stream = dir + "/" + scenario + ".mavlink";
    r.summary = clitest::run_json(args + " --json --mavlink " + q(stream));
    for (const json& w : r.summary["warnings"])
        if (w["name"] == "sensor_fault") r.warning = w;
    const clitest::Result brief = run(args);
    REQUIRE(brief.exit_code == 0);
    r.brief = brief.out;
    const mavtest::Stream s = mavtest::decode(clitest::read_file(stream), false);
    REQUIRE(s.error.empty());
    for (const mavtest::Frame& f : s.frames)
        if (f.msgid == 253) r.texts.push_back(mavtest::text(f));
    return r;
}

bool said(const std::vector<std::string>& texts, const std::string& start) {
    return std::any_of(texts.begin(), texts.end(), [&](const std::string& t) { return t.rfind(start, 0) == 0; });
}
}  // namespace

TEST_CASE("replay says a sensor fault was a gap in the samples, and how long", "[cli][faults]") {
    const std::string dir = clitest::temp_dir();
    const FaultRun r = fly(dir, "4s-racing-fault-missed-samples");
    REQUIRE(r.warning.is_object());
    CHECK(r.warning["cause"] == json::array({"sample_gap"}));
    // The gaps, read off the log's own time column (ms): every interval beyond the joint
    // estimator's 0.75 s (max_sample_gap_s; three usual intervals are 0.2 s).
    std::istringstream lines(clitest::read_file(r.log));
    std::string line;
    long previous_ms = -1, gaps = 0, longest_ms = 0;
    while (std::getline(lines, line)) {
        const long t_ms = std::stol(line.substr(0, line.find(',')));
        if (previous_ms >= 0 && t_ms - previous_ms > 750) {
            ++gaps;
            longest_ms = std::max(longest_ms, t_ms - previous_ms);
        }
        previous_ms = t_ms;
    }
    REQUIRE(gaps >= 3);  // the scenario drops out about twice a minute for 1-3 s
    CHECK(r.warning["sample_gaps"]["count"] == gaps);
    CHECK(r.warning["sample_gaps"]["longest_s"].get<double>() == Approx(longest_ms * 1e-3).margin(1e-3));
    CHECK_FALSE(r.warning.contains("current_offset_a"));
    CHECK(r.warning["active_at_end"] == false);  // a gap ends with the sample after it
    // Each gap is a spell of its own, from the sample ending it to the next.
    CHECK(r.warning["spell_count"] == gaps);
    REQUIRE(r.warning["spells"].size() == static_cast<size_t>(std::min<long>(gaps, 16)));
    for (const json& sp : r.warning["spells"]) CHECK(sp["to_s"].get<double>() > sp["from_s"].get<double>());
    CHECK_THAT(r.brief, Catch::Contains("sensor_fault at ") && Catch::Contains(std::to_string(gaps) + " gaps between samples, longest "));
    CHECK(said(r.texts, "battsim: sensor fault: no reading for "));
    CHECK_FALSE(said(r.texts, "battsim: sensor fault: current"));
}

TEST_CASE("replay says a sensor fault was the current sensor's offset, and its size", "[cli][faults]") {
    const std::string dir = clitest::temp_dir();
    const FaultRun r = fly(dir, "4s-racing-fault-current-offset");
    REQUIRE(r.warning.is_object());
    CHECK(r.warning["cause"] == json::array({"current_offset"}));
    // The simulator's truth: the sensor reads 1.5 A high. Learnt on the ground before the
    // take-off, to within a few tenths.
    const json truth = json::parse(clitest::read_file(dir + "/4s-racing-fault-current-offset.truth.json"));
    const double injected_a = truth["scenario"]["sensor"]["faults"]["current_offset_a"].get<double>();
    REQUIRE(injected_a == 1.5);
    CHECK(r.warning["current_offset_a"].get<double>() == Approx(injected_a).margin(0.3));
    CHECK(r.warning["active_at_end"] == true);  // an offset stays
    // The sensor reads 1.5 A on the ground, above the 1 A take-off current: the flight is the
    // joint estimator's own, on the offset-corrected current, so it starts at the truth's
    // take-off and the fault, learnt on the ground, was raised before it.
    CHECK(r.summary["flight"]["start_s"].get<double>() == Approx(truth["flight"]["takeoff_s"].get<double>()).margin(0.5));
    CHECK(r.summary["flight"]["end_s"].get<double>() == Approx(truth["flight"]["landing_s"].get<double>()).margin(2.0));
    CHECK(r.warning["flight_time_s"].is_null());
    CHECK(r.summary["flight"]["remaining_time_s"]["at20"].is_number());
    CHECK_FALSE(r.warning.contains("sample_gaps"));
    CHECK_THAT(r.brief, Catch::Contains("current sensor offset 1."));
    CHECK(said(r.texts, "battsim: sensor fault: current offset 1."));

    // --config-out takes the learnt offset out of the config; the next replay through it
    // has no fault and counts the charge the pack really gave.
    const std::string fixed = dir + "/fixed.json";
    const std::string config = kSource + "/configs/sim-4s.json";
    const clitest::Result out = run("replay " + q(r.log) + " -c " + q(config) + " --estimator joint --config-out " + q(fixed));
    INFO(out.err);
    REQUIRE(out.exit_code == 0);
    CHECK_THAT(out.err, Catch::Contains("extensions.current_sensor.offset_a"));
    const json written = json::parse(clitest::read_file(fixed));
    CHECK(written["battery"]["extensions"]["current_sensor"]["offset_a"].get<double>() ==
          Approx(-r.warning["current_offset_a"].get<double>()).margin(1e-4));
    const json again = clitest::run_json("replay " + q(r.log) + " -c " + q(fixed) + " --estimator joint --json");
    for (const json& w : again["warnings"]) CHECK(w["name"] != "sensor_fault");
    const double log_charge_ah = truth["flight"]["log_charge_ah"].get<double>();
    const double before_err = std::abs(r.summary["consumed"]["ah"].get<double>() - r.summary["initial_state"]["consumed_mah"].get<double>() * 1e-3 - log_charge_ah);
    const double after_err = std::abs(again["consumed"]["ah"].get<double>() - again["initial_state"]["consumed_mah"].get<double>() * 1e-3 - log_charge_ah);
    CHECK(before_err > 0.05);         // 1.5 A over 263 s is 0.11 Ah
    CHECK(after_err < 0.3 * before_err);
}

TEST_CASE("replay says a sensor fault was a cell reading, and does not blame the config for it", "[cli][faults]") {
    const std::string dir = clitest::temp_dir();
    const FaultRun r = fly(dir, "4s-racing-fault-loose-lead");
    REQUIRE(r.warning.is_object());
    CHECK(r.warning["cause"] == json::array({"cells"}));
    CHECK(r.summary["samples"]["rejected"].contains("cell_voltage"));
    CHECK_FALSE(r.summary["samples"]["rejected"].contains("pack_voltage_high"));
    CHECK_THAT(r.brief, Catch::Contains("cell readings outside the limits") && Catch::Contains("a loose balance lead"));
    CHECK_THAT(r.brief, !Catch::Contains("does the config match this pack"));
    CHECK(said(r.texts, "battsim: sensor fault: cell reading out of range"));
}

TEST_CASE("replay: a clean flight has no sensor fault and says so", "[cli][faults]") {
    const std::string dir = clitest::temp_dir();
    const FaultRun r = fly(dir, "4s-racing-healthy-a");
    CHECK(r.warning.is_null());
    CHECK(r.summary["sensor_fault_samples"] == 0);
    CHECK_FALSE(said(r.texts, "battsim: sensor fault"));
    CHECK_THAT(r.brief, Catch::Contains("warnings: none"));
}
