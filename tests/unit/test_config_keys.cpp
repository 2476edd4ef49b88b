// The config key reference (src/host/config_keys.*), read off the reader itself: complete,
// described, its defaults inside their ranges, and covering every key the committed configs
// and the writer use.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "host/config_json.h"
#include "host/config_keys.h"

using namespace battsim;
using nlohmann::json;

namespace {

std::map<std::string, host::ConfigKey> keys_by_name() {
    std::map<std::string, host::ConfigKey> out;
    for (const host::ConfigKey& k : host::config_keys()) out[k.key] = k;
    return out;
}

// Every leaf of a config JSON as the reference names it ("a.b[].c"); arrays of numbers as one key.
void leaf_keys(const json& j, const std::string& at, std::set<std::string>& out) {
    if (j.is_object()) {
        for (auto it = j.begin(); it != j.end(); ++it) leaf_keys(it.value(), at.empty() ? it.key() : at + "." + it.key(), out);
    } else if (j.is_array() && !j.empty() && j[0].is_object()) {
        out.insert(at);
        for (const json& e : j) leaf_keys(e, at + "[]", out);
    } else {
        out.insert(at);
    }
}

}  // namespace

TEST_CASE("Config keys: every key is described, and every description names a key", "[config][keys]") {
    CHECK(host::config_keys_without_description() == std::vector<std::string>{});
    CHECK(host::config_descriptions_without_key() == std::vector<std::string>{});
}

TEST_CASE("Config keys: types, defaults and ranges as the reader has them, by hand", "[config][keys]") {
    const auto keys = keys_by_name();
    REQUIRE(keys.count("joint.persistence"));
    const host::ConfigKey& p = keys.at("joint.persistence");
    CHECK(p.type == "integer");
    CHECK(p.default_value == json(3));  // three short verdicts in a row (README)
    CHECK(p.lo == 1);
    CHECK(p.hi == 1e6);
    const host::ConfigKey& hold = keys.at("telemetry.clear_hold_s");
    CHECK(hold.type == "number");
    CHECK(hold.default_value == json(5.0));
    CHECK(hold.hi == 36000);
    CHECK(keys.at("joint.health_filter.enabled").default_value == json(true));
    CHECK(keys.at("estimator").default_value == json("reference"));
    CHECK(keys.at("battery.extensions.rc_branches").type == "array of objects");
    CHECK(keys.at("battery.extensions.rc_branches[].time_constant_s").lo == 1e-3);
    CHECK(keys.at("joint.ocv_cell_voltage_v").type == "array of numbers");
    CHECK(keys.at("joint.ocv_cell_voltage_v").default_value.is_null());
    // The take-off keys are the health filter's alone.
    CHECK(keys.count("joint.health_filter.solves_from_takeoff_soc") == 1);
    CHECK(keys.count("joint.verdict_filter.solves_from_takeoff_soc") == 0);
    // A borrowed description names the key it comes from.
    CHECK(keys.at("joint.health_filter.gate_sigmas").about == "As `joint.gate_sigmas`, for this filter.");
}

TEST_CASE("Config keys: every default lies in its own range and integers are whole", "[config][keys]") {
    for (const host::ConfigKey& k : host::config_keys()) {
        if (k.type != "number" && k.type != "integer") continue;
        INFO(k.key);
        REQUIRE(k.default_value.is_number());
        const double d = k.default_value.get<double>();
        CHECK(d >= k.lo);
        CHECK(d <= k.hi);
        if (k.type == "integer") CHECK(d == std::floor(d));
    }
}

TEST_CASE("Config keys: the reference holds every key the writer writes and the committed configs use", "[config][keys]") {
    const auto keys = keys_by_name();
    std::set<std::string> used;
    leaf_keys(host::config_to_json(host::default_config()), "", used);
    const std::filesystem::path configs = std::filesystem::path(BATTSIM_SOURCE_DIR) / "configs";
    int files = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(configs)) {
        if (e.path().extension() != ".json") continue;
        std::ifstream in(e.path());
        std::stringstream text;
        text << in.rdbuf();
        const json j = json::parse(text.str(), nullptr, false);
        if (!j.is_object() || j.value("schema", "") != "battsim.config") continue;  // scenarios, manifests
        ++files;
        leaf_keys(j, "", used);
    }
    CHECK(files >= 20);
    for (const std::string& k : used) {
        INFO(k);
        CHECK(keys.count(k) == 1);
    }
}
