// battsim replay --mavlink / --tlog from the outside: the stream read back by the tests' own
// decoder (tests/support/mavlink_decode.h), against the summary JSON of the same run.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <string>

#include "cli_util.h"
#include "mavlink_decode.h"

using clitest::q;
using clitest::run;
using nlohmann::json;

namespace {
const std::string kSource = BATTSIM_SOURCE_DIR;

// A config: configs/sim-4s.json with `telemetry` set.
std::string config_with(const std::string& dir, const json& telemetry) {
    json c = json::parse(clitest::read_file(kSource + "/configs/sim-4s.json"));
    c["telemetry"] = telemetry;
    const std::string path = dir + "/telemetry-config.json";
    clitest::write_file(path, c.dump(2));
    return path;
}
}  // namespace

TEST_CASE("replay --mavlink and --tlog tell a ground station what the summary says", "[cli][telemetry]") {
    const std::string dir = clitest::temp_dir();
    // A pack at 75 % of its capacity: the joint estimator warns early in the flight.
    const std::string log = dir + "/cap75.csv";
    const clitest::Result sim = run("simulate " + q(kSource + "/configs/scenarios/4s-racing-capacity-75.json") + " -o " + q(log));
    INFO(sim.err);
    REQUIRE(sim.exit_code == 0);
    const std::string config = config_with(dir, {{"system_id", 7}, {"battery_id", 1}, {"interval_s", 0.5}});
    const std::string raw = dir + "/out.mavlink", tlog = dir + "/out.tlog";
    const json summary = clitest::run_json("replay " + q(log) + " -c " + q(config) + " --estimator joint --json --mavlink " +
                                           q(raw) + " --tlog " + q(tlog));

    const mavtest::Stream r = mavtest::decode(clitest::read_file(raw), false);
    const mavtest::Stream t = mavtest::decode(clitest::read_file(tlog), true);
    REQUIRE(r.error.empty());
    REQUIRE(t.error.empty());
    REQUIRE(r.frames.size() == t.frames.size());
    uint64_t last_us = 0;
    long statuses = 0;
    int32_t last_consumed = -1;
    std::map<std::string, double> texts;        // sentence → log time first sent (s)
    std::map<std::string, double> first_texts;  // its first 16 characters → log time first sent
    double last_text_s = -1;
    int text_frames = 0;
    for (size_t i = 0; i < r.frames.size(); ++i) {
        const mavtest::Frame& f = r.frames[i];
        CHECK(f.payload == t.frames[i].payload);  // the same frames, stamped
        CHECK(f.seq == static_cast<uint8_t>(i));
        CHECK(f.sysid == 7);
        CHECK(f.compid == 180);
        CHECK(t.frames[i].tlog_time_us >= last_us);
        last_us = t.frames[i].tlog_time_us;
        if (f.msgid == 147) {
            ++statuses;
            const mavtest::Battery b = mavtest::battery(f);
            CHECK(b.id == 1);
            CHECK(b.voltages_mv[3] != 0xFFFF);  // the simulated log has four cells
            CHECK(b.voltages_mv[4] == 0xFFFF);
            if (b.current_consumed_mah >= 0) {
                CHECK(b.current_consumed_mah >= last_consumed);  // charge only flows out
                last_consumed = b.current_consumed_mah;
            }
        }
        if (f.msgid == 253) {
            const double at_s = static_cast<double>(t.frames[i].tlog_time_us) * 1e-6;
            const std::string sentence = mavtest::text(f);
            // Said again every 30 s (text_repeat_s) while active: the numbers may move.
            if (!first_texts.count(sentence.substr(0, 16))) first_texts[sentence.substr(0, 16)] = at_s;
            texts.emplace(sentence, at_s);
            ++text_frames;
            if (last_text_s >= 0) CHECK(at_s - last_text_s >= 30.0 - 1e-6);
            last_text_s = at_s;
        }
    }
    // Two a second, over the whole log.
    const double log_s = summary["flight"]["end_s"].get<double>() + 60.0;  // 60 s on the ground after landing
    CHECK(statuses == Approx(2.0 * log_s).margin(4));
    CHECK(last_consumed > 1000);

    // The short-flight warning, with its cause, at the very sample the summary raised it.
    bool short_flight = false;
    for (const json& w : summary["warnings"]) {
        if (w["name"] != "short_flight") continue;
        short_flight = true;
        REQUIRE(first_texts.count("battsim: flight "));
        CHECK(first_texts["battsim: flight "] == Approx(w["first_time_s"].get<double>()).margin(1e-3));
        bool with_cause = false;
        for (const auto& [sentence, time_s] : texts)
            with_cause |= sentence.rfind("battsim: flight ", 0) == 0 && sentence.find("short, capacity") != std::string::npos;
        CHECK(with_cause);
        CHECK(text_frames >= 2);  // still short 30 s later: said again
    }
    CHECK(short_flight);
    // Its cause was raised with it, so it has no sentence of its own.
    for (const auto& [sentence, time_s] : texts) CHECK(sentence.rfind("battsim: low capacity", 0) != 0);
}

