// Constant-current discharge processing: cropping, counting, smoothing, decimation, the
// lookup-table rules, the zones, and the real Samsung C/10 discharge.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "core/model/tremblay.h"
#include "host/discharge/discharge.h"
#include "host/sim/ocv.h"
#include "host/sim/simulate.h"
#include "sim_scenarios.h"
#include "test_files.h"

using namespace battsim::host;
using namespace battsim::host::discharge;

namespace {
std::string write(const std::string& name, const std::string& text) {
    static const std::string dir = testsupport::scratch_dir("discharge");
    const std::string path = dir + "/" + name + ".csv";
    testsupport::write_file(path, text);
    return path;
}

DischargeOptions options(double min_v, double max_v) {
    DischargeOptions o;
    o.min_voltage_v = min_v;
    o.max_voltage_v = max_v;
    return o;
}
}  // namespace

TEST_CASE("Crop, charge, energy and mean current", "[discharge]") {
    // 3 s disconnected (0 V), then 3600 s at 2 A falling linearly 4.1 → 3.0 V, then unplugged.
    std::string csv = "time_s,voltage_v,current_a\n0,0,0\n1,0,0\n2,0.01,0\n";
    for (int k = 0; k <= 3600; ++k) {
        char line[64];
        std::snprintf(line, sizeof line, "%d,%.5f,2\n", 3 + k, 4.1 - 1.1 * k / 3600.0);
        csv += line;
    }
    csv += "3604,0,0\n3605,0,0\n";
    const std::string path = write("crop", csv);
    const DischargeResult r = process_discharge(path, options(2.9, 4.2));
    std::remove(path.c_str());
    CHECK(r.samples_read == 3606);
    CHECK(r.samples_kept == 3601);
    CHECK(r.start_time_s == 3.0);
    CHECK(r.duration_s == 3600.0);
    CHECK(r.capacity_mah == Approx(2000.0).epsilon(1e-5));
    CHECK(r.mean_current_a == Approx(2.0).epsilon(1e-5));
    // ∫ V·I dt with the rectangular rule: 2 A × mean voltage (excluding the first sample).
    CHECK(r.energy_mwh == Approx(2000.0 * (4.1 + 3.0) / 2).epsilon(1e-3));
    CHECK(r.curve.size() == 3601);
    CHECK(r.table.size() == 131);  // 4.20 → 2.90 every 10 mV
    CHECK(r.table.front().voltage_v == 4.2);
    CHECK(r.table.back().voltage_v == Approx(2.9));
}

TEST_CASE("Lookup table: repeats averaged, skipped rows take the next value, edges the nearest", "[discharge]") {
    // 4.00 twice (10 and 20 mAh), 3.99 skipped, 3.98 (30), 3.97 (40) at 3.6 A, one sample a second.
    const std::string path = write("table", "time_s,voltage_v,current_a\n0,4.00,3.6\n10,4.00,3.6\n20,3.98,3.6\n30,3.97,3.6\n");
    const DischargeResult r = process_discharge(path, options(3.95, 4.02));
    std::remove(path.c_str());
    // Charge at each sample: 0, 10, 20, 30 mAh (3.6 A × 10 s = 10 mAh).
    REQUIRE(r.table.size() == 8);  // 4.02 … 3.95
    auto row = [&](double v) -> const TableRow& {
        for (const TableRow& t : r.table) {
            if (std::fabs(t.voltage_v - v) < 1e-9) return t;
        }
        FAIL("no row for " << v);
        return r.table[0];
    };
    CHECK(row(4.00).consumed_mah == Approx(5.0));  // (0 + 10) / 2
    CHECK(row(4.00).measured);
    CHECK(row(3.99).consumed_mah == Approx(20.0));  // skipped: the next available (3.98)
    CHECK_FALSE(row(3.99).measured);
    CHECK(row(3.98).consumed_mah == Approx(20.0));
    CHECK(row(3.97).consumed_mah == Approx(30.0));
    CHECK(row(4.02).consumed_mah == Approx(5.0));  // above the data: the nearest edge
    CHECK(row(3.95).consumed_mah == Approx(30.0)); // below the data: the nearest edge
    CHECK(row(3.97).consumed_mwh == Approx(10 * (4.00 + 3.98 + 3.97)).epsilon(1e-4));  // 3.6 A × V × 10 s
}

