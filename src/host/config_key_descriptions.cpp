#include "host/config_key_descriptions.h"

namespace battsim {
namespace host {

const std::map<std::string, std::string>& config_key_descriptions() {
    static const std::map<std::string, std::string> about = {
    };
    return about;
}

}  // namespace host
}  // namespace battsim
