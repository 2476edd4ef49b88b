// Tremblay–Dessaint model against values computed by hand (double precision, see the
// comments) for the two shipped reference parameter sets.
#include <catch2/catch.hpp>
#include <cmath>

#include "core/model/tremblay.h"
#include "host/config_json.h"

using battsim::core::TremblayModel;
using battsim::core::TremblayParams;

namespace {
TremblayParams modified_params() {
    TremblayParams p;  // defaults are the modified set
    return p;
}
TremblayParams original_params() {
    TremblayParams p;
    p.exponential_capacity_ah = 0.8f;
    p.nominal_zone_capacity_ah = 1.42f;
    p.internal_resistance_ohm = 0.0208f;
    p.curve_current_a = 0.06340690796660907f;
    return p;
}
}  // namespace

TEST_CASE("Derived parameters of the modified reference set", "[model]") {
    TremblayModel m;
    m.configure(modified_params());
    // A = 16.8 − 15.26; B = 3/0.3; E0 = 16.8 + 0.02·7 − A; K = A·e^−3·(Q−Qexp)/(Q·(Qexp+i)).
    CHECK(m.a_v() == Approx(1.54).epsilon(1e-6));
    CHECK(m.b_per_ah() == Approx(10.0).epsilon(1e-6));
    CHECK(m.e0_v() == Approx(15.4).epsilon(1e-6));
    CHECK(m.k_v() == Approx(0.008470181759446598).epsilon(1e-4));
}

TEST_CASE("Derived parameters of the original reference set", "[model]") {
    TremblayModel m;
    m.configure(original_params());
    CHECK(m.a_v() == Approx(1.54).epsilon(1e-6));
    CHECK(m.b_per_ah() == Approx(3.75).epsilon(1e-6));
    CHECK(m.e0_v() == Approx(15.261318863685704).epsilon(1e-6));
    CHECK(m.k_v() == Approx(0.042968611629187935).epsilon(1e-4));
}

TEST_CASE("Model voltage at hand-computed points", "[model]") {
    TremblayModel mod, orig;
    mod.configure(modified_params());
    orig.configure(original_params());
    struct P { float it, i, fi; double v_mod, v_orig; };
    const P points[] = {
        {0.0f, 0.0f, 0.0f, 16.94, 16.801318863685704},
        {0.3f, 7.0f, 7.0f, 15.26, 15.226731790950154},  // the exponential-zone point itself (modified)
        {0.5f, 20.0f, 10.0f, 14.879088621107169, 14.41547203237448},
        {1.0f, 40.0f, 30.0f, 13.860084036725635, 10.711642030881265},
        {1.5f, 30.0f, 25.0f, 7.8417461557041985, -20.655841482462687},
    };
    for (const P& p : points) {
        INFO("it=" << p.it << " i=" << p.i << " i*=" << p.fi);
        CHECK(mod.voltage_v(p.it, p.i, p.fi) == Approx(p.v_mod).margin(2e-4));
        CHECK(orig.voltage_v(p.it, p.i, p.fi) == Approx(p.v_orig).margin(2e-3));
    }
}

TEST_CASE("Model stays finite and monotonic up to and beyond Q", "[model]") {
    TremblayModel m;
    m.configure(modified_params());
    float prev = m.voltage_v(0.0f, 10.0f, 10.0f);
    for (int k = 1; k <= 2000; ++k) {
        const float it = 1.55f * 1.2f * static_cast<float>(k) / 2000.0f;  // runs past Q
        const float v = m.voltage_v(it, 10.0f, 10.0f);
        REQUIRE(std::isfinite(v));
        REQUIRE(v <= prev);
        prev = v;
    }
    CHECK(std::isfinite(m.voltage_v(1.55f, 10.0f, 10.0f)));
    CHECK(std::isfinite(m.voltage_v(-1.0f, 10.0f, 10.0f)));
    CHECK(m.voltage_v(-1.0f, 0.0f, 0.0f) == m.voltage_v(0.0f, 0.0f, 0.0f));  // clamped at full
    CHECK(m.voltage_v(1e9f, 0.0f, 0.0f) == m.voltage_v(m.max_used_ah(), 0.0f, 0.0f));
}