TEST_CASE("Smoothing and decimation", "[discharge]") {
    std::string csv = "time_s,voltage_v,current_a\n";
    for (int k = 0; k < 100; ++k) csv += std::to_string(k) + "," + (k % 2 ? "4.0" : "3.9") + ",1\n";
    const std::string path = write("smooth", csv);
    DischargeOptions o = options(3.0, 4.2);
    o.decimate = 10;
    DischargeResult r = process_discharge(path, o);
    REQUIRE(r.curve.size() == 10);
    CHECK(r.curve[3].voltage_v == Approx(3.95));       // block average of alternating samples
    CHECK(r.curve[3].time_s == Approx(34.5));
    o.decimate = 1;
    o.reaction_s = 20;  // the moving average damps the ±50 mV alternation
    r = process_discharge(path, o);
    double swing = 0;
    for (size_t i = 80; i < 99; ++i) swing = std::max(swing, std::fabs(r.curve[i + 1].voltage_v - r.curve[i].voltage_v));
    CHECK(swing < 0.01);
    o.reaction_s = 0;
    o.alpha = 1.0;  // alpha 1 = no smoothing
    r = process_discharge(path, o);
    CHECK(r.curve[5].voltage_v == 4.0);
    std::remove(path.c_str());
}

TEST_CASE("The zones of a Tremblay curve are found where the model puts them", "[discharge]") {
    battsim::core::TremblayParams p;
    p.full_voltage_v = 4.2f;
    p.exponential_voltage_v = 4.05f;
    p.exponential_capacity_ah = 0.25f;
    p.capacity_ah = 3.0f;
    p.internal_resistance_ohm = 0.03f;
    p.curve_current_a = 1.0f;
    battsim::core::TremblayModel m;
    m.configure(p);
    std::string csv = "time_s,voltage_v,current_a\n";
    for (int k = 0; k < 2 * 3600 * 2.9; k += 2) {
        char line[64];
        const float used = k / 3600.0f;
        std::snprintf(line, sizeof line, "%d,%.5f,1\n", k, m.voltage_v(used, 1.0f, 1.0f));
        csv += line;
    }
    const std::string path = write("zones", csv);
    const DischargeResult r = process_discharge(path, options(2.5, 4.3));
    std::remove(path.c_str());
    REQUIRE(r.zones.found);
    CHECK(r.zones.exponential_end_ah == Approx(0.25).epsilon(0.3));
    CHECK(r.zones.nominal_end_ah > 2.0);
    CHECK(r.zones.nominal_end_ah < 2.9);
    const battsim::core::TremblayParams back = params_from_discharge(r, p);
    CHECK(back.full_voltage_v == Approx(m.voltage_v(0.0f, 1.0f, 1.0f)).margin(0.01));
    CHECK(back.curve_current_a == Approx(1.0));
}

TEST_CASE("Discharge input errors say what to do", "[discharge]") {
    const std::string neg = write("neg", "time_s,voltage_v,current_a\n0,4.1,-3\n1,4.0,-3\n2,3.9,-3\n");
    CHECK_THROWS_WITH(process_discharge(neg, options(3.0, 4.2)), Catch::Contains("--negative-discharge"));
    CHECK_THROWS_WITH(process_discharge(neg, options(4.5, 4.6)), Catch::Contains("above the minimum voltage"));
    CHECK_THROWS_AS(process_discharge(neg, options(4.0, 3.0)), std::invalid_argument);
    std::remove(neg.c_str());
    CHECK_THROWS_AS(process_discharge("/nonexistent.csv", options(3.0, 4.2)), InputError);
}

