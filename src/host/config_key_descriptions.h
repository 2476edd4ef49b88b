// What each config key does, by its key in the reference ("joint.health_filter.enabled"),
// for config_keys.h. Kept apart from the reader so the reader stays short; a test checks the
// two name the same keys.
#pragma once
#include <map>
#include <string>

namespace battsim {
namespace host {

const std::map<std::string, std::string>& config_key_descriptions();

}  // namespace host
}  // namespace battsim