TEST_CASE("set_capacity scales the zone capacities; set_resistance re-derives E0", "[model]") {
    TremblayModel m;
    m.configure(modified_params());
    m.set_capacity_ah(1.24f);  // ratio 0.8
    CHECK(m.capacity_ah() == Approx(1.24f));
    CHECK(m.params().exponential_capacity_ah == Approx(0.24f));
    CHECK(m.params().nominal_zone_capacity_ah == Approx(1.2f));
    CHECK(m.b_per_ah() == Approx(12.5f));
    // The scaled model passes through the scaled exponential point at the curve current.
    CHECK(m.voltage_v(0.24f, 7.0f, 7.0f) == Approx(15.26f).margin(1e-4));

    m.configure(modified_params());
    m.set_resistance_ohm(0.05f);
    CHECK(m.e0_v() == Approx(16.8 + 0.05 * 7.0 - 1.54).epsilon(1e-6));
    // At the curve current the resistance cancels: the curve points still hold.
    CHECK(m.voltage_v(0.3f, 7.0f, 7.0f) == Approx(15.26f).margin(1e-4));
    // Away from it, one extra 0.03 ohm·(20 − 7) A of sag.
    TremblayModel base;
    base.configure(modified_params());
    CHECK(base.voltage_v(0.5f, 20.0f, 20.0f) - m.voltage_v(0.5f, 20.0f, 20.0f) == Approx(0.03 * 13.0).margin(1e-4));
}

TEST_CASE("Inverse and energy integral", "[model]") {
    TremblayModel m;
    m.configure(modified_params());
    for (float it : {0.05f, 0.5f, 1.0f, 1.4f}) {
        const float v = m.voltage_v(it, 2.0f, 2.0f);
        CHECK(m.used_ah_at_voltage(v, 2.0f) == Approx(it).margin(2e-4));
    }
    CHECK(m.used_ah_at_voltage(20.0f, 0.0f) == 0.0f);               // above full
    CHECK(m.used_ah_at_voltage(-5.0f, 0.0f) == m.max_used_ah());    // below anything
    // Energy: compare the closed form with a fine trapezoid of the model itself.
    double trap = 0;
    const int n = 20000;
    for (int k = 0; k < n; ++k) {
        const float a = 1.0f * k / n, b = 1.0f * (k + 1) / n;
        trap += 0.5 * (m.voltage_v(a, 5.0f, 5.0f) + m.voltage_v(b, 5.0f, 5.0f)) * (b - a);
    }
    CHECK(m.energy_wh_to(1.0f, 5.0f) == Approx(trap).epsilon(1e-4));
    CHECK(m.energy_wh_to(0.0f, 5.0f) == 0.0f);
}

TEST_CASE("Shipped configs load and carry the data README's parameters", "[model][config]") {
    using namespace battsim::host;
    const std::string dir = std::string(BATTSIM_SOURCE_DIR) + "/configs/";
    LoadedConfig mod = load_config_file(dir + "reference-modified.json");
    LoadedConfig orig = load_config_file(dir + "reference-original.json");
    CHECK(mod.monitor.battery.curve_current_a == Approx(7.0f));
    CHECK(mod.monitor.battery.exponential_capacity_ah == Approx(0.3f));
    CHECK(orig.monitor.battery.curve_current_a == Approx(0.0634069f));
    CHECK(orig.monitor.battery.internal_resistance_ohm == Approx(0.0208f));
    CHECK(orig.monitor.shunt.offset_ma == Approx(-982.8158579f));
    TremblayModel m;
    m.configure(orig.monitor.battery);
    CHECK(m.k_v() == Approx(0.042968611629187935).epsilon(1e-4));
}
