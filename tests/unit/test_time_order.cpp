// TimeOrder: a binary log's rows in time order; a corrupt time stamp dropped alone, a gap kept.
#include <catch2/catch.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "host/io/time_order.h"

using battsim::host::TimeOrder;

namespace {
struct Run {
    std::vector<double> times_s;       // what came out, in order (µs / 1e6: exact for these)
    std::vector<std::string> notes;    // "kind: text"
};

// Offers rows at these times (s), row k placed at "row k"; voltage carries k to see which went.
Run order(const std::vector<double>& times_s, std::vector<int>* kept = nullptr) {
    Run run;
    TimeOrder o("CURR time", "row", [&run](const char* kind, const std::string& text) {
        run.notes.push_back(std::string(kind) + ": " + text);
    });
    battsim::core::Sample s;
    const auto drain = [&] {
        while (o.pop(s)) {
            run.times_s.push_back(static_cast<double>(s.time_us) / 1e6);
            if (kept) kept->push_back(static_cast<int>(s.voltage_v));
        }
    };
    for (size_t k = 0; k < times_s.size(); ++k) {
        battsim::core::Sample in;
        in.voltage_v = static_cast<float>(k);
        o.offer(in, times_s[k] * 1e6, "row " + std::to_string(k));
        drain();
    }
    o.finish();
    drain();
    return run;
}
}  // namespace

TEST_CASE("TimeOrder: in-order rows pass at once, a row going back is dropped alone", "[io-logs][time-order]") {
    const Run a = order({0.0, 0.1, 0.2, 0.2, 0.3});
    CHECK(a.times_s == std::vector<double>{0.0, 0.1, 0.2, 0.2, 0.3});
    CHECK(a.notes.empty());
    std::vector<int> kept;
    const Run b = order({0.0, 0.1, 0.3, 0.2, 0.4}, &kept);
    CHECK(kept == std::vector<int>{0, 1, 2, 4});
    REQUIRE(b.notes.size() == 1);
    CHECK(b.notes[0] == "backwards: row 3: CURR time 0.200000 s goes back before the previous row (0.300000 s); row dropped");
}

TEST_CASE("TimeOrder: one corrupt time stamp far ahead is dropped, not every row after it", "[io-logs][time-order]") {
    // A flipped bit throws row 2 16,777 s ahead; before, rows 3.. all "went back" and were lost.
    std::vector<int> kept;
    const Run r = order({114.3, 114.4, 16891.8, 114.5, 114.6, 114.7}, &kept);
    CHECK(kept == std::vector<int>{0, 1, 3, 4, 5});
    REQUIRE(r.notes.size() == 1);
    CHECK(r.notes[0] ==
          "glitch: row 2: CURR time 16891.800000 s jumps 16777.400 s ahead of the previous row (114.400000 s), and row "
          "3 is back at 114.500000 s: a corrupt time stamp; 1 row dropped");
    // A run of rows carrying it (a text log's CURR rows after a bad GPS row) goes with it.
    kept.clear();
    const Run g = order({10.0, 11.0, 5010.0, 5010.0, 5010.0, 13.0, 14.0}, &kept);
    CHECK(kept == std::vector<int>{0, 1, 5, 6});
    REQUIRE(g.notes.size() == 1);
    CHECK_THAT(g.notes[0], Catch::EndsWith("a corrupt time stamp; 3 rows dropped"));
    // Within the held rows, a row out of order is dropped alone and the jump still judged.
    kept.clear();
    const Run w = order({10.0, 5010.0, 5011.0, 5010.5, 12.0}, &kept);
    CHECK(kept == std::vector<int>{0, 4});
    REQUIRE(w.notes.size() == 2);
    CHECK(w.notes[0] == "backwards: row 3: CURR time 5010.500000 s goes back before the previous row (5011.000000 s); row dropped");
    CHECK_THAT(w.notes[1], Catch::EndsWith("2 rows dropped"));
}

TEST_CASE("TimeOrder: a corrupt stamp on the log's first row costs that row, not the log", "[io-logs][time-order]") {
    // Before, the first row was taken as it came, and every row after it went back.
    std::vector<int> kept;
    const Run r = order({16891.8, 114.5, 114.6, 114.7}, &kept);
    CHECK(kept == std::vector<int>{1, 2, 3});
    REQUIRE(r.notes.size() == 1);
    CHECK(r.notes[0] ==
          "glitch: row 0: CURR time 16891.800000 s is the log's first, 16777.300 s ahead of the rows after it, and "
          "row 1 is back at 114.500000 s: a corrupt time stamp; 1 row dropped");
    // ... and the rows that carried it with it; good first rows and then a jump are judged as ever.
    kept.clear();
    const Run run = order({5010.0, 5010.0, 13.0, 14.0}, &kept);
    CHECK(kept == std::vector<int>{2, 3});
    REQUIRE(run.notes.size() == 1);
    CHECK_THAT(run.notes[0], Catch::EndsWith("a corrupt time stamp; 2 rows dropped"));
    // A small step back after the first row is that row's own fault, as anywhere else.
    kept.clear();
    const Run s = order({10.0, 9.9, 10.1}, &kept);
    CHECK(kept == std::vector<int>{0, 2});
    REQUIRE(s.notes.size() == 1);
    CHECK(s.notes[0] == "backwards: row 1: CURR time 9.900000 s goes back before the previous row (10.000000 s); row dropped");
    // A log of one row keeps it.
    CHECK(order({3.0}).times_s == std::vector<double>{3.0});
}

