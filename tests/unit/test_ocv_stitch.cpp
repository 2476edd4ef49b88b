// The OCV table stitched from partial flights: simulate flights of one pack model starting
// at different states of charge (the truth plant's own rest curve is known), fit from the
// config's model curve, and check the table, the starts and the error before and after.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "host/config_json.h"
#include "host/fit/ocv_stitch.h"
#include "host/sim/ocv.h"
#include "host/sim/simulate.h"
#include "sim_scenarios.h"
#include "test_files.h"

using namespace battsim::host;

namespace {

// Nine flights of the simulator's 4S pack (each its own seed: a fleet of one pack model),
// starting from full down to 44 %, racing and hover by turns, each drawing a quarter to a
// half of the pack so that the slices overlap; none is flown into the cutoff; the last one
// is held out.
struct Fleet {
    std::vector<std::string> logs;
    std::vector<double> start_soc;
};

const Fleet& fleet() {
    static const Fleet f = [] {
        Fleet out;
        const std::string dir = testsupport::scratch_dir("ocv-stitch");
        const double socs[] = {1.0, 0.92, 0.84, 0.76, 0.68, 0.6, 0.52, 0.44, 0.7};
        for (int k = 0; k < 9; ++k) {
            const std::string kind = k % 2 ? "hover" : "racing";
            const std::string flight_s = k % 2 ? "150" : "100";
            const std::string base = R"({"schema": "battsim.scenario", "version": 1, "name": "fleet)" + std::to_string(k) +
                                     R"(", "seed": )" + std::to_string(300 + k) + R"(, "monitor_config": "embedded",
              "pack": {"cells": 4, "capacity_ah": 1.55, "initial_soc": )" + std::to_string(socs[k]) + R"(},
              "profile": {"kind": ")" + kind + R"(", "idle_before_s": 30, "flight_s": )" + flight_s + R"(, "idle_after_s": 40}})";
            const sim::SimulationResult r = sim::simulate(simtest::code_scenario(base, "{}"));
            const std::string path = dir + "/fleet" + std::to_string(k) + ".csv";
            testsupport::write_file(path, r.log_text);
            out.logs.push_back(path);
            out.start_soc.push_back(socs[k]);
        }
        return out;
    }();
    return f;
}

}  // namespace

TEST_CASE("OCV stitch: partial flights recover the plant's rest curve", "[fit][sim]") {
    const Fleet& f = fleet();
    const LoadedConfig config = default_config();  // the reference 4S pack's model curve, no table
    REQUIRE(config.monitor.joint.ocv.points == 0);
    fit::OcvStitchOptions o;
    o.slow_time_s = 60.0;  // what the choice among 20…90 s picks here; fixed to keep the test quick
    const std::vector<std::string> fit_logs(f.logs.begin(), f.logs.end() - 1);
    const fit::OcvStitch s = fit::stitch_ocv(fit_logs, {f.logs.back()}, ReaderOptions{}, config, o);

    REQUIRE(s.table_v.size() == 21u);
    for (size_t j = 1; j < s.table_v.size(); ++j) CHECK(s.table_v[j] > s.table_v[j - 1]);
    // Where the flights reach, the table is the plant's rest curve within a few millivolts
    // (the plant's cells spread by their own seeds; the C/5 bench table of the suites is
    // within 2 mV of it over this range).
    const sim::OcvCurve& truth = sim::OcvCurve::generic_lipo();
    double worst_mv = 0.0;
    int compared = 0;
    for (size_t j = 0; j < s.table_v.size(); ++j) {
        const double soc = static_cast<double>(j) / 20.0;
        if (soc < 0.3 || soc > 0.96 || s.support[j] < 100.0) continue;
        worst_mv = std::max(worst_mv, std::fabs(s.table_v[j] - truth.voltage_v(soc)) * 1000.0);
        ++compared;
    }
    INFO("worst table error " << worst_mv << " mV over " << compared << " points");
    CHECK(compared >= 12);  // 14 points lie in 0.30-0.95: a support that broke would compare none
    CHECK(worst_mv < 12.0);  // 8.0 mV when written, 8.1 since the empty point keeps its prior
    // No flight reaches empty: the empty point stays at its prior, the config's minimum voltage
    // (sigma 10 mV). The smoothness had carried the correction's slope down to it, 209 mV below.
    INFO("empty point " << s.table_v[0] << " V, its prior " << s.prior_v[0] << " V");
    CHECK(s.support[0] < 1.0);
    CHECK(s.table_v[0] == Approx(s.prior_v[0]).margin(0.01));
    CHECK(s.soc_max == Approx(1.0).margin(1e-9));  // the fullest start is full
    CHECK(s.soc_min < 0.15);
    // The starts, in order, near the truth.
    for (size_t k = 0; k < s.flights.size(); ++k) {
        INFO("flight " << k);
        CHECK(s.flights[k].start_soc == Approx(f.start_soc[k]).margin(0.025));
    }
    CHECK(s.flights.back().test);
    // The model's own curve misses the measurement by tens of millivolts; the table by a few,
    // on the flight it never saw as well.
    CHECK(s.rms_before_v > 0.015);
    CHECK(s.rms_v < 0.004);
    CHECK(s.test_rms_v < s.test_rms_before_v / 5.0);
    // The flights' median ohmic resistance: the simulator's 4S pack is 16 mΩ at 25 °C and
    // warms in flight (the fit's own warming term takes the fall).
    CHECK(s.resistance_ohm == Approx(0.018).margin(0.004));

    const LoadedConfig out = fit::with_stitched_table(config, s);
    REQUIRE(out.monitor.joint.ocv.points == 21);
    CHECK(out.monitor.joint.ocv.cell_voltage_v[20] == Approx(s.table_v[20]).margin(1e-6));
    for (const auto& n : s.notes) UNSCOPED_INFO(n);
    CHECK(s.notes.empty());  // a fleet that stitches: nothing to warn of
    const nlohmann::json j = fit::to_json(s);
    CHECK(j["schema"] == "battsim.ocv_stitch");
    CHECK(j["flights"].size() == 9u);
}