TEST_CASE("Samsung 30Q C/10 discharge", "[discharge][data]") {
    DischargeOptions o = options(2.5, 4.2);
    o.reader.columns.current_negative_is_discharge = true;
    o.reaction_s = 60;
    o.decimate = 10;
    const DischargeResult r = process_discharge(std::string(BATTSIM_DATA_DIR) + "/samsung-30q/Q30_S001_C10.csv", o);
    CHECK(r.capacity_mah == Approx(2969).margin(2));  // the data README's trapezoid: 2.969 Ah
    CHECK(r.mean_current_a == Approx(0.300).margin(0.001));
    CHECK(r.samples_kept == 35604);  // the last row (2.4995 V) is below the minimum
    CHECK(r.info.notes.empty());      // one row below it is no discharge going on
    REQUIRE(r.zones.found);
    CHECK(r.zones.exponential_end_ah < 0.3);
    CHECK(r.zones.nominal_end_ah > 2.0);
    // The table falls monotonically in voltage, so the consumed charge only grows.
    for (size_t i = 1; i < r.table.size(); ++i) CHECK(r.table[i].consumed_mah >= r.table[i - 1].consumed_mah - 1.0);

    // Cut at row 21000 (3.62 V, 1.75 of 2.97 Ah): it stops above the minimum, so no zones, and
    // no start config read off it (its last point had passed for the knee, the part for the
    // whole); no knee either, which says the same with the minimum lowered to where it stops.
    std::ifstream in(std::string(BATTSIM_DATA_DIR) + "/samsung-30q/Q30_S001_C10.csv");
    std::string part, line;
    for (int k = 0; k < 21000 && std::getline(in, line); ++k) part += line + "\n";
    const std::string cut = testsupport::scratch_dir("discharge") + "/part.csv";
    std::ofstream(cut) << part;
    const DischargeResult p = process_discharge(cut, o);
    CHECK(p.capacity_mah == Approx(1751).margin(2));
    CHECK_FALSE(p.zones.found);
    CHECK_THAT(p.zones.note, Catch::StartsWith("the log ends at 3.618 V, above the minimum voltage of 2.500 V: the "
                                               "discharge stopped before its end, and 1751.0 mAh"));
    CHECK(p.ended_early == p.zones.note);
    CHECK_THROWS_WITH(ocv_table_from_discharge(p, 1, 0.02, 21), Catch::Contains("the log ends at 3.618 V"));
    DischargeOptions lowered = o;
    lowered.min_voltage_v = 3.61;
    const DischargeResult q = process_discharge(cut, lowered);
    CHECK(q.ended_early.empty());
    CHECK_FALSE(q.zones.found);
    CHECK_THAT(q.zones.note, Catch::StartsWith("no knee at the end of the curve (it never falls 2.5 times faster than "
                                               "over its middle; it ends at 3.6"));
    // A minimum above where the discharge goes on under load is said (a Li-ion cell read with
    // a LiPo pack's 3.325 V floor lost its last sixth without a word).
    DischargeOptions lipo = o;
    lipo.min_voltage_v = 3.325;
    const DischargeResult lipo_floor =
        process_discharge(std::string(BATTSIM_DATA_DIR) + "/samsung-30q/Q30_S001_C10.csv", lipo);
    REQUIRE(lipo_floor.info.notes.size() == 1);
    CHECK_THAT(lipo_floor.info.notes[0], Catch::StartsWith("the discharge goes on under load below the minimum voltage of "
                                                           "3.325 V for 58") &&
                                             Catch::Contains("down to 2.500 V"));
    // A maximum off the table's step gives no row below the minimum.
    DischargeOptions off_step = o;
    off_step.max_voltage_v = 4.205;
    const DischargeResult full = process_discharge(std::string(BATTSIM_DATA_DIR) + "/samsung-30q/Q30_S001_C10.csv", off_step);
    REQUIRE_FALSE(full.table.empty());
    CHECK(full.table.back().voltage_v >= off_step.min_voltage_v);
    CHECK(full.table.back().voltage_v == Approx(2.505));
}

