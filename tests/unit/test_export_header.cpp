// battsim export-config --firmware: the generated header carries every MonitorConfig field,
// and the firmware's compiled-in floats are bit for bit the ones battsim loads from JSON.
#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

#include "battsim_config.h"
#include "host/config_json.h"
#include "host/export_header.h"
#include "test_firmware_support.h"

using namespace battsim;

namespace {

struct FieldSpan {
    std::string path;
    size_t offset = 0;
    size_t size = 0;
    size_t align = 0;
};

std::vector<FieldSpan> field_spans(const core::MonitorConfig& c) {
    std::vector<FieldSpan> spans;
    const char* base = reinterpret_cast<const char*>(&c);
    host::visit_monitor_config(c, [&](const std::string& path, const auto& member) {
        using T = std::decay_t<decltype(member)>;
        spans.push_back({path, static_cast<size_t>(reinterpret_cast<const char*>(&member) - base), sizeof(T), alignof(T)});
    });
    return spans;
}

// "" when every field of a and b has the same bytes, else the first differing path.
std::string first_difference(const core::MonitorConfig& a, const core::MonitorConfig& b) {
    const char* pa = reinterpret_cast<const char*>(&a);
    const char* pb = reinterpret_cast<const char*>(&b);
    for (const FieldSpan& f : field_spans(a)) {
        if (std::memcmp(pa + f.offset, pb + f.offset, f.size) != 0) return f.path;
    }
    return std::string();
}

}  // namespace

TEST_CASE("export: float literals read back as the same float", "[export]") {
    std::mt19937 rng(3);
    int tested = 0;
    for (int i = 0; i < 200000; ++i) {
        const uint32_t bits = static_cast<uint32_t>(rng());
        float v;
        std::memcpy(&v, &bits, sizeof v);
        if (!std::isfinite(v)) continue;
        const std::string lit = host::float_literal(v);
        REQUIRE(lit.back() == 'f');
        const float back = std::strtof(lit.substr(0, lit.size() - 1).c_str(), nullptr);
        INFO(lit);
        REQUIRE(fwtest::same_bits(back, v));
        ++tested;
    }
    CHECK(tested > 190000);
    CHECK(host::float_literal(30.0f) == "30.0f");
    CHECK(host::float_literal(1.55f) == "1.55f");
    CHECK(host::float_literal(-0.0f) == "-0.0f");
    CHECK(host::float_literal(-982.8158579f) == "-982.81586f");
    CHECK(host::float_literal(1.1920929e-7f) == "1.1920929e-07f");
    CHECK_THROWS_AS(host::float_literal(std::numeric_limits<float>::quiet_NaN()), std::invalid_argument);
    CHECK_THROWS_AS(host::float_literal(std::numeric_limits<float>::infinity()), std::invalid_argument);
}

TEST_CASE("export: the field list covers every byte of MonitorConfig but padding", "[export]") {
    core::MonitorConfig c;
    std::vector<FieldSpan> spans = field_spans(c);
    std::sort(spans.begin(), spans.end(), [](const FieldSpan& a, const FieldSpan& b) { return a.offset < b.offset; });
    size_t covered_to = 0;
    for (const FieldSpan& f : spans) {
        INFO(f.path << " at byte " << f.offset);
        REQUIRE(f.offset >= covered_to);  // listed twice or overlapping: a wrong path
        // A gap is padding only if it is shorter than this member's alignment and ends where
        // alignment puts the member; anything wider is a field missing from the list.
        const size_t gap = f.offset - covered_to;
        INFO("bytes " << covered_to << ".." << f.offset << " of MonitorConfig are in no listed field: add the new "
                      "field to visit_monitor_config() in src/host/export_header.h");
        REQUIRE(gap < f.align);
        covered_to = f.offset + f.size;
    }
    INFO("MonitorConfig ends with unlisted bytes " << covered_to << ".." << sizeof(core::MonitorConfig)
                                                   << ": add the new field to visit_monitor_config()");
    REQUIRE(sizeof(core::MonitorConfig) - covered_to < alignof(core::MonitorConfig));
}

TEST_CASE("export: the firmware's compiled-in config equals the JSON battsim loads, bit for bit", "[export][firmware]") {
    // constexpr: the firmware can keep it in flash and build it at compile time.
    constexpr core::MonitorConfig compiled = battsim_generated::monitor_config();
    const host::LoadedConfig loaded = host::load_config_file(fwtest::reference_config_path());
    CHECK(first_difference(compiled, loaded.monitor).empty());
    CHECK(std::string(battsim_generated::kConfigName) == loaded.name);
    // The loaded config is not just the defaults, so the comparison has teeth.
    CHECK_FALSE(first_difference(core::MonitorConfig{}, loaded.monitor).empty());
    // The telemetry's settings come from the same JSON.
    constexpr telemetry::TelemetryConfig t = battsim_generated::telemetry_config();
    CHECK(t.system_id == loaded.telemetry.system_id);
    CHECK(t.component_id == loaded.telemetry.component_id);
    CHECK(t.battery_id == loaded.telemetry.battery_id);
    CHECK(t.interval_s == loaded.telemetry.interval_s);
    CHECK(t.low_time_s == loaded.telemetry.low_time_s);
    CHECK(t.critical_time_s == loaded.telemetry.critical_time_s);
    CHECK(t.text_repeat_s == loaded.telemetry.text_repeat_s);
    CHECK(t.clear_hold_s == loaded.telemetry.clear_hold_s);
}

