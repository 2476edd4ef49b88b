// battsim: replay, evaluate and fit drone battery logs through the same core the
// firmware runs.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>
#include <set>
#include <string>

#include "command.h"
#include "json_errors.h"
#include "run_guarded.h"
#include "host/io/atomic_file.h"

namespace battsim {
namespace cli {
std::vector<Command>& command_registry() {
    static std::vector<Command> registry;
    return registry;
}
}  // namespace cli
}  // namespace battsim

namespace {
int run_main(int argc, char** argv) {
    using namespace battsim::cli;
    // Ctrl-C during a long replay must not leave *.tmp.PID.N files beside the outputs.
    battsim::host::install_temp_cleanup_on_signals();
    CLI::App app{"battsim: model-based drone battery monitoring, replayed and evaluated on the host"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("battsim ") + BATTSIM_VERSION);

    // Registration order depends on link order; sort so --help is stable.
    auto& commands = command_registry();
    std::sort(commands.begin(), commands.end(),
              [](const Command& a, const Command& b) { return a.name < b.name; });
    std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
    for (auto& c : commands) {
        CLI::App* sub = app.add_subcommand(c.name, c.description);
        actions.emplace_back(sub, c.setup(*sub));
    }
    // An empty value (an unset shell variable: `-o "$OUT"`) had read as the option not given,
    // so an output went unwritten with exit 0, or failed after the work with exit 5. Every
    // option that takes a value refuses it; no option means anything by "".
    const CLI::Validator non_empty(
        [](std::string& v) { return v.empty() ? std::string("expected a value, found an empty string") : std::string(); },
        "", "NON_EMPTY");
    // A whole number written as a float ("1e5", "300.0") reads as that number: CLI11's own
    // integer parsing had answered `--max-points 1e5` with "not in range 20 to 100000000".
    // A fraction is refused as one. transform() runs before the option's own range check.
    const CLI::Validator whole_number(
        [](std::string& v) {
            size_t first = v.find_first_not_of(" \t");
            if (first != std::string::npos && (v[first] == '-' || v[first] == '+')) ++first;
            if (first >= v.size() || !(std::isdigit(static_cast<unsigned char>(v[first])) || v[first] == '.'))
                return "expected a whole number, found " + v;  // CLI11 had said "not in range" of "abc"
            if (v.find_first_of(".eE") == std::string::npos) return std::string();  // digits: CLI11 reads them
            char* end = nullptr;
            const double d = std::strtod(v.c_str(), &end);
            if (end == v.c_str() || *end != '\0' || !std::isfinite(d)) return std::string();  // not a number: CLI11 says so
            if (d != std::floor(d)) return "expected a whole number, found " + v;
            if (std::fabs(d) < 9e15) v = std::to_string(static_cast<long long>(d));
            return std::string();
        },
        "", "WHOLE_NUMBER");
    const std::function<void(CLI::App*)> refuse_empty = [&](CLI::App* a) {
        for (CLI::Option* o : a->get_options()) {
            if (o->get_type_size_max() <= 0) continue;
            const std::string type = o->get_type_name();
            if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0) o->transform(whole_number);
            o->transform(non_empty);  // transform() goes first: before any range check says "not in range"
        }
        for (CLI::App* s : a->get_subcommands([](CLI::App*) { return true; })) refuse_empty(s);
    };
    refuse_empty(&app);
    // CLI11 answers a misspelt command with "A subcommand is required"; name it instead.
    if (argc > 1 && argv[1][0] != '-') {
        const std::string word = argv[1];
        const bool known = std::any_of(commands.begin(), commands.end(), [&](const Command& c) { return c.name == word; });
        if (!known) {
            std::cerr << "battsim: unknown command \"" << word << "\"; the commands are:";
            for (const Command& c : commands) std::cerr << " " << c.name;
            std::cerr << " (battsim --help)\n";
            return kExitUsage;
        }
    }
    // `--summary=$OUT` with OUT unset reads in CLI11 as the option without a value, which then
    // took the next argument (a log's name) as its own; split off the empty value so that the
    // empty-value check above refuses it.
    std::set<std::string> value_options;  // the command's options that take a value ("--output")
    if (argc > 1 && argv[1][0] != '-')
        for (const CLI::Option* o : app.get_subcommand(argv[1])->get_options())
            if (o->get_type_size_max() > 0)
                for (const std::string& name : o->get_lnames()) value_options.insert("--" + name);
    std::vector<std::string> args;
    for (int i = 0; i < argc; ++i) {
        const std::string token = argv[i];
        const bool empty_long_value = i > 0 && token.find('=') == token.size() - 1 &&
                                      value_options.count(token.substr(0, token.size() - 1)) != 0;
        if (empty_long_value && std::find(args.begin(), args.end(), "--") == args.end()) {
            args.push_back(token.substr(0, token.size() - 1));
            args.emplace_back();
        } else {
            args.push_back(token);
        }
    }
    std::vector<const char*> arg_ptrs;
    for (const std::string& s : args) arg_ptrs.push_back(s.c_str());
    try {
        app.parse(static_cast<int>(arg_ptrs.size()), arg_ptrs.data());
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e) == 0 ? kExitOk : kExitUsage;  // --help, --version
        // Named by the command, as every other message is ("battsim replay: ..."): a script
        // reading standard error had no prefix to tell a usage error by.
        std::string who = "battsim";
        for (const CLI::App* sub : app.get_subcommands()) who += " " + sub->get_name();
        std::cerr << who << ": " << e.what() << "\n(" << who << " --help)\n";
        return kExitUsage;
    }
    for (auto& a : actions) {
        if (a.first->parsed()) {
            const int code = run_guarded(a.first->get_name(), a.second, std::cerr);
            // What went to standard output (a report, "-o -", --json) is an output like a
            // file: a full disk or a closed pipe had exited 0 with the numbers lost.
            errno = 0;
            std::cout.flush();
            if (!std::cout) {
                const int err = errno;
                std::cerr << "battsim " << a.first->get_name() << ": error: writing to standard output failed"
                          << (err ? std::string(" (") + std::strerror(err) + ")" : std::string()) << "\n";
                return kExitOutputError;
            }
            return code;
        }
    }
    return kExitUsage;
}
}  // namespace

int main(int argc, char** argv) {
    using namespace battsim::cli;
    const std::vector<std::string> args(argv, argv + argc);
    if (!json_requested(args)) return run_main(argc, argv);
    // Both streams pass through as before; they are restored before returning, so nothing
    // written after main (a static's destructor) reaches a buffer that is gone.
    RecordingBuf out(std::cout.rdbuf(), 0), err(std::cerr.rdbuf(), 64 * 1024);
    std::streambuf* const cout_buf = std::cout.rdbuf(&out);
    std::streambuf* const cerr_buf = std::cerr.rdbuf(&err);
    const int code = run_main(argc, argv);
    std::cout.flush();
    std::cerr.flush();
    std::cout.rdbuf(cout_buf);
    std::cerr.rdbuf(cerr_buf);
    const std::string command = command_word(args);
    if (writes_error_object(command, code, out.bytes())) {
        std::cout << dump_error_json(error_json(command, code, err.text(), BATTSIM_VERSION, err.truncated())) << "\n";
        std::cout.flush();
    }
    return code;
}