TEST_CASE("replay --mavlink: a bad telemetry section or an unwritable path is a clear error", "[cli][telemetry]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/healthy.csv";
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/4s-racing-healthy-a.json") + " -o " + q(log)).exit_code == 0);

    const std::string bad = config_with(dir, {{"low_time_s", 30}, {"critical_time_s", 45}});
    clitest::Result r = run("replay " + q(log) + " -c " + q(bad) + " --mavlink " + q(dir + "/x.mavlink"));
    CHECK(r.exit_code != 0);
    CHECK(r.err.find("$.telemetry.critical_time_s") != std::string::npos);
    CHECK(r.err.find("expected at most low_time_s") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir + "/x.mavlink"));

    const std::string typo = config_with(dir, {{"sysid", 3}});
    r = run("replay " + q(log) + " -c " + q(typo) + " --mavlink " + q(dir + "/x.mavlink"));
    CHECK(r.exit_code != 0);
    CHECK(r.err.find("$.telemetry.sysid") != std::string::npos);

    r = run("replay " + q(log) + " --mavlink " + q(dir + "/x.bin") + " --tlog " + q(dir + "/x.bin"));
    CHECK(r.exit_code == 2);
    CHECK(r.err == "battsim replay: --tlog and --mavlink name the same file: " + dir + "/x.bin\n");
    CHECK_FALSE(std::filesystem::exists(dir + "/x.bin"));

    r = run("replay " + q(log) + " --mavlink " + q(dir + "/no-such-dir/x.mavlink"));
    CHECK(r.exit_code == 5);
    CHECK(r.err.find("no-such-dir") != std::string::npos);

    // A healthy pack: no text at all, and the stream ends OK.
    const std::string ok = dir + "/ok.mavlink";
    r = run("replay " + q(log) + " -c " + q(kSource + "/configs/sim-4s.json") + " --estimator joint --mavlink " + q(ok));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const mavtest::Stream s = mavtest::decode(clitest::read_file(ok), false);
    REQUIRE(s.error.empty());
    uint8_t last_state = 0;
    for (const mavtest::Frame& f : s.frames) {
        CHECK(f.msgid != 253);
        if (f.msgid == 147) last_state = mavtest::battery(f).charge_state;
    }
    CHECK(last_state == 1);  // MAV_BATTERY_CHARGE_STATE_OK, on the ground after the landing
}

TEST_CASE("replay --said lists the texts the stream carried, at their times", "[cli][telemetry]") {
    const std::string dir = clitest::temp_dir();
    const std::string log = dir + "/cap75.csv";
    REQUIRE(run("simulate " + q(kSource + "/configs/scenarios/4s-racing-capacity-75.json") + " -o " + q(log)).exit_code == 0);
    const std::string tlog = dir + "/out.tlog";
    const json summary = clitest::run_json("replay " + q(log) + " -c " + q(kSource + "/configs/sim-4s.json") +
                                           " --estimator joint --json --said --tlog " + q(tlog));
    const mavtest::Stream t = mavtest::decode(clitest::read_file(tlog), true);
    REQUIRE(t.error.empty());
    std::vector<std::pair<double, std::string>> sent;
    for (const mavtest::Frame& f : t.frames)
        if (f.msgid == 253) sent.emplace_back(static_cast<double>(f.tlog_time_us) * 1e-6, mavtest::text(f));
    const json& said = summary["said"];
    REQUIRE(said.size() == sent.size());
    REQUIRE(sent.size() >= 2);  // the short flight, and its repeat
    const double start_s = summary["flight"]["start_s"].get<double>();
    for (size_t i = 0; i < sent.size(); ++i) {
        CHECK(said[i]["text"] == sent[i].second);
        CHECK(said[i]["time_s"].get<double>() == Approx(sent[i].first).margin(1e-6));
        CHECK(said[i]["flight_time_s"].get<double>() == Approx(sent[i].first - start_s).margin(1e-3));
        CHECK(said[i]["severity"] == "warning");
    }
    // For people: the same lines after the brief.
    const clitest::Result brief = run("replay " + q(log) + " -c " + q(kSource + "/configs/sim-4s.json") + " --estimator joint --said");
    REQUIRE(brief.exit_code == 0);
    CHECK(brief.out.find("  said (ground station):\n") != std::string::npos);
    CHECK(brief.out.find("s into the flight  warning  " + sent[0].second + "\n") != std::string::npos);
}

