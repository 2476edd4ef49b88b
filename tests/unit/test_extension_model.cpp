// The core model extensions: off = the plain Tremblay model bit for bit; each extension
// against its closed form.
#include <catch2/catch.hpp>
#include <cmath>

#include "core/model/extensions/extended_model.h"

using battsim::core::ExtendedModel;
using battsim::core::ModelExtensions;
using battsim::core::TremblayModel;
using battsim::core::TremblayParams;

namespace {
TremblayParams reference() { return TremblayParams{}; }  // the modified reference set
}  // namespace

TEST_CASE("Extensions off reproduce the Tremblay model bit for bit", "[extension]") {
    TremblayModel base;
    base.configure(reference());
    ExtendedModel ext;
    ext.configure(reference(), ModelExtensions{});
    float used = 0.0f;
    for (int k = 0; k < 2000; ++k) {
        const float i = 5.0f + 40.0f * static_cast<float>((k * 37) % 100) / 100.0f;
        const float fi = 0.7f * i;
        ext.update(i, 0.067f, false, 0.0f);
        used += i * 0.067f / 3600.0f;
        REQUIRE(ext.voltage_v(used, i, fi) == base.voltage_v(used, i, fi));
    }
    for (float v : {16.9f, 16.0f, 15.2f, 14.1f, 13.0f}) {
        CHECK(ext.used_ah_at_voltage(v, 0.5f) == base.used_ah_at_voltage(v, 0.5f));
    }
}

TEST_CASE("An RC branch follows its step response and relaxes", "[extension]") {
    ModelExtensions e;
    e.rc_count = 1;
    e.rc[0].resistance_ohm = 0.01f;
    e.rc[0].time_constant_s = 5.0f;
    ExtendedModel m;
    m.configure(reference(), e);
    TremblayModel base;
    base.configure(reference());
    const float i = 20.0f;
    for (int k = 0; k < 100; ++k) m.update(i, 0.1f, false, 0.0f);  // 10 s
    const double expected = 0.01 * 20.0 * (1.0 - std::exp(-10.0 / 5.0));
    CHECK(m.status().rc_voltage_v[0] == Approx(expected).epsilon(1e-4));
    CHECK(base.voltage_v(0.1f, i, i) - m.voltage_v(0.1f, i, i) == Approx(expected).epsilon(1e-3));
    const float at_stop = m.status().rc_voltage_v[0];
    for (int k = 0; k < 50; ++k) m.update(0.0f, 0.1f, false, 0.0f);  // 5 s at rest
    CHECK(m.status().rc_voltage_v[0] == Approx(at_stop * std::exp(-1.0)).epsilon(1e-4));
    // One long step equals many short ones (exact discretisation).
    ExtendedModel a, b;
    a.configure(reference(), e);
    b.configure(reference(), e);
    a.update(10.0f, 3.0f, false, 0.0f);
    for (int k = 0; k < 30; ++k) b.update(10.0f, 0.1f, false, 0.0f);
    CHECK(a.status().rc_voltage_v[0] == Approx(b.status().rc_voltage_v[0]).epsilon(1e-4));
}

TEST_CASE("Temperature dependence: Arrhenius R and K, linear Q and E0", "[extension]") {
    ModelExtensions e;
    e.temperature.enabled = true;
    e.temperature.reference_c = 25.0f;
    e.temperature.resistance_activation_k = 3000.0f;
    e.temperature.polarisation_activation_k = 2000.0f;
    e.temperature.capacity_ah_per_c = 0.01f;
    e.temperature.e0_v_per_c = 0.001f;
    ExtendedModel m;
    m.configure(reference(), e);
    TremblayModel base;
    base.configure(reference());
    // At the reference temperature nothing changes (within float rounding of the re-evaluation).
    m.update(10.0f, 0.1f, true, 25.0f);
    CHECK(m.voltage_v(0.4f, 10.0f, 8.0f) == Approx(base.voltage_v(0.4f, 10.0f, 8.0f)).margin(1e-5));
    m.update(10.0f, 0.1f, true, 0.0f);
    const double inv = 1.0 / 273.15 - 1.0 / 298.15;
    CHECK(m.status().resistance_ohm == Approx(0.02 * std::exp(3000.0 * inv)).epsilon(1e-5));
    CHECK(m.status().capacity_ah == Approx(1.55 - 0.25).epsilon(1e-5));
    // At zero charge drawn and zero current only E0 and A remain: the E0 shift shows alone.
    const double e0_shift = 0.001 * (0.0 - 25.0);
    CHECK(m.voltage_v(0.0f, 0.0f, 0.0f) - base.voltage_v(0.0f, 0.0f, 0.0f) == Approx(e0_shift).margin(1e-5));
    // Colder: the resistive drop grows by exactly the Arrhenius factor.
    const double drop_cold = m.voltage_v(0.0f, 0.0f, 0.0f) - m.voltage_v(0.0f, 10.0f, 0.0f);
    CHECK(drop_cold == Approx(10.0 * 0.02 * std::exp(3000.0 * inv)).epsilon(1e-4));
}

