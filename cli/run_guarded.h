// What escapes a subcommand's action, mapped to an exit code. Header-only so the unit tests
// check the mapping without running the binary (nothing reaches it on purpose).
#pragma once
#include <exception>
#include <functional>
#include <new>
#include <ostream>
#include <string>

#include "exit_codes.h"
#include "host/config_reader.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace cli {

// Runs `action` of `command`. The commands catch the errors they expect and return their
// codes; an input or config error that still gets out keeps its documented code (3, 4), and
// memory running out is 71, and anything else is an internal error, exit 70 (it had been 1,
// batch's "some logs failed"; running out of memory had also been 70, "a bug in battsim").
inline int run_guarded(const std::string& command, const std::function<int()>& action, std::ostream& err) {
    const std::string me = "battsim " + command + ": ";
    try {
        return action();
    } catch (const host::InputError& e) {
        err << me << e.what() << "\n";
        return kExitInputError;
    } catch (const host::ConfigError& e) {
        err << me << "config: " << e.what() << "\n";
        return kExitConfigError;
    } catch (const std::bad_alloc&) {
        err << me << "out of memory (exit " << int(kExitOutOfMemory)
            << "; try fewer --jobs, a shorter log or a machine with more memory)\n";
        return kExitOutOfMemory;
    } catch (const std::exception& e) {
        err << me << "internal error: " << e.what() << " (a bug in battsim, exit " << int(kExitInternal)
            << "; please report it with the command line)\n";
        return kExitInternal;
    } catch (...) {
        err << me << "internal error: an exception of unknown type (a bug in battsim, exit " << int(kExitInternal)
            << "; please report it with the command line)\n";
        return kExitInternal;
    }
}

}  // namespace cli
}  // namespace battsim