TEST_CASE("replay --said: the aged pack's short flight that cleared is withdrawn in flight", "[cli][telemetry][data]") {
    const std::string flight = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/29.csv";
    const json summary = clitest::run_json("replay " + q(flight) + " -c " + q(kSource + "/configs/sim-4s.json") +
                                           " --estimator joint --json --said");
    json short_flight;
    for (const json& w : summary["warnings"])
        if (w["name"] == "short_flight") short_flight = w;
    REQUIRE(short_flight.is_object());
    // On for 1.9 s 13.5 s into the flight (for its resistance), off, and on again as it lands
    // (for its capacity); until the fiftieth session's minute-long R0 under the polarisation
    // one spell of 3.3 s, for its capacity, and "not short now".
    REQUIRE(short_flight["spell_count"] == 2);
    const double off_s = short_flight["spells"][0]["to_s"].get<double>();
    const json& said = summary["said"];
    REQUIRE(said.size() == 3);
    CHECK(said[0]["severity"] == "warning");
    CHECK(said[0]["text"].get<std::string>().rfind("battsim: flight ", 0) == 0);
    CHECK(said[1]["severity"] == "notice");
    CHECK(said[1]["text"] == "battsim: short flight cleared, 3% short now");
    CHECK(said[2]["severity"] == "warning");
    // After telemetry.clear_hold_s (5 s) of it off (and its reading clear of the bar).
    CHECK(said[1]["time_s"].get<double>() >= off_s + 5.0);
    CHECK(said[1]["flight_time_s"].is_number());
}

TEST_CASE("replay's brief: warnings on the ground and after the landing are said where they came", "[cli][telemetry]") {
    const std::string dir = clitest::temp_dir();
    // 0.1 s samples: on the ground, [a 60 s flight at 20 A, 15 s on the ground,] a 3 s gap, more ground.
    const auto log = [&dir](const std::string& name, bool flight) {
        std::string text = "time_s,voltage_v,current_a\n";
        double t = 0.0;
        const auto add = [&](double seconds, double v, double a) {
            for (int k = 0; k < static_cast<int>(seconds * 10.0 + 0.5); ++k, t += 0.1) {
                char row[64];
                std::snprintf(row, sizeof row, "%.3f,%.3f,%.3f\n", t, v, a);
                text += row;
            }
        };
        add(20.0, 16.6, 0.3);
        if (flight) add(60.0, 15.4, 20.0), add(15.0, 16.0, 0.3);
        t += 3.0;
        add(10.0, 16.0, 0.3);
        clitest::write_file(dir + "/" + name, text);
        return q(dir + "/" + name);
    };
    const std::string cfg = " -c " + q(kSource + "/configs/sim-4s.json") + " --estimator joint --said";
    // No flight at all: the gap is still a warning, and the brief still lists it.
    clitest::Result r = run("replay " + log("ground.csv", false) + cfg);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.out, Catch::Contains("no flight (the current never stayed above the flying threshold long enough for a take-off)\n  warnings:\n    sensor_fault at 23.0 s"));
    CHECK_THAT(r.out, Catch::Contains("23.0 s, on the ground  warning  battsim: sensor fault: no reading for 3.1 s"));
    // After the landing: counted from it, not "77 s into" a 60 s flight.
    r = run("replay " + log("landed.csv", true) + cfg);
    REQUIRE(r.exit_code == 0);
    const json j = clitest::run_json("replay " + q(dir + "/landed.csv") + cfg + " --json");
    const double after_s = j["said"][0]["flight_time_s"].get<double>() - j["flight"]["duration_s"].get<double>();
    REQUIRE(after_s > 10.0);
    char when[64];
    std::snprintf(when, sizeof when, "%.1f s after the landing", after_s);
    CHECK_THAT(r.out, Catch::Contains(std::string("sensor_fault at 98.0 s (") + when));
    CHECK_THAT(r.out, Catch::Contains(std::string(when) + "  warning  battsim: sensor fault: no reading for 3.1 s"));
    CHECK(r.out.find("s into the flight") == std::string::npos);  // no warning placed in the flight
}
