// Exit codes shared by every subcommand (documented in the README's "Exit codes" table).
// Apart from command.h so that a test can check the mapping without CLI11.
#pragma once

namespace battsim {
namespace cli {

enum ExitCode : int {
    kExitOk = 0,
    kExitFailure = 1,      // the job ran but found failures (batch rows failed, regressions)
    kExitUsage = 2,        // bad command line
    kExitInputError = 3,   // unreadable or malformed input file
    kExitConfigError = 4,  // bad configuration file
    kExitOutputError = 5,  // could not write an output
    // An error no command expected: a bug in battsim, not in the run's inputs. Its own code
    // (sysexits' EX_SOFTWARE) so a pipeline never takes it for "some logs failed" (1).
    kExitInternal = 70,
    // Memory ran out (std::bad_alloc): the machine's limit, not a bug nor a bad input; a
    // pipeline may retry with fewer --jobs or on a bigger machine (sysexits' EX_OSERR).
    kExitOutOfMemory = 71,
};

}  // namespace cli
}  // namespace battsim
