// A short simulated flight built in code for the simulator tests: the monitor config is
// embedded (no files), `base` gives the name, seed and profile, `extra_json` is merged on top.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "host/config_json.h"
#include "host/sim/scenario.h"

namespace simtest {

inline battsim::host::sim::Scenario code_scenario(const std::string& base, const std::string& extra_json) {
    using nlohmann::json;
    json j = json::parse(base);
    j.merge_patch(json::parse(extra_json));
    json cfg = battsim::host::config_to_json(battsim::host::default_config());
    if (j["pack"]["cells"] != 4) {  // the embedded config is the 4S reference pack
        cfg["battery"]["cells_in_series"] = j["pack"]["cells"];
        cfg["sensor"]["max_pack_voltage_v"] = 40.0;
    }
    return battsim::host::sim::scenario_from_json(j, j["name"].get<std::string>() + ".json", "", &cfg);
}

}  // namespace simtest
