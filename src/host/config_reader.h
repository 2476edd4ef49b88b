// The strict JSON object reader behind every config section: each member read is
// remembered, so that leftovers are reported as unknown keys when the reader goes out of
// scope (a typo never silently falls back to a default), and every number must be finite
// and in range. Messages name the file and the JSON path, "cfg.json: $.battery.x: ...";
// load_config_file() adds the line and column, "cfg.json:7:20: $.battery.x: ...".
#pragma once
#include <cmath>
#include <exception>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/io/json_text.h"

namespace battsim {
namespace host {

class ConfigError : public JsonValueError {
public:
    using JsonValueError::JsonValueError;
};

// Every setting a reader meets, for the key reference (config_keys.h): collected only while
// a recorder is installed (the probe), so reading a config costs nothing extra.
struct ConfigKeyRecord {
    std::string path;  // as in messages: "$.joint.health_filter.enabled"
    std::string type;  // "number", "integer", "boolean", "string", or "member" (an object or array)
    nlohmann::json default_value;
    double lo = 0, hi = 0;
};
inline std::vector<ConfigKeyRecord>*& config_key_recorder() {
    static thread_local std::vector<ConfigKeyRecord>* recorder = nullptr;
    return recorder;
}

// The shortest decimal that reads back as the same float, so written configs stay readable
// (0.004, not 0.004000000189989805) and still round-trip exactly.
nlohmann::json config_number(float x);

class ConfigObjectReader {
public:
    ConfigObjectReader(const nlohmann::json& j, std::string path, const std::string& origin)
        : j_(j), path_(std::move(path)), origin_(origin) {
        if (!j.is_object()) fail(path_, "expected an object");
    }
    ConfigObjectReader(const ConfigObjectReader&) = delete;
    ConfigObjectReader& operator=(const ConfigObjectReader&) = delete;
    // Unknown keys are found when the section has been read; not while another error unwinds.
    ~ConfigObjectReader() noexcept(false) {
        if (std::uncaught_exceptions() > 0) return;
        for (auto it = j_.begin(); it != j_.end(); ++it) {
            if (!used_.count(it.key())) fail(path_ + "." + it.key(), "unknown key", true);
        }
    }
    // A missing member keeps `out` (the default).
    template <typename T>
    void number(const char* key, T& out, double lo, double hi) {
        if (std::is_integral<T>::value) {
            record(key, "integer", nlohmann::json(static_cast<long long>(out)), lo, hi);
        } else {
            record(key, "number", config_number(static_cast<float>(out)), lo, hi);
        }
        if (const nlohmann::json* v = find(key)) {
            const double x = check(*v, child(key), lo, hi);
            // An integer setting given 2.5 had been read as 2 without a word.
            if (std::is_integral<T>::value && x != std::floor(x)) fail(child(key), "expected a whole number, found " + json_brief(*v));
            out = static_cast<T>(x);
        }
    }
    void string(const char* key, std::string& out) {
        record(key, "string", nlohmann::json(out), 0, 0);
        if (const nlohmann::json* v = find(key)) {
            if (!v->is_string()) fail(child(key), "expected a string");
            out = v->get<std::string>();
        }
    }
    void boolean(const char* key, bool& out) {
        record(key, "boolean", nlohmann::json(out), 0, 0);
        if (const nlohmann::json* v = find(key)) {
            if (!v->is_boolean()) fail(child(key), "expected true or false");
            out = v->get<bool>();
        }
    }
    // The member (an object or array read by the caller), or nullptr when absent; marked as
    // known either way.
    const nlohmann::json* member(const char* key) {
        record(key, "member", nullptr, 0, 0);
        return find(key);
    }
    // A number anywhere below this object (array elements), checked like number().
    double check(const nlohmann::json& v, const std::string& where, double lo, double hi) const {
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
    const std::string& origin() const { return origin_; }
    [[noreturn]] void fail(const std::string& where, const std::string& what, bool at_key = false) const {
        throw ConfigError(origin_, where, what, at_key);
    }

private:
    const nlohmann::json* find(const char* key) {
        used_.insert(key);
        auto it = j_.find(key);
        return it == j_.end() ? nullptr : &*it;
    }
    void record(const char* key, const char* type, nlohmann::json default_value, double lo, double hi) const {
        if (std::vector<ConfigKeyRecord>* r = config_key_recorder())
            r->push_back(ConfigKeyRecord{child(key), type, std::move(default_value), lo, hi});
    }

    const nlohmann::json& j_;
    std::string path_;
    const std::string& origin_;
    std::set<std::string> used_;
};

}  // namespace host
}  // namespace battsim