TEST_CASE("TimeOrder: a real gap is kept: the log goes on from it", "[io-logs][time-order]") {
    // Logging stopped for 100 s: held, then released as the log goes on (no row lost, no note).
    std::vector<double> t{0.0, 0.1, 100.2};
    for (int k = 1; k <= 80; ++k) t.push_back(100.2 + 0.1 * k);
    const Run r = order(t);
    CHECK(r.times_s.size() == t.size());
    CHECK(r.notes.empty());
    // ... and at the end of the log a held jump is a gap too, when enough rows follow it to
    // show one (or it is short enough to be one).
    const Run end = order({0.0, 0.1, 500.0, 500.1, 500.2, 500.3});
    CHECK(end.times_s == std::vector<double>{0.0, 0.1, 500.0, 500.1, 500.2, 500.3});
    CHECK(end.notes.empty());
    const Run short_end = order({0.0, 0.1, 20.0});
    CHECK(short_end.times_s == std::vector<double>{0.0, 0.1, 20.0});
    // A row back before the last one kept, after a jump, is out of order, not the jump's undoing.
    std::vector<int> kept;
    const Run back = order({10.0, 11.0, 100.0, 5.0, 100.5, 100.6, 100.7}, &kept);
    CHECK(kept == std::vector<int>{0, 1, 2, 4, 5, 6});
    REQUIRE(back.notes.size() == 1);
    CHECK(back.notes[0] == "backwards: row 3: CURR time 5.000000 s goes back before the previous row (11.000000 s); row dropped");
}

TEST_CASE("TimeOrder: times no log can hold are dropped, not wrapped", "[io-logs][time-order]") {
    const Run r = order({1.0, 1.8446744073709552e13, -1.0, 2.0});
    CHECK(r.times_s == std::vector<double>{1.0, 2.0});
    REQUIRE(r.notes.size() == 2);
    CHECK_THAT(r.notes[0], Catch::StartsWith("bad-time: row 1: CURR time 18446744073709.55"));
    CHECK_THAT(r.notes[1], Catch::StartsWith("bad-time: row 2: CURR time -1.000000 s"));
}

TEST_CASE("TimeOrder: a corrupt stamp on the log's last rows is dropped, not taken for a gap", "[io-logs][time-order]") {
    // A flipped bit in log171.bin's last CURR time had read as a 16,948 s flight.
    std::vector<int> kept;
    const Run r = order({10.0, 10.1, 10.2, 16787.4}, &kept);
    CHECK(kept == std::vector<int>{0, 1, 2});
    REQUIRE(r.notes.size() == 1);
    CHECK(r.notes[0] ==
          "glitch: row 3: CURR time 16787.400000 s jumps 16777.200 s ahead of the previous row (10.200000 s), and the "
          "log ends within 1 row of it: too few to show a logging gap, so a corrupt time stamp; 1 row dropped");
    CHECK(order({10.0, 10.1, 5000.0, 5000.1, 5000.2}).times_s.size() == 2);
}

TEST_CASE("TimeOrder: a corrupt stamp a few seconds ahead costs its own row", "[io-logs][time-order]") {
    // Held from 30 s only, a stamp 20 s ahead had made every row of the next 20 s "go back".
    std::vector<double> t;
    for (int k = 0; k < 400; ++k) t.push_back(100.0 + 0.1 * k);
    t[50] += 20.0;  // among the log's first rows, which are held too
    t[250] += 20.0;
    std::vector<int> kept;
    const Run r = order(t, &kept);
    CHECK(kept.size() == 398);
    CHECK(std::find(kept.begin(), kept.end(), 50) == kept.end());
    CHECK(std::find(kept.begin(), kept.end(), 250) == kept.end());
    REQUIRE(r.notes.size() == 2);
    CHECK_THAT(r.notes[0], Catch::EndsWith("a corrupt time stamp; 1 row dropped"));
    CHECK_THAT(r.notes[1], Catch::EndsWith("a corrupt time stamp; 1 row dropped"));
    // A logging gap of 2 s is kept whole.
    std::vector<double> g;
    for (int k = 0; k < 100; ++k) g.push_back(0.1 * k + (k >= 50 ? 2.0 : 0.0));
    const Run gap = order(g);
    CHECK(gap.times_s.size() == 100);
    CHECK(gap.notes.empty());
}