TEST_CASE("export: every number the JSON can set reaches the header", "[export]") {
    host::LoadedConfig base = host::load_config_file(fwtest::reference_config_path());
    base.telemetry.system_id = 3;  // a telemetry section in the JSON, so its keys are perturbed too
    const nlohmann::json j = host::config_to_json(base);
    REQUIRE(j.contains("telemetry"));
    const std::string base_header = host::firmware_config_header(base, "x.json");

    // Every numeric leaf, by JSON pointer.
    std::vector<nlohmann::json::json_pointer> leaves;
    const nlohmann::json flat = j.flatten();
    for (auto it = flat.begin(); it != flat.end(); ++it) {
        if (it->is_number() && it.key() != "/version") leaves.emplace_back(it.key());  // the schema's, not a setting
    }
    REQUIRE(leaves.size() > 30);
    size_t changed = 0;
    for (const auto& ptr : leaves) {
        const double v = j.at(ptr).get<double>();
        bool loaded_one = false;
        for (double nv : {v * 1.013 + 0.0007, v * 0.987 - 0.0007, v + 1.0, v - 1.0, v * 2.0, v * 0.5}) {
            if (j.at(ptr).is_number_integer()) nv = std::round(nv);
            if (nv == v) continue;
            nlohmann::json k = j;
            k[ptr] = j.at(ptr).is_number_integer() ? nlohmann::json(static_cast<long long>(nv)) : nlohmann::json(nv);
            host::LoadedConfig changed_config;
            try {
                changed_config = host::config_from_json(k, "perturbed");
            } catch (const host::ConfigError&) {
                continue;  // out of that key's range: try another value
            }
            loaded_one = true;
            INFO("JSON " << ptr.to_string() << " changed from " << v << " to " << nv);
            REQUIRE(host::firmware_config_header(changed_config, "x.json") != base_header);
            ++changed;
            break;
        }
        if (!loaded_one) WARN("no accepted perturbation for " << ptr.to_string());
    }
    CHECK(changed == leaves.size());
}

TEST_CASE("battsim export-config writes the header and reports bad input", "[export][cli]") {
    const std::string dir = fwtest::temp_dir("export");
    const std::string out = dir + "/battsim_config.h";
    fwtest::Run r = fwtest::run(BATTSIM_BINARY, "export-config --firmware " + fwtest::q(fwtest::reference_config_path()) +
                                                    " -o " + fwtest::q(out));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const std::string header = fwtest::read_file(out);
    CHECK(header == host::firmware_config_header(host::load_config_file(fwtest::reference_config_path()),
                                                 "reference-modified.json"));
    CHECK(header.find("constexpr battsim::core::MonitorConfig monitor_config()") != std::string::npos);
    CHECK(header.find("    c.shunt.offset_ma = -982.81586f;\n") != std::string::npos);
    CHECK(header.find("    c.power_average.initial_value = 316.0f;\n") != std::string::npos);

    // Same bytes again: determinism.
    r = fwtest::run(BATTSIM_BINARY, "export-config --firmware " + fwtest::q(fwtest::reference_config_path()));
    CHECK(r.exit_code == 0);
    CHECK(r.out == header);

    const std::string bad = dir + "/bad.json";
    fwtest::write_file(bad, "{\"schema\": \"battsim.config\", \"version\": 1, \"battery\": {\"capacity_ah\": \"big\"}}");
    r = fwtest::run(BATTSIM_BINARY, "export-config --firmware " + fwtest::q(bad) + " -o " + fwtest::q(dir + "/x.h"));
    CHECK(r.exit_code == 4);
    CHECK(r.err.find("capacity_ah") != std::string::npos);
    CHECK(fwtest::read_file(dir + "/x.h").empty());

    r = fwtest::run(BATTSIM_BINARY, "export-config --firmware " + fwtest::q(fwtest::reference_config_path()) + " -o " +
                                        fwtest::q(dir + "/no/such/dir/x.h"));
    CHECK(r.exit_code == 5);
    r = fwtest::run(BATTSIM_BINARY, "export-config -o " + fwtest::q(out));
    CHECK(r.exit_code == 2);

    // --estimator overrides the config's (the reference config says reference), and says so.
    r = fwtest::run(BATTSIM_BINARY, "export-config --firmware " + fwtest::q(fwtest::reference_config_path()) +
                                        " --estimator joint");
    REQUIRE(r.exit_code == 0);
    host::LoadedConfig joint = host::load_config_file(fwtest::reference_config_path());
    REQUIRE(joint.monitor.estimator == core::EstimatorKind::Reference);
    joint.monitor.estimator = core::EstimatorKind::Joint;
    CHECK(r.out == host::firmware_config_header(joint, "reference-modified.json with --estimator joint"));
    r = fwtest::run(BATTSIM_BINARY, "export-config --firmware " + fwtest::q(fwtest::reference_config_path()) +
                                        " --estimator kalman");
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("--estimator") != std::string::npos);
}
