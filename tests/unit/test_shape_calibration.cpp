// The calibration's choice among candidate shares, by hand (the replays behind each
// candidate's error are exercised from the outside in tests/cli/test_calibrate_cli.cpp).
#include <catch2/catch.hpp>

#include "host/fit/shape_calibration.h"

using battsim::host::choose_candidate;
using battsim::host::ShapeCandidate;

namespace {
ShapeCandidate cand(double share, double error) {
    ShapeCandidate c;
    c.slow_share = share;
    c.mean_abs_error = error;
    return c;
}
}  // namespace

TEST_CASE("Shape calibration: the configured share stays within the tolerance", "[fit]") {
    // Configured 0.2 is 4 % off; 0.3 would be 1 % off, but 4 % is within the rests' own error.
    const std::vector<ShapeCandidate> c = {cand(0.2, 0.04), cand(0.1, 0.08), cand(0.3, 0.01)};
    CHECK(choose_candidate(c, 0.05) == 0);
    CHECK(choose_candidate(c, 0.03) == 2);  // beyond a tighter tolerance the best wins
    CHECK(choose_candidate(c, 0.04) == 0);  // on the bar: kept
}

TEST_CASE("Shape calibration: the best share, the nearer one on a tie", "[fit]") {
    // 0.5 and 0.6 fit equally (a share that no longer moves the end capacity): 0.5 is nearer 0.2.
    const std::vector<ShapeCandidate> c = {cand(0.2, 0.14), cand(0.6, 0.02), cand(0.5, 0.02), cand(0.4, 0.07)};
    CHECK(choose_candidate(c, 0.05) == 2);
    const std::vector<ShapeCandidate> lower = {cand(0.2, 0.09), cand(0.1, 0.03), cand(0.15, 0.01)};
    CHECK(choose_candidate(lower, 0.05) == 2);
    CHECK(choose_candidate({}, 0.05) == 0);
}