TEST_CASE("OCV stitch: flights that all start at one charge say the table is not identified", "[fit][sim]") {
    // The full pack's flight twice: no slices to stitch, so the table's shape could be anything
    // the sag's model lets it be, and the report says so.
    fit::OcvStitchOptions o;
    o.slow_time_s = 60.0;
    const fit::OcvStitch s = fit::stitch_ocv({fleet().logs[0], fleet().logs[0]}, {}, ReaderOptions{}, default_config(), o);
    REQUIRE_FALSE(s.notes.empty());
    CHECK(s.notes[0].find("start within 0 %") != std::string::npos);
}

TEST_CASE("OCV stitch: options and logs it cannot use", "[fit]") {
    const LoadedConfig config = default_config();
    fit::OcvStitchOptions o;
    o.points = 1;
    CHECK_THROWS_AS(fit::stitch_ocv({fleet().logs[0]}, {}, ReaderOptions{}, config, o), std::invalid_argument);
    o = fit::OcvStitchOptions{};
    o.rest_weight = 0.0;
    CHECK_THROWS_AS(fit::stitch_ocv({fleet().logs[0]}, {}, ReaderOptions{}, config, o), std::invalid_argument);
    o = fit::OcvStitchOptions{};
    testsupport::TempDir dir("ocv-stitch-bad");
    const std::string tiny = dir.write("tiny.csv", "time_s,voltage_v,current_a\n0,16.0,0.1\n0.1,16.0,0.1\n");
    // Too little data is the log's fault (an InputError: exit 3), not the options'.
    CHECK_THROWS_AS(fit::stitch_ocv({tiny}, {}, ReaderOptions{}, config, o), fit::TooLittleData);
}

TEST_CASE("fit-ocv --test-every K holds out the 2nd log and every Kth after it", "[fit]") {
    const auto marks = [](size_t count, unsigned every) {
        std::vector<fit::OcvStitchLog> logs(count);
        fit::hold_out_every(logs, every);
        std::string m;
        for (const fit::OcvStitchLog& l : logs) m += l.test ? 'T' : 'f';
        return m;
    };
    CHECK(marks(7, 2) == "fTfTfTf");
    CHECK(marks(7, 3) == "fTffTff");  // indices 1, 4
    CHECK(marks(9, 4) == "fTfffTfff");  // indices 1, 5
    CHECK(marks(1, 2) == "f");
    CHECK(marks(2, 1000000) == "fT");
    CHECK(marks(3, 1) == "TTT");  // K = 1 (the CLI refuses it): every log
    CHECK(marks(0, 3).empty());

    // K = 0 (not given) keeps the marks; K > 0 sets every log's.
    std::vector<fit::OcvStitchLog> logs(3);
    logs[0].test = true;
    fit::hold_out_every(logs, 0);
    CHECK(logs[0].test);
    CHECK_FALSE(logs[1].test);
    fit::hold_out_every(logs, 2);
    CHECK_FALSE(logs[0].test);
    CHECK(logs[1].test);
    CHECK_FALSE(logs[2].test);
}