TEST_CASE("battsim discharge writes its outputs and exits with the documented codes", "[discharge][cli][data]") {
    const std::string bin = BATTSIM_BINARY;
    const std::string dir = testsupport::scratch_dir("discharge") + "/run";
    const std::string log = std::string(BATTSIM_DATA_DIR) + "/samsung-30q/Q30_S001_4C.csv";
    const std::string cmd = bin + " discharge " + log + " --negative-discharge --min-voltage 2.5 --max-voltage 4.2 --table " + dir +
                            "-table.csv --plot " + dir + "-plot.svg --json > " + dir + "-out.json 2>/dev/null";
    REQUIRE(std::system(cmd.c_str()) == 0);
    std::ifstream table(dir + "-table.csv");
    std::string header;
    std::getline(table, header);
    CHECK(header == "voltage_v,consumed_mah,consumed_mwh,measured");
    std::ifstream svg(dir + "-plot.svg");
    std::string first;
    std::getline(svg, first);
    CHECK(first.find("<?xml") == 0);
    std::ifstream js(dir + "-out.json");
    const nlohmann::json j = nlohmann::json::parse(js);
    CHECK(j["table"].size() == 171);
    CHECK(j["schema_version"] == 1);
    CHECK(j["battsim_version"] == BATTSIM_VERSION);  // as every report says which release wrote it
    for (const char* suffix : {"-table.csv", "-plot.svg", "-out.json"}) std::remove((dir + suffix).c_str());
    CHECK(WEXITSTATUS(std::system((bin + " discharge /nonexistent.csv > /dev/null 2>&1").c_str())) == 3);
    CHECK(WEXITSTATUS(std::system((bin + " discharge " + log + " --plot x.pdf > /dev/null 2>&1").c_str())) == 2);
    // Without --negative-discharge the current is negative: an input error that says so.
    CHECK(WEXITSTATUS(std::system((bin + " discharge " + log + " --min-voltage 2.5 --max-voltage 4.2 > /dev/null 2>&1").c_str())) == 3);
    // A drive cycle has no zones to read a start config off: refused before any output is
    // written (the summary had been written first).
    const std::string pana = std::string(BATTSIM_DATA_DIR) + "/panasonic-18650pf/us06_n10c.csv";
    const std::string cfg = std::string(BATTSIM_SOURCE_DIR) + "/configs/fitted/start/panasonic-18650pf-1s.json";
    const std::string cmd2 = bin + " discharge " + pana + " -c " + cfg + " --negative-discharge --summary " + dir +
                             "-s.json --config-out " + dir + "-c.json > /dev/null 2>&1";
    CHECK(WEXITSTATUS(std::system(cmd2.c_str())) == 3);
    CHECK_FALSE(std::ifstream(dir + "-s.json").good());
    CHECK_FALSE(std::ifstream(dir + "-c.json").good());
}

TEST_CASE("OCV table from a discharge: by hand", "[discharge][ocv]") {
    // A 2S pack discharged at 0.5 A over 1 Ah, its pack voltage falling 4.2 → 3.2 V linearly
    // in charge: with R = 0.1 Ω the cells' rest voltage at SOC s is (4.2 − (1 − s) + 0.05) / 2.
    DischargeResult r;
    r.capacity_mah = 1000;
    r.mean_current_a = 0.5;
    for (int k = 0; k <= 100; ++k) {
        CurvePoint p;
        p.consumed_mah = 10.0 * k;
        p.voltage_v = 4.2 - 0.001 * p.consumed_mah;
        p.current_a = 0.5;
        r.curve.push_back(p);
    }
    const OcvTableRead t = ocv_table_from_discharge(r, 2, 0.1, 5);
    REQUIRE(t.cell_voltage_v.size() == 5);
    const double expected[5] = {1.625, 1.75, 1.875, 2.0, 2.125};
    for (int k = 0; k < 5; ++k) CHECK(t.cell_voltage_v[k] == Approx(expected[k]).margin(1e-12));
    CHECK(t.capacity_ah == 1.0);
    CHECK(t.mean_c_rate == 0.5);
    REQUIRE(t.notes.size() == 1);  // C/2 is too fast for a rest curve
    CHECK(t.notes[0].find("0.5C") != std::string::npos);
    // Between curve points the voltage is interpolated: 7 points put SOC 1/6 at 833.3 mAh.
    const OcvTableRead t7 = ocv_table_from_discharge(r, 2, 0.1, 7);
    CHECK(t7.cell_voltage_v[1] == Approx((4.2 - 1000.0 * 5.0 / 6.0 * 0.001 + 0.05) / 2).margin(1e-12));

    // A dip on a flat stretch is lifted so the table keeps rising.
    for (CurvePoint& p : r.curve) p.voltage_v = p.consumed_mah < 500 ? 4.0 : 3.0;
    r.curve[40].voltage_v = 3.9;  // 400 mAh: SOC 0.6 reads lower than SOC 0.4's 4.0 would allow
    r.mean_current_a = 0.1;
    const OcvTableRead flat = ocv_table_from_discharge(r, 1, 0.0, 6);
    for (size_t k = 1; k < flat.cell_voltage_v.size(); ++k) CHECK(flat.cell_voltage_v[k] > flat.cell_voltage_v[k - 1]);
    CHECK_FALSE(flat.notes.empty());

    CHECK_THROWS_AS(ocv_table_from_discharge(r, 1, 0.0, 1), std::invalid_argument);
    CHECK_THROWS_AS(ocv_table_from_discharge(r, 1, 0.0, 22), std::invalid_argument);
    CHECK_THROWS_AS(ocv_table_from_discharge(r, 0, 0.0, 21), std::invalid_argument);
    CHECK_THROWS_AS(ocv_table_from_discharge(r, 1, -0.1, 21), std::invalid_argument);
}

