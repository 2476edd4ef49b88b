#include "host/config_extensions.h"

#include "host/config_reader.h"

namespace battsim {
namespace host {

namespace {
using nlohmann::json;
using Reader = ConfigObjectReader;
constexpr double kBig = 1e9;
const auto num = config_number;
}  // namespace

core::ModelExtensions extensions_from_json(const json& j, const std::string& origin, const std::string& where) {
    core::ModelExtensions e;
    Reader root(j, where, origin);
    if (const json* rc = root.member("rc_branches")) {
        const std::string p = root.child("rc_branches");
        if (!rc->is_array()) root.fail(p, "expected an array of {resistance_ohm, time_constant_s}");
        if (rc->size() > static_cast<size_t>(core::kMaxRcBranches))
            root.fail(p, "at most " + std::to_string(core::kMaxRcBranches) + " branches");
        for (size_t k = 0; k < rc->size(); ++k) {
            Reader b((*rc)[k], p + "[" + std::to_string(k) + "]", origin);
            b.number("resistance_ohm", e.rc[k].resistance_ohm, 0, 100);
            b.number("time_constant_s", e.rc[k].time_constant_s, 1e-3, kBig);
        }
        e.rc_count = static_cast<uint8_t>(rc->size());
    }
    if (const json* t = root.member("temperature")) {
        Reader r(*t, root.child("temperature"), origin);
        e.temperature.enabled = true;
        r.number("reference_c", e.temperature.reference_c, -100, 200);
        r.number("resistance_activation_k", e.temperature.resistance_activation_k, -1e5, 1e5);
        r.number("polarisation_activation_k", e.temperature.polarisation_activation_k, -1e5, 1e5);
        r.number("capacity_ah_per_c", e.temperature.capacity_ah_per_c, -1e3, 1e3);
        r.number("e0_v_per_c", e.temperature.e0_v_per_c, -10, 10);
    }
    if (const json* t = root.member("thermal")) {
        Reader r(*t, root.child("thermal"), origin);
        e.thermal.enabled = true;
        r.number("ambient_c", e.thermal.ambient_c, -100, 200);
        r.number("thermal_resistance_k_per_w", e.thermal.thermal_resistance_k_per_w, 0, 1e6);
        r.number("time_constant_s", e.thermal.time_constant_s, 1e-3, kBig);
    }
    if (const json* h = root.member("hysteresis")) {
        Reader r(*h, root.child("hysteresis"), origin);
        r.number("magnitude_v", e.hysteresis.magnitude_v, -100, 100);
        r.number("rate_per_ah", e.hysteresis.rate_per_ah, 0, kBig);
    }
    if (const json* o = root.member("ocv_correction")) {
        Reader r(*o, root.child("ocv_correction"), origin);
        r.number("span_ah", e.ocv.span_ah, 1e-6, 1e4);
        const json* d = r.member("delta_v");
        const std::string p = r.child("delta_v");
        if (d == nullptr) r.fail(p, "missing: expected an array of 2 to " + std::to_string(core::kMaxOcvPoints) + " numbers");
        if (!d->is_array() || d->size() < 2 || d->size() > static_cast<size_t>(core::kMaxOcvPoints))
            r.fail(p, "expected an array of 2 to " + std::to_string(core::kMaxOcvPoints) + " numbers");
        for (size_t k = 0; k < d->size(); ++k)
            e.ocv.delta_v[k] = static_cast<float>(r.check((*d)[k], p + "[" + std::to_string(k) + "]", -100, 100));
        e.ocv.count = static_cast<uint8_t>(d->size());
    }
    if (const json* s = root.member("current_sensor")) {
        Reader r(*s, root.child("current_sensor"), origin);
        r.number("gain", e.current_sensor.gain, 1e-3, 1e3);
        r.number("offset_a", e.current_sensor.offset_a, -kBig, kBig);
        r.number("lead_s", e.current_sensor.lead_s, -100, 100);
    }
    return e;
}

json extensions_to_json(const core::ModelExtensions& e) {
    json j = json::object();
    if (e.rc_count > 0) {
        json a = json::array();
        for (int k = 0; k < e.rc_count; ++k)
            a.push_back({{"resistance_ohm", num(e.rc[k].resistance_ohm)}, {"time_constant_s", num(e.rc[k].time_constant_s)}});
        j["rc_branches"] = a;
    }
    if (e.temperature.enabled) {
        j["temperature"] = {{"reference_c", num(e.temperature.reference_c)},
                            {"resistance_activation_k", num(e.temperature.resistance_activation_k)},
                            {"polarisation_activation_k", num(e.temperature.polarisation_activation_k)},
                            {"capacity_ah_per_c", num(e.temperature.capacity_ah_per_c)},
                            {"e0_v_per_c", num(e.temperature.e0_v_per_c)}};
    }
    if (e.thermal.enabled) {
        j["thermal"] = {{"ambient_c", num(e.thermal.ambient_c)},
                        {"thermal_resistance_k_per_w", num(e.thermal.thermal_resistance_k_per_w)},
                        {"time_constant_s", num(e.thermal.time_constant_s)}};
    }
    if (e.hysteresis.magnitude_v != 0.0f) {
        j["hysteresis"] = {{"magnitude_v", num(e.hysteresis.magnitude_v)}, {"rate_per_ah", num(e.hysteresis.rate_per_ah)}};
    }
    if (e.ocv.count >= 2) {
        json d = json::array();
        for (int k = 0; k < e.ocv.count; ++k) d.push_back(num(e.ocv.delta_v[k]));
        j["ocv_correction"] = {{"span_ah", num(e.ocv.span_ah)}, {"delta_v", d}};
    }
    const core::CurrentSensorCorrection& s = e.current_sensor;
    if (s.gain != 1.0f || s.offset_a != 0.0f || s.lead_s != 0.0f) {
        j["current_sensor"] = {{"gain", num(s.gain)}, {"offset_a", num(s.offset_a)}, {"lead_s", num(s.lead_s)}};
    }
    return j;
}

}  // namespace host
}  // namespace battsim
