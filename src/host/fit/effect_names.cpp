#include "host/fit/effect_names.h"

namespace battsim {
namespace host {
namespace fit {

namespace {
struct EffectName {
    const char* extension;  // fit --add
    const char* candidate;  // residual --candidates
};
const EffectName kNames[] = {
    {"rc", "rc_polarisation"}, {"temperature", "temperature"}, {"thermal", "self_heating"},
    {"ocv", "soc_shape"},      {"sensor", "current_sensor"},   {"hysteresis", "hysteresis"},
    {"timing", "sample_timing"},
};
}  // namespace

std::string candidate_name(const std::string& name) {
    for (const EffectName& e : kNames)
        if (name == e.extension) return e.candidate;
    return name;
}

std::string extension_name(const std::string& name) {
    for (const EffectName& e : kNames)
        if (name == e.candidate) return e.extension;
    return name;
}

}  // namespace fit
}  // namespace host
}  // namespace battsim
