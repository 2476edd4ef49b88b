#include "host/fit/trace.h"

#include <cmath>

#include "host/replay.h"

namespace battsim {
namespace host {
namespace fit {

std::string trace_label(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    const size_t dot = name.find_last_of('.');
    if (dot != std::string::npos && dot > 0) name = name.substr(0, dot);
    return name;
}

Trace load_trace(const std::string& path, const ReaderOptions& reader, const LoadedConfig& config) {
    Trace t;
    t.path = path;
    t.label = trace_label(path);
    t.flying_current_a = config.monitor.flying.min_flying_current_a;
    ReplayOptions options;
    options.reader = reader;
    options.config = config;
    // The trace is the measurement: replay it with the plain model, so the flight window and
    // the settling point do not depend on the extensions being fitted.
    options.config.monitor.extensions = core::ModelExtensions{};
    bool first = true;
    uint64_t t0_us = 0;
    auto observe = [&](const core::Sample& s, const core::MonitorStatus& st) {
        if (first) {
            t0_us = s.time_us;
            first = false;
        }
        TracePoint p;
        p.time_s = static_cast<double>(s.time_us - t0_us) * 1e-6;
        p.dt_s = st.dt_s;
        p.voltage_v = s.voltage_v;
        p.current_a = s.current_a;
        p.has_temperature = s.has_temperature;
        p.temperature_c = s.temperature_c;
        p.valid = st.sample_valid;
        p.flying = st.flying;
        p.initialised = st.initialised;
        p.monitor_model_v = st.model_voltage_v;
        p.monitor_consumed_mah = st.consumed_mah;
        p.monitor_filtered_a = st.filtered_current_a;
        if (p.valid && p.has_temperature && std::isfinite(p.temperature_c)) t.has_temperature = true;
        t.points.push_back(p);
    };
    const nlohmann::json summary = replay_log(path, options, observe);
    const nlohmann::json& input = summary["input"];
    t.info.path = path;
    t.info.format = parse_log_format(input["format"].get<std::string>());
    t.info.cell_count = input["cells"].get<int>();
    t.info.has_temperature = input["has_temperature"].get<bool>();
    for (const auto& note : input["notes"]) t.info.notes.push_back(note.get<std::string>());
    t.notes = log_notes(summary);
    // Replayed without the extensions (above), so the config's own temperature terms are
    // judged here.
    for (const std::string& temperature : {missing_temperature_note(config.monitor, t.has_temperature),
                                           measured_temperature_note(config.monitor, t.has_temperature)})
        if (!temperature.empty()) t.notes.push_back(temperature);
    // The summary's flight window: initialised valid samples from the first flying sample
    // to the last flying one.
    long first_flying = -1, last_flying = -1;
    for (size_t k = 0; k < t.points.size(); ++k) {
        const TracePoint& p = t.points[k];
        if (!p.valid || !p.initialised) continue;
        if (t.settle_index < 0) {
            t.settle_index = static_cast<long>(k);
            t.monitor_initial_ah = p.monitor_consumed_mah * 0.001f;
        }
        if (p.flying) {
            if (first_flying < 0) first_flying = static_cast<long>(k);
            last_flying = static_cast<long>(k);
        }
    }
    for (long k = first_flying; k >= 0 && k <= last_flying; ++k) {
        TracePoint& p = t.points[static_cast<size_t>(k)];
        p.in_flight = p.valid && p.initialised;
    }
    return t;
}

void say_notes(const std::string& command, const Trace& trace, std::ostream* out) {
    if (!out) return;
    for (const std::string& note : trace.notes) *out << command << ": note: " << trace.path << ": " << note << "\n";
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
