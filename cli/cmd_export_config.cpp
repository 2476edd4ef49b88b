// battsim export-config --firmware CFG.json -o battsim_config.h: the firmware's compiled-in
// configuration, generated from the JSON battsim itself reads.
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/export_header.h"

namespace battsim {
namespace cli {
namespace {

struct ExportArgs {
    std::string firmware;
    std::string output = "-";
    std::string estimator;  // empty = as the config says
};

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<ExportArgs>();
    sub.add_option("--firmware,-c,--config", a->firmware, "Config JSON to export as the firmware's C++ header (-c as in the other commands)")->required();
    sub.add_option("-o,--output", a->output, "Header to write (\"-\" = standard output)")->capture_default_str();
    sub.add_option("--estimator", a->estimator, "Estimator compiled in: reference or joint; default from the config")
        ->check(CLI::IsMember({"reference", "joint"}));
    return [a]() -> int {
        if (int rc = check_outputs("battsim export-config", {{"--firmware", a->firmware}}, {text_output("-o/--output", a->output)}))
            return rc;
        try {
            for (const std::string& note : host::export_firmware_config(a->firmware, a->output, a->estimator))
                std::cerr << "battsim export-config: note: " << note << "\n";
        } catch (const host::ConfigError& e) {
            std::cerr << "battsim export-config: " << e.what() << "\n";
            return kExitConfigError;
        } catch (const std::invalid_argument& e) {
            std::cerr << "battsim export-config: " << a->firmware << ": " << e.what() << "\n";
            return kExitConfigError;
        } catch (const std::runtime_error& e) {
            std::cerr << "battsim export-config: " << e.what() << "\n";
            return kExitOutputError;
        }
        return kExitOk;
    };
}

const RegisterCommand reg{{"export-config", "Write a config JSON as the firmware's battsim_config.h", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
