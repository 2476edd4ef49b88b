// battsim merge TABLE.json…: join the JSON tables of `batch --shard` runs into the table
// one unsharded run would have written.
#include <iostream>

#include "command.h"
#include "common_options.h"
#include "host/batch/table.h"
#include "host/io/atomic_file.h"
#include "host/io/sample_reader.h"

namespace battsim {
namespace cli {
namespace {

struct MergeArgs {
    std::vector<std::string> tables;
    std::string format = "md";
    std::string output = "-";
    bool output_given = false;
    std::string packs;
    std::string monitors;
};

int run(const MergeArgs& a) {
    const char* me = "battsim merge: ";
    host::TableFormat format;
    try {
        format = host::parse_table_format(a.format);
    } catch (const std::invalid_argument& e) {
        std::cerr << me << e.what() << "\n";
        return kExitUsage;
    }
    // Each table is read whole from its file (standard input would hold only one, and "-"
    // had read as a missing file named "-").
    for (const std::string& path : a.tables)
        if (path == "-") {
            std::cerr << me << "the tables are read from files, not standard input: give each shard's path\n";
            return kExitUsage;
        }
    std::vector<host::NamedPath> inputs;
    add_named(inputs, "a table", a.tables);
    if (int rc = check_outputs("battsim merge", inputs,
                               {text_output(a.output_given ? "-o/--output" : "the table (standard output without -o)", a.output),
                                text_output("--packs", a.packs),
                                text_output("--monitors", a.monitors)}))
        return rc;
    nlohmann::json merged;
    try {
        std::vector<nlohmann::json> tables;
        for (const std::string& path : a.tables) tables.push_back(host::read_table_file(path));
        merged = host::merge_tables(tables, a.tables);
    } catch (const host::InputError& e) {
        std::cerr << me << e.what() << "\n";
        return kExitInputError;
    }
    try {
        host::write_file_atomic(a.output, host::render_table(merged, format));
        if (!a.packs.empty()) host::write_file_atomic(a.packs, host::render_packs(merged, format));
        if (!a.monitors.empty()) host::write_file_atomic(a.monitors, host::render_monitors(merged, format));
    } catch (const std::runtime_error& e) {
        std::cerr << me << e.what() << "\n";
        return kExitOutputError;
    }
    // Same exit status as the single run: failed rows stay failures after a merge.
    const size_t failed = host::failed_rows(merged);
    if (failed > 0) std::cerr << me << failed << " of " << merged["rows"].size() << " logs failed\n";
    return failed > 0 ? kExitFailure : kExitOk;
}

std::function<int()> setup(CLI::App& sub) {
    auto a = std::make_shared<MergeArgs>();
    sub.add_option("TABLES", a->tables, "Tables written by `battsim batch --shard K/N --format json`")->required();
    sub.add_option("--format", a->format, "Output format: md, csv or json")->capture_default_str();
    auto* output = sub.add_option("-o,--output", a->output, "Write the table here (atomically) instead of standard output");
    sub.add_option("--packs", a->packs, "Also write the per-pack table here, in --format (\"-\" = standard output)");
    sub.add_option("--monitors", a->monitors, "Also write the per-monitor table here, in --format (\"-\" = standard output)");
    return [a, output]() {
        a->output_given = output->count() > 0;
        return run(*a);
    };
}

const RegisterCommand reg{{"merge", "Join shard tables of `battsim batch` into the table of one run", setup}};

}  // namespace
}  // namespace cli
}  // namespace battsim
