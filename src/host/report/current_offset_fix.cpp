#include "host/report/current_offset_fix.h"

#include <algorithm>
#include <string>

namespace battsim {
namespace host {

double correct_current_offset(const nlohmann::json& summary, core::MonitorConfig& config) {
    for (const nlohmann::json& w : summary.value("warnings", nlohmann::json::array())) {
        if (w.value("name", std::string()) != "sensor_fault" || !w.contains("current_offset_a")) continue;
        const auto causes = w.value("cause", nlohmann::json::array());
        if (std::find(causes.begin(), causes.end(), "current_offset") == causes.end()) continue;
        const double learnt_a = w["current_offset_a"].get<double>();
        config.extensions.current_sensor.offset_a -= static_cast<float>(learnt_a);
        return learnt_a;
    }
    return 0.0;
}

}  // namespace host
}  // namespace battsim