TEST_CASE("Lumped thermal state heats towards ambient + Rth·P and yields to a measurement", "[extension]") {
    ModelExtensions e;
    e.temperature.enabled = true;
    e.temperature.reference_c = 20.0f;
    e.thermal.enabled = true;
    e.thermal.ambient_c = 20.0f;
    e.thermal.thermal_resistance_k_per_w = 2.0f;
    e.thermal.time_constant_s = 100.0f;
    ExtendedModel m;
    m.configure(reference(), e);
    CHECK(m.status().temperature_c == 20.0f);
    for (int k = 0; k < 100; ++k) m.update(10.0f, 1.0f, false, 0.0f);  // one time constant
    const double steady = 20.0 + 2.0 * 10.0 * 10.0 * 0.02;       // 2 K/W · I²R
    CHECK(m.status().temperature_c == Approx(20.0 + (steady - 20.0) * (1.0 - std::exp(-1.0))).epsilon(1e-3));
    CHECK_FALSE(m.status().temperature_measured);
    m.update(10.0f, 1.0f, true, -5.0f);
    CHECK(m.status().temperature_c == -5.0f);
    CHECK(m.status().temperature_measured);
}

TEST_CASE("Hysteresis moves towards -M while discharging and +M while charging", "[extension]") {
    ModelExtensions e;
    e.hysteresis.magnitude_v = 0.02f;
    e.hysteresis.rate_per_ah = 50.0f;
    ExtendedModel m;
    m.configure(reference(), e);
    for (int k = 0; k < 3600; ++k) m.update(1.0f, 1.0f, false, 0.0f);  // 1 Ah through
    CHECK(m.status().hysteresis_v == Approx(-0.02).margin(1e-6));
    for (int k = 0; k < 3600; ++k) m.update(-1.0f, 1.0f, false, 0.0f);
    CHECK(m.status().hysteresis_v == Approx(0.02).margin(1e-6));
    const float at_rest = m.status().hysteresis_v;
    m.update(0.0f, 100.0f, false, 0.0f);
    CHECK(m.status().hysteresis_v == at_rest);  // no current, no movement
}

TEST_CASE("OCV correction interpolates linearly and holds its ends", "[extension]") {
    ModelExtensions e;
    e.ocv.count = 3;
    e.ocv.span_ah = 1.0f;
    e.ocv.delta_v[0] = 0.1f;
    e.ocv.delta_v[1] = -0.1f;
    e.ocv.delta_v[2] = 0.3f;
    ExtendedModel m;
    m.configure(reference(), e);
    TremblayModel base;
    base.configure(reference());
    auto delta = [&](float used) { return m.voltage_v(used, 0.0f, 0.0f) - base.voltage_v(used, 0.0f, 0.0f); };
    CHECK(delta(0.0f) == Approx(0.1).margin(1e-5));
    CHECK(delta(0.25f) == Approx(0.0).margin(1e-5));
    CHECK(delta(0.75f) == Approx(0.1).margin(1e-5));
    CHECK(delta(1.0f) == Approx(0.3).margin(1e-5));
    CHECK(delta(1.4f) == Approx(0.3).margin(1e-5));
}

TEST_CASE("Current-sensor gain, offset and timing skew", "[extension]") {
    ModelExtensions e;
    e.current_sensor.gain = 1.05f;
    e.current_sensor.offset_a = -0.5f;
    e.current_sensor.lead_s = 0.1f;
    ExtendedModel m;
    m.configure(reference(), e);
    CHECK(m.corrected_current_a(10.0f) == Approx(10.0f * 1.05f - 0.5f));
    TremblayModel base;
    base.configure(reference());
    m.update(10.0f, 0.1f, false, 0.0f);
    m.update(20.0f, 0.1f, false, 0.0f);  // slope 100 A/s: the model sees 20 + 0.1·100 = 30 A
    CHECK(m.voltage_v(0.1f, 20.0f, 15.0f) == Approx(base.voltage_v(0.1f, 30.0f, 15.0f)).margin(1e-5));
}

TEST_CASE("The inversion finds the charge that gives the voltage", "[extension]") {
    ModelExtensions e;
    e.rc_count = 1;
    e.rc[0].resistance_ohm = 0.01f;
    e.rc[0].time_constant_s = 2.0f;
    e.ocv.count = 4;
    e.ocv.span_ah = 1.5f;
    e.ocv.delta_v[1] = 0.02f;
    e.ocv.delta_v[2] = -0.03f;
    ExtendedModel m;
    m.configure(reference(), e);
    for (int k = 0; k < 20; ++k) m.update(3.0f, 0.1f, false, 0.0f);
    for (float used : {0.1f, 0.5f, 0.9f, 1.3f}) {
        const float v = m.voltage_v(used, 3.0f, 3.0f);
        CHECK(m.used_ah_at_voltage(v, 3.0f) == Approx(used).margin(1e-4));
    }
}

TEST_CASE("Bad extension settings stay finite", "[extension]") {
    ModelExtensions e;
    e.rc_count = 9;
    e.rc[0].time_constant_s = 0.0f;
    e.rc[1].time_constant_s = -3.0f;
    e.rc[2].resistance_ohm = NAN;
    e.ocv.count = 1;
    e.thermal.enabled = true;
    e.thermal.time_constant_s = 0.0f;
    e.temperature.enabled = true;
    e.temperature.resistance_activation_k = 1e5f;
    ExtendedModel m;
    m.configure(reference(), e);
    for (int k = 0; k < 100; ++k) m.update(50.0f, 0.1f, k % 2 == 0, -200.0f);
    m.update(NAN, 0.1f, false, 0.0f);
    const float v = m.voltage_v(0.5f, 50.0f, 40.0f);
    CHECK(std::isfinite(v));
    CHECK(std::isfinite(m.used_ah_at_voltage(14.0f, 1.0f)));
}
