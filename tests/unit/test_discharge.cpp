// Constant-current discharge processing: cropping, counting, smoothing, decimation, the
// lookup-table rules, the zones, and the real Samsung C/10 discharge.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "core/model/tremblay.h"
#include "host/discharge/discharge.h"
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
    REQUIRE(r.zones.found);
    CHECK(r.zones.exponential_end_ah < 0.3);
    CHECK(r.zones.nominal_end_ah > 2.0);
    // The table falls monotonically in voltage, so the consumed charge only grows.
    for (size_t i = 1; i < r.table.size(); ++i) CHECK(r.table[i].consumed_mah >= r.table[i - 1].consumed_mah - 1.0);
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
    for (const char* suffix : {"-table.csv", "-plot.svg", "-out.json"}) std::remove((dir + suffix).c_str());
    CHECK(WEXITSTATUS(std::system((bin + " discharge /nonexistent.csv > /dev/null 2>&1").c_str())) == 3);
    CHECK(WEXITSTATUS(std::system((bin + " discharge " + log + " --plot x.pdf > /dev/null 2>&1").c_str())) == 2);
    // Without --negative-discharge the current is negative: an input error that says so.
    CHECK(WEXITSTATUS(std::system((bin + " discharge " + log + " --min-voltage 2.5 --max-voltage 4.2 > /dev/null 2>&1").c_str())) == 3);
}
