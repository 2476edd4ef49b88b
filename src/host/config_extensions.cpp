#include "host/config_extensions.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace battsim {
namespace host {

namespace {

using nlohmann::json;

// Strict member reader: every key must be known, every number finite and in range.
class Members {
public:
    Members(const json& j, std::string path, const std::string& origin) : j_(j), path_(std::move(path)), origin_(origin) {
        if (!j.is_object()) fail(path_, "expected an object");
    }
    void finish() const {
        for (auto it = j_.begin(); it != j_.end(); ++it) {
            if (!used_.count(it.key())) fail(path_ + "." + it.key(), "unknown key");
        }
    }
    void number(const char* key, float& out, double lo, double hi) {
        used_.insert(key);
        auto it = j_.find(key);
        if (it == j_.end()) return;
        out = static_cast<float>(check(*it, path_ + "." + key, lo, hi));
    }
    const json* member(const char* key) {
        used_.insert(key);
        auto it = j_.find(key);
        return it == j_.end() ? nullptr : &*it;
    }
    double check(const json& v, const std::string& where, double lo, double hi) const {
        if (!v.is_number()) fail(where, "expected a number");
        const double x = v.get<double>();
        if (!std::isfinite(x) || x < lo || x > hi) {
            std::ostringstream m;
            m << "value " << x << " out of range [" << lo << ", " << hi << "]";
            fail(where, m.str());
        }
        return x;
    }
    std::string child(const char* key) const { return path_ + "." + key; }
    [[noreturn]] void fail(const std::string& where, const std::string& what) const {
        throw ConfigError(origin_ + ": " + where + ": " + what);
    }

private:
    const json& j_;
    std::string path_;
    const std::string& origin_;
    std::set<std::string> used_;
};

constexpr double kBig = 1e9;

// The shortest decimal that reads back as the same float, so configs stay readable
// (0.004, not 0.004000000189989805) and still round-trip exactly.
json num(float x) {
    char buf[32];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, static_cast<double>(x));
        const double y = std::strtod(buf, nullptr);
        if (static_cast<float>(y) == x) return json(y);
    }
    return json(static_cast<double>(x));
}

}  // namespace

core::ModelExtensions extensions_from_json(const json& j, const std::string& origin, const std::string& where) {
    core::ModelExtensions e;
    Members root(j, where, origin);
    if (const json* rc = root.member("rc_branches")) {
        const std::string p = root.child("rc_branches");
        if (!rc->is_array()) root.fail(p, "expected an array of {resistance_ohm, time_constant_s}");
        if (rc->size() > static_cast<size_t>(core::kMaxRcBranches))
            root.fail(p, "at most " + std::to_string(core::kMaxRcBranches) + " branches");
        for (size_t k = 0; k < rc->size(); ++k) {
            Members b((*rc)[k], p + "[" + std::to_string(k) + "]", origin);
            b.number("resistance_ohm", e.rc[k].resistance_ohm, 0, 100);
            b.number("time_constant_s", e.rc[k].time_constant_s, 1e-3, kBig);
            b.finish();
        }
        e.rc_count = static_cast<uint8_t>(rc->size());
    }
    if (const json* t = root.member("temperature")) {
        Members r(*t, root.child("temperature"), origin);
        e.temperature.enabled = true;
        r.number("reference_c", e.temperature.reference_c, -100, 200);
        r.number("resistance_activation_k", e.temperature.resistance_activation_k, -1e5, 1e5);
        r.number("polarisation_activation_k", e.temperature.polarisation_activation_k, -1e5, 1e5);
        r.number("capacity_ah_per_c", e.temperature.capacity_ah_per_c, -1e3, 1e3);
        r.number("e0_v_per_c", e.temperature.e0_v_per_c, -10, 10);
        r.finish();
    }
    if (const json* t = root.member("thermal")) {
        Members r(*t, root.child("thermal"), origin);
        e.thermal.enabled = true;
        r.number("ambient_c", e.thermal.ambient_c, -100, 200);
        r.number("thermal_resistance_k_per_w", e.thermal.thermal_resistance_k_per_w, 0, 1e6);
        r.number("time_constant_s", e.thermal.time_constant_s, 1e-3, kBig);
        r.finish();
    }
    if (const json* h = root.member("hysteresis")) {
        Members r(*h, root.child("hysteresis"), origin);
        r.number("magnitude_v", e.hysteresis.magnitude_v, -100, 100);
        r.number("rate_per_ah", e.hysteresis.rate_per_ah, 0, kBig);
        r.finish();
    }
    if (const json* o = root.member("ocv_correction")) {
        Members r(*o, root.child("ocv_correction"), origin);
        r.number("span_ah", e.ocv.span_ah, 1e-6, 1e4);
        const json* d = r.member("delta_v");
        const std::string p = r.child("delta_v");
        if (d == nullptr) r.fail(p, "missing: expected an array of 2 to " + std::to_string(core::kMaxOcvPoints) + " numbers");
        if (!d->is_array() || d->size() < 2 || d->size() > static_cast<size_t>(core::kMaxOcvPoints))
            r.fail(p, "expected an array of 2 to " + std::to_string(core::kMaxOcvPoints) + " numbers");
        for (size_t k = 0; k < d->size(); ++k)
            e.ocv.delta_v[k] = static_cast<float>(r.check((*d)[k], p + "[" + std::to_string(k) + "]", -100, 100));
        e.ocv.count = static_cast<uint8_t>(d->size());
        r.finish();
    }
    if (const json* s = root.member("current_sensor")) {
        Members r(*s, root.child("current_sensor"), origin);
        r.number("gain", e.current_sensor.gain, 1e-3, 1e3);
        r.number("offset_a", e.current_sensor.offset_a, -kBig, kBig);
        r.number("lead_s", e.current_sensor.lead_s, -100, 100);
        r.finish();
    }
    root.finish();
    return e;
}

bool extensions_active(const core::ModelExtensions& e) {
    return e.rc_count > 0 || e.temperature.enabled || e.thermal.enabled || e.hysteresis.magnitude_v != 0.0f ||
           e.ocv.count >= 2 || e.current_sensor.gain != 1.0f || e.current_sensor.offset_a != 0.0f ||
           e.current_sensor.lead_s != 0.0f;
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

ExtendedConfig extended_config_from_json(const json& j, const std::string& origin) {
    ExtendedConfig out;
    json base = j;
    json ext;
    if (base.is_object()) {
        auto b = base.find("battery");
        if (b != base.end() && b->is_object()) {
            auto e = b->find("extensions");
            if (e != b->end()) {
                ext = *e;
                b->erase(e);
            }
        }
    }
    out.config = config_from_json(base, origin);
    if (!ext.is_null()) out.extensions = extensions_from_json(ext, origin);
    return out;
}

ExtendedConfig load_extended_config_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ConfigError(path + ": cannot open config file");
    json j;
    try {
        j = json::parse(in);
    } catch (const json::parse_error& e) {
        throw ConfigError(path + ": not valid JSON (" + std::string(e.what()) + ")");
    }
    return extended_config_from_json(j, path);
}

json extended_config_to_json(const ExtendedConfig& c) {
    json j = config_to_json(c.config);
    if (extensions_active(c.extensions)) j["battery"]["extensions"] = extensions_to_json(c.extensions);
    return j;
}

}  // namespace host
}  // namespace battsim
