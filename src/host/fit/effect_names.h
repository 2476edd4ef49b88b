#pragma once
// The model's effects have a short name in `fit --add` (rc, thermal, ocv, sensor, timing)
// and a descriptive one in `residual --candidates` (rc_polarisation, self_heating, ...);
// each command takes either, so a name read in one command's report works in the other.
#include <string>

namespace battsim {
namespace host {
namespace fit {

// residual's name for a fit --add name (temperature and hysteresis are the same in both);
// any other text is returned as it is.
std::string candidate_name(const std::string& name);
// fit --add's name for a residual candidate; any other text is returned as it is.
std::string extension_name(const std::string& name);

}  // namespace fit
}  // namespace host
}  // namespace battsim
