#include "host/report/config_out.h"

#include "host/report/current_offset_fix.h"

namespace battsim {
namespace host {

LoadedConfig filed_config(const LoadedConfig& run_config, const std::string& config_path, bool estimator_given) {
    LoadedConfig filed = run_config;
    if (estimator_given)
        filed.monitor.estimator = (config_path.empty() ? builtin_config() : load_config_file(config_path)).monitor.estimator;
    return filed;
}

ConfigCorrections with_corrections(const LoadedConfig& filed, const nlohmann::json& summary) {
    ConfigCorrections c;
    c.config = filed;
    // const lookups: the summary is written after this, and must not gain null keys here.
    const auto check = summary.find("charger_check");
    if (check != summary.end() && check->is_object()) {
        const auto gain = check->find("suggested_current_gain");
        if (gain != check->end() && gain->is_number()) {
            c.config.monitor.extensions.current_sensor.gain = static_cast<float>(gain->get<double>());
            c.gain_taken = true;
        }
    }
    c.offset_taken_a = correct_current_offset(summary, c.config.monitor);
    return c;
}

}  // namespace host
}  // namespace battsim
