// The config reference: every key a config JSON may hold, with its type, default, range and
// meaning, found by probing the reader itself (config_from_json), so it cannot miss a key
// or state another range than the one enforced. `battsim make-config --list-keys` prints it;
// docs/config-keys.md is that output, and a test keeps the two equal.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace battsim {
namespace host {

struct ConfigKey {
    std::string key;   // "joint.health_filter.enabled"; array elements as "[]"
    std::string type;  // "number", "integer", "boolean", "string", "array of numbers"
    nlohmann::json default_value;  // null: none (the setting is off until given)
    double lo = 0, hi = 0;         // numbers: the accepted range
    std::string about;             // what it does
};

// Every key, in the order the reader meets them (sections as they appear in a config).
std::vector<ConfigKey> config_keys();

// The keys' descriptions that name no key the reader knows, and keys without one: both
// empty when the reference is complete (a test checks).
std::vector<std::string> config_keys_without_description();
std::vector<std::string> config_descriptions_without_key();

// The reference as Markdown (docs/config-keys.md) or as JSON ({"keys": [...]}).
std::string config_keys_markdown(const std::vector<ConfigKey>& keys);
nlohmann::json config_keys_json(const std::vector<ConfigKey>& keys);

}  // namespace host
}  // namespace battsim