TEST_CASE("OCV table from a simulated C/5 discharge recovers the plant's rest curve", "[discharge][ocv][truth]") {
    // The simulator's healthy 4S pack hovering at 4.6 W (about 0.3 A, C/5) to its cutoff,
    // sampled once a second, with the voltage sensor's gain error set to zero: what is left
    // between the table and the plant's own curve is the polarisation's sag (I·Rp, under a
    // millivolt per cell here), the cells' spread and the reading's quantisation.
    using namespace battsim::host::sim;
    const Scenario sc = simtest::code_scenario(R"({
      "schema": "battsim.scenario", "version": 1, "name": "c5", "seed": 4001, "monitor_config": "embedded",
      "pack": {"cells": 4, "capacity_ah": 1.55},
      "profile": {"kind": "hover", "idle_before_s": 30, "armed_s": 0, "flight_s": 36000, "idle_after_s": 10,
                  "mean_power_w": 4.6, "gust_sd": 0, "takeoff_boost_s": 0},
      "sensor": {"period_ms": 1000, "tap_period_ms": 1000, "unit": {"bus_gain_error": 0}},
      "log": {"format": "csv"}
    })", "{}");
    const SimulationResult sim = simulate(sc);
    const std::string dir = testsupport::scratch_dir("discharge-ocv");
    write_simulation(sim, dir + "/c5.csv", dir + "/c5.truth.json");
    DischargeOptions o = options(13.3, 16.8);
    const DischargeResult r = process_discharge(dir + "/c5.csv", o);
    const OcvTableRead t = ocv_table_from_discharge(r, 4, 0.02, 21);  // 0.02 Ω: the sim-4s config's
    CHECK(t.notes.empty());
    CHECK(t.mean_c_rate == Approx(0.2).margin(0.02));
    // From 25 % up within a millivolt (measured: 0.7). Lower down the cells' spread shows:
    // normalised to what the pack delivered, which its weakest cell sets, the mean cell
    // there is a little fuller than the table's SOC says (+3.8 / +2.1 / +1.6 mV at 10 / 15 / 20 %).
    const OcvCurve& plant = OcvCurve::generic_lipo();
    double worst_mv = 0;
    for (int k = 2; k <= 20; ++k) {  // 10 … 100 %
        const double err_mv = 1000.0 * (t.cell_voltage_v[k] - plant.voltage_v(0.05 * k));
        INFO("SOC " << 0.05 * k << ": table " << t.cell_voltage_v[k] << " V, plant " << plant.voltage_v(0.05 * k) << " V");
        CHECK(std::fabs(err_mv) < (k >= 5 ? 1.0 : 5.0));
        if (k >= 5) worst_mv = std::max(worst_mv, std::fabs(err_mv));
    }
    // Normalised to the charge delivered, the bottom is the cutoff's rest voltage, not an
    // extrapolated tail: the configs' tables, normalised to the rated 1.55 Ah, read 3.25 V there.
    CHECK(t.cell_voltage_v[0] > 3.3);
    CHECK(t.capacity_ah == Approx(1.55).epsilon(0.02));
    std::printf("simulated C/5 OCV table: worst %.2f mV from the plant's over 25–100 %%\n", worst_mv);
}

TEST_CASE("battsim discharge reads the joint estimator's OCV table off the Samsung 30Q discharges", "[discharge][ocv][cli][data]") {
    const std::string bin = BATTSIM_BINARY;
    const std::string dir = testsupport::scratch_dir("discharge-ocv-cli");
    const std::string data = std::string(BATTSIM_DATA_DIR) + "/samsung-30q/";
    const std::string cfg = std::string(BATTSIM_SOURCE_DIR) + "/configs/fitted/samsung-30q.json";  // 1S, R = 0.029 Ω
    auto read = [&](const std::string& rate, const std::string& extra) {
        const std::string cmd = bin + " discharge " + data + "Q30_S001_" + rate + ".csv --negative-discharge -c " + cfg +
                                " --min-voltage 2.5 --max-voltage 4.2 --json " + extra + " > " + dir + "/" + rate +
                                ".json 2> " + dir + "/" + rate + ".err";
        REQUIRE(std::system(cmd.c_str()) == 0);
        std::ifstream js(dir + "/" + rate + ".json");
        return nlohmann::json::parse(js)["ocv_table"];
    };
    const nlohmann::json c10 = read("C10", "--config-out " + dir + "/cell.json");
    REQUIRE(c10["cell_voltage_v"].size() == 21);
    CHECK(c10["notes"].empty());
    CHECK(c10["capacity_ah"].get<double>() == Approx(2.969).margin(0.002));  // the data README's 2.969 Ah to 2.5 V
    CHECK(c10["cell_voltage_v"][20].get<double>() == Approx(4.1416).margin(0.001));  // the first sample, 4.1419 V at 0.3 A
    for (size_t k = 1; k < 21; ++k) CHECK(c10["cell_voltage_v"][k].get<double>() > c10["cell_voltage_v"][k - 1].get<double>());
    // The written config carries the table and loads back: a replay with it runs.
    std::ifstream cj(dir + "/cell.json");
    const nlohmann::json written = nlohmann::json::parse(cj);
    REQUIRE(written["joint"]["ocv_cell_voltage_v"].size() == 21);
    for (size_t k = 0; k < 21; ++k)  // the summary rounds to 0.1 mV
        CHECK(written["joint"]["ocv_cell_voltage_v"][k].get<double>() == Approx(c10["cell_voltage_v"][k].get<double>()).margin(6e-5));
    CHECK(std::system((bin + " replay " + data + "Q30_S001_2C.csv --negative-discharge -c " + dir +
                       "/cell.json --estimator joint --json > /dev/null 2>&1").c_str()) == 0);
    // Read off the 1C discharge the same way, the middle of the curve sits lower by the
    // polarisation the I·R term does not take back (measured 35–50 mV from 30 to 70 %),
    // and the command says the discharge was too fast.
    const nlohmann::json c1 = read("1C", "");
    for (int k = 6; k <= 14; ++k) {
        const double below_mv = 1000.0 * (c10["cell_voltage_v"][k].get<double>() - c1["cell_voltage_v"][k].get<double>());
        INFO("SOC " << 0.05 * k << ": 1C table " << below_mv << " mV below the C/10 one");
        CHECK(below_mv > 20.0);
        CHECK(below_mv < 70.0);
    }
    REQUIRE(c1["notes"].size() == 1);
    std::ifstream err(dir + "/1C.err");
    const std::string err_text((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
    CHECK(err_text.find("faster than C/4") != std::string::npos);
    CHECK(WEXITSTATUS(std::system((bin + " discharge " + data + "Q30_S001_C10.csv --negative-discharge -c " + cfg +
                                   " --min-voltage 2.5 --ocv-points 30 > /dev/null 2>&1").c_str())) == 2);
}

namespace {
// 3600 s from 4.1 V to `end_v` at `amps` (alternating with `burst_a` every other 10 s when given),
// one row a second.
std::string cc_discharge(double amps, double burst_a = 0.0, double end_v = 3.0) {
    std::string csv = "time_s,voltage_v,current_a\n";
    for (int k = 0; k <= 3600; ++k) {
        const double a = burst_a > 0.0 && (k / 10) % 2 == 1 ? burst_a : amps;
        char line[64];
        std::snprintf(line, sizeof line, "%d,%.5f,%.3f\n", k, 4.1 - (4.1 - end_v) * k / 3600.0, a);
        csv += line;
    }
    return csv;
}

bool has_note(const DischargeResult& r, const std::string& start) {
    for (const std::string& n : r.info.notes)
        if (n.rfind(start, 0) == 0) return true;
    return false;
}
}  // namespace

TEST_CASE("The C-rate is of the config's rated capacity when one is given, and a charge far from it is noted",
          "[discharge]") {
    DischargeOptions o = options(3.0, 4.2);  // the log's last sample is the minimum: a whole discharge
    // 2 A for an hour (1.999 Ah to the minimum): 1C of the charge delivered, 0.8C of a 2.5 Ah rating.
    const std::string path = write("rated", cc_discharge(2.0));
    DischargeResult r = process_discharge(path, o);
    CHECK(mean_c_rate(r) == Approx(1.0).epsilon(1e-3));
    CHECK(c_rate_text(r) == "1C of the charge it delivered, no -c config to rate it by");
    o.rated_capacity_ah = 2.5;
    r = process_discharge(path, o);
    CHECK(mean_c_rate(r) == Approx(0.8).epsilon(1e-4));
    CHECK(c_rate_text(r) == "0.8C of the config's rated 2.5 Ah");
    CHECK(ocv_table_from_discharge(r, 1, 0.0, 5).mean_c_rate == Approx(0.8).epsilon(1e-4));
    CHECK(discharge_to_json(r, false)["c_rate_of"] == "rated capacity");
    for (const std::string& n : r.info.notes) UNSCOPED_INFO(n);
    CHECK(r.info.notes.empty());  // 2 Ah of 2.5: within 0.5-2 times
    // A current in mA read as amperes: 2000 Ah from a 2.5 Ah pack had read as "ran at 1C".
    r = process_discharge(write("rated-ma", cc_discharge(2000.0)), o);
    CHECK(c_rate_text(r) == "800C of the config's rated 2.5 Ah");
    CHECK(has_note(r, "the discharge delivered 1.999e+06 mAh, 800 times the config's rated 2.5 Ah: a current or time "
                      "unit off by a thousand"));
    // A tenth of the rating, run to the minimum: also noted, as a pack's matter.
    o.rated_capacity_ah = 20.0;
    CHECK(has_note(process_discharge(path, o), "the discharge delivered 1999 mAh, 0.1 times the config's rated 20 Ah: a "
                                               "config for another pack, or a pack worn or not charged full?"));
    // Not when a --min-voltage above the cell's end cut it short (said in its own note).
    o.min_voltage_v = 3.5;
    CHECK_FALSE(has_note(process_discharge(write("rated-low", cc_discharge(2.0, 0.0, 2.9)), o), "the discharge delivered"));
    // Not when the log stops above the minimum: that it is part of a discharge is said instead.
    o.min_voltage_v = 2.9;
    const DischargeResult part = process_discharge(path, o);
    CHECK_FALSE(part.ended_early.empty());
    CHECK_FALSE(has_note(part, "the discharge delivered"));
}

TEST_CASE("A current that was not constant is noted: a flight is no constant-current discharge", "[discharge]") {
    const DischargeOptions o = options(2.9, 4.2);
    CHECK_FALSE(has_note(process_discharge(write("constant", cc_discharge(2.0)), o), "the current was not constant"));
    // 2 A and 20 A bursts in turn, each half the time.
    const DischargeResult r = process_discharge(write("bursts", cc_discharge(2.0, 20.0)), o);
    CHECK(has_note(r, "the current was not constant: 50 % of the time more than 20 % off its median"));
}
