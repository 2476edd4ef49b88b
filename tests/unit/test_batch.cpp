// The batch library: input expansion and order, shards, manifests (JSON and CSV, with
// their error messages), the table and its pack trends, merge, golden comparison, and
// the thread pool's determinism. Logs are small synthetic raw logs in a temp dir.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "host/stats.h"
#include "host/batch/batch.h"
#include "host/batch/inputs.h"
#include "host/batch/manifest.h"
#include "host/batch/table.h"
#include "host/config_json.h"
#include "raw_logs.h"
#include "test_files.h"

using namespace battsim::host;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using TempDir = testsupport::TempDir;

using testsupport::raw_flight;

std::vector<std::string> paths_of(const std::vector<ExpandedPath>& v) {
    std::vector<std::string> out;
    for (const auto& e : v) out.push_back(fs::path(e.path).filename().string());
    return out;
}

// Message of the InputError `f` throws, "" if none.
template <typename F>
std::string input_error(F f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Inputs and shards

TEST_CASE("natural order puts flight 9 before flight 10 and is total", "[batch]") {
    CHECK(natural_less("9.csv", "10.csv"));
    CHECK_FALSE(natural_less("10.csv", "9.csv"));
    CHECK(natural_less("a2b", "a10a"));
    CHECK(natural_less("x.csv", "y.csv"));
    CHECK(natural_less("1.csv", "1.json"));
    // Equal numbers spelt differently still order one way only.
    CHECK(natural_less("01.csv", "1.csv") != natural_less("1.csv", "01.csv"));
    CHECK_FALSE(natural_less("5.csv", "5.csv"));
}

TEST_CASE("directories, patterns and files expand in a fixed order", "[batch]") {
    TempDir t;
    for (const char* n : {"10.csv", "9.csv", "100.csv", ".hidden.csv", "notes.txt"}) t.write(n, "x");
    t.write("sub/1.csv", "x");
    const auto dir = expand_inputs({t.path()});
    // Files only (not the sub-directory), hidden skipped, digits as numbers.
    CHECK(paths_of(dir) == std::vector<std::string>{"9.csv", "10.csv", "100.csv", "notes.txt"});
    for (const auto& e : dir) CHECK(e.error.empty());

    const auto glob = expand_inputs({t.path() + "/*.csv", t.path("sub/1.csv")});
    CHECK(paths_of(glob) == std::vector<std::string>{"9.csv", "10.csv", "100.csv", "1.csv"});
    // A file met twice, however spelt or reached, is refused: it would count twice.
    CHECK_THROWS_WITH(expand_inputs({t.path() + "/*.csv", t.path("sub/../9.csv")}),
                      "\"" + t.path("sub/../9.csv") + "\" names the same log as \"" + t.path("9.csv") + "\" (from \"" +
                          t.path() + "/*.csv\"); list each log once (twice, it would count twice in the per-pack and "
                                     "per-monitor tables)");
    fs::create_symlink(t.path("10.csv"), t.path("link.csv"));
    CHECK_THROWS_AS(expand_inputs({t.path("10.csv"), t.path("link.csv")}), std::invalid_argument);
    CHECK_THROWS_AS(expand_inputs({t.path("gone.csv"), t.path("sub/../gone.csv")}), std::invalid_argument);

    const auto none = expand_inputs({t.path() + "/*.bin", t.path("missing.csv")});
    REQUIRE(none.size() == 2);
    CHECK(none[0].error == "pattern matches no file");
    CHECK(none[1].error.empty());  // a missing file is the replay's to report
    TempDir empty;
    CHECK(expand_inputs({empty.path()})[0].error == "directory holds no log files");
}

TEST_CASE("a directory or pattern leaves out battsim's own outputs: summaries, tables and the command's files",
          "[batch]") {
    // `batch DIR --out DIR -o DIR/t.csv` had read its own 9.json and t.csv as logs the second night.
    TempDir t;
    for (const char* n : {"9.csv", "10.bin", "9.json", "fleet.MD", "x.truth.json", "t.csv"}) t.write(n, "x");
    const auto dir = expand_inputs({t.path()}, {t.path("t.csv"), "-", ""});
    CHECK(paths_of(dir) == std::vector<std::string>{"9.csv", "10.bin"});
    CHECK(paths_of(expand_inputs({t.path() + "/*"}, {t.path("t.csv")})) == std::vector<std::string>{"9.csv", "10.bin"});
    // Asked for by name or by a pattern of their own, they are read (and the replay says what they are).
    CHECK(paths_of(expand_inputs({t.path() + "/*.json"})) == std::vector<std::string>{"9.json", "x.truth.json"});
    CHECK(paths_of(expand_inputs({t.path("t.csv")}, {t.path("t.csv")})) == std::vector<std::string>{"t.csv"});
    TempDir only;
    only.write("30.json", "{}");
    CHECK(expand_inputs({only.path()})[0].error == "directory holds no log files");
}

TEST_CASE("shards partition the inputs by index modulo N", "[batch]") {
    const ShardSpec s = parse_shard("2/3");
    CHECK(s.index == 2);
    CHECK(s.count == 3);
    CHECK(to_string(s) == "2/3");
    for (size_t n : {1u, 2u, 7u, 10u}) {
        for (size_t i = 0; i < n; ++i) {
            int owners = 0;
            for (size_t k = 1; k <= 3; ++k) owners += parse_shard(std::to_string(k) + "/3").contains(i);
            CHECK(owners == 1);
        }
    }
    CHECK(s.contains(1));
    CHECK(s.contains(4));
    CHECK_FALSE(s.contains(0));
    CHECK(ShardSpec().contains(12345));
    for (const char* bad : {"0/3", "4/3", "3", "a/b", "1/0", "-1/2", "1/2/3", ""})
        CHECK_THROWS_WITH(parse_shard(bad), Catch::Contains("expected K/N"));
}

TEST_CASE("manifest paths expand ${VAR} and ${VAR:-default}", "[batch]") {
    ::setenv("BATTSIM_TEST_VAR", "/data", 1);
    ::unsetenv("BATTSIM_TEST_UNSET");
    CHECK(expand_variables("${BATTSIM_TEST_VAR}/a.csv") == "/data/a.csv");
    CHECK(expand_variables("${BATTSIM_TEST_UNSET:-../x}/a.csv") == "../x/a.csv");
    CHECK(expand_variables("${BATTSIM_TEST_VAR:-../x}/a.csv") == "/data/a.csv");
    CHECK(expand_variables("plain") == "plain");
    CHECK_THROWS_WITH(expand_variables("${BATTSIM_TEST_UNSET}/a"), Catch::Contains("BATTSIM_TEST_UNSET is not set"));
    CHECK_THROWS_WITH(expand_variables("${OPEN"), Catch::Contains("expected '}'"));
    // A relative value leading a path is the working directory's, as for the shell that set
    // it; within a path it is left as it is.
    ::setenv("BATTSIM_TEST_VAR", "../data", 1);
    CHECK(expand_variables("${BATTSIM_TEST_VAR}/a.csv") ==
          (std::filesystem::current_path() / "../data").lexically_normal().string() + "/a.csv");
    CHECK(expand_variables("x/${BATTSIM_TEST_VAR}") == "x/../data");
    CHECK(expand_variables("${BATTSIM_TEST_UNSET:-../x}/a.csv") == "../x/a.csv");  // the manifest's, as before
    ::unsetenv("BATTSIM_TEST_VAR");
}

// ---------------------------------------------------------------------------------------
// Manifests

TEST_CASE("JSON manifest: defaults, entries and relative paths", "[batch]") {
    TempDir t;
    const std::string m = t.write("m/fleet.json", R"({
  "schema": "battsim.manifest", "version": 1,
  "base_dir": "../logs",
  "defaults": {"config": "cfg.json", "pack": "A", "monitor": "quad-1", "format": "csv",
               "columns": {"time": "t", "time_unit": "ms", "voltage": "v", "current": "i", "current_unit": "mA"}},
  "logs": [
    {"path": "1.csv", "test": 7, "no_temperature": true},
    {"path": "/abs/2.csv", "pack": "B", "monitor": 2, "columns": {"current": "amps", "current_unit": "A", "cells": ["c1", "c2"],
                                                    "negative_is_discharge": true}}
  ]
})");
    const Manifest man = load_manifest(m);
    REQUIRE(man.logs.size() == 2);
    CHECK(man.logs[0].path == t.path("logs/1.csv"));
    CHECK(man.logs[0].line == 7);
    CHECK(man.logs[1].path == "/abs/2.csv");
    CHECK(*man.defaults.config == t.path("m/cfg.json"));  // configs: relative to the manifest
    CHECK(*man.logs[0].settings.test == "7");
    LogSettings s = man.defaults;
    s.overlay(man.logs[1].settings);
    const ReaderOptions r = s.reader_options();
    CHECK(*s.pack == "B");
    CHECK(*s.monitor == "2");  // whole numbers are labels too
    CHECK(*man.defaults.monitor == "quad-1");
    CHECK(r.format == LogFormat::Csv);
    CHECK(r.columns.time == "t");
    CHECK(r.columns.time_scale_to_s == 1e-3);
    CHECK(r.columns.current == "amps");
    CHECK(r.columns.current_scale_to_a == 1.0);
    CHECK(r.columns.cells == std::vector<std::string>{"c1", "c2"});
    CHECK(r.columns.current_negative_is_discharge);
    CHECK_FALSE(r.ignore_temperature);
    LogSettings first = man.defaults;
    first.overlay(man.logs[0].settings);
    CHECK(first.reader_options().ignore_temperature);
}

TEST_CASE("JSON manifest errors name the line, column and what was expected", "[batch]") {
    TempDir t;
    auto err = [&](const std::string& text) {
        const std::string p = t.write("bad.json", text);
        return input_error([&] { load_manifest(p); });
    };
    const std::string p = t.path("bad.json");
    CHECK(err("{\n  \"schema\": \"battsim.manifest\",\n  \"logs\": [\n    {\"path\": \"a.csv\", \"pak\": \"A\"}\n  ]\n}") ==
          p + ":4:23: $.logs[0].pak: unknown key; expected one of average_ms, charged_mah, columns, config, current_source, estimator, format, monitor, no_temperature, pack, path, test");
    CHECK(err("{\"schema\": \"battsim.manifest\",\n \"logs\": [{\"path\": 3}]}") ==
          p + ":2:20: $.logs[0].path: expected a string, found 3");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": [{\"test\": \"x\"}]}") ==
          p + ":1:41: $.logs[0]: expected a \"path\" key naming the log");
    CHECK(err("{\"schema\": \"battsim.manifest\",\n\"logs\": [{\"path\": \"a\", \"format\": \"xls\"}]}") ==
          p + ":2:34: $.logs[0].format: unknown log format \"xls\"; expected one of auto, raw, csv, dataflash-text, "
              "dataflash-bin, ulog");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"a\", \"columns\": {\"time_unit\": \"h\"}}]}") ==
          p + ":1:80: $.logs[0].columns.time_unit: unknown time unit \"h\"; expected s, ms or us");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": []}") == p + ":1:40: $.logs: expected at least one log entry");
    CHECK(err("{\"schema\": \"battsim.config\", \"logs\": []}") ==
          p + ":1:12: $.schema: expected \"battsim.manifest\", found \"battsim.config\"");
    CHECK(err("{\n  \"schema\": \"battsim.manifest\",\n  \"logs\": [\n    {\"path\": \"a.csv\",}\n  ]\n}") ==
          p + ":4:22: not valid JSON: syntax error while parsing object key - unexpected '}'; expected string literal");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"${BATTSIM_TEST_NOT_SET_EVER}/a\"}]}")
              .find("BATTSIM_TEST_NOT_SET_EVER is not set") != std::string::npos);
    CHECK(input_error([&] { load_manifest(t.path("nope.json")); }) == t.path("nope.json") + ": cannot open manifest: no such file");
    // A stray closer used to stall the position scanner (an endless loop before the message).
    CHECK(err("[}") == p + ":1:2: not valid JSON: syntax error while parsing value - unexpected '}'; expected '[', '{', or a literal");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"version\": 1e400}") == p + ":1:43: not valid JSON: number 1e400 is beyond a double's range");
    // The charger's count: a positive number, on a log's entry only (not in the defaults).
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"a\", \"charged_mah\": -3}]}") ==
          p + ":1:70: $.logs[0].charged_mah: expected a positive number of mAh, found -3");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"defaults\": {\"charged_mah\": 900}, \"logs\": [{\"path\": \"a\"}]}")
              .find("$.defaults.charged_mah: \"charged_mah\" belongs to one log: give it in that log's entry") !=
          std::string::npos);
    // So does a test label (it had labelled every row alike).
    CHECK(err("{\"schema\": \"battsim.manifest\", \"defaults\": {\"test\": \"T\"}, \"logs\": [{\"path\": \"a\"}]}")
              .find("$.defaults.test: \"test\" belongs to one log") != std::string::npos);
    const std::string ok = t.write("ok.json", "{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"a\", \"charged_mah\": 912.5}]}");
    CHECK(*load_manifest(ok).logs[0].settings.charged_mah == 912.5);
    // The averaging window (blackbox logs): in the defaults or per log, in ms.
    const std::string avg = t.write("avg.json", "{\"schema\": \"battsim.manifest\", \"defaults\": {\"average_ms\": 10}, "
                                                "\"logs\": [{\"path\": \"a\"}, {\"path\": \"b\", \"average_ms\": 2.5}]}");
    const Manifest am = load_manifest(avg);
    CHECK(am.defaults.reader_options().average_us == 10000u);
    LogSettings b = am.defaults;
    b.overlay(am.logs[1].settings);
    CHECK(b.reader_options().average_us == 2500u);
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"a\", \"average_ms\": 0}]}") ==
          p + ":1:69: $.logs[0].average_ms: expected an averaging window of 0.001 to 60000 ms, found 0");
    CHECK(err("{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"a\", \"average_ms\": \"9\"}]}") ==
          p + ":1:69: $.logs[0].average_ms: expected a number of ms, found \"9\"");
}

TEST_CASE("CSV manifest: header, comments, quoting and errors with line and field", "[batch]") {
    TempDir t;
    const std::string m = t.write("fleet.csv",
                                  "# pack assignments\n"
                                  "path,pack,test,time_col,time_unit,current_unit,cell_cols,negative_discharge\n"
                                  "a.csv,A,,\"my time\",ms,mA,c1;c2;c3,yes\n"
                                  "\n"
                                  "/x/b.csv, B ,\"flight \"\"b\"\"\",,,,,\n");
    const Manifest man = load_manifest(m);
    REQUIRE(man.logs.size() == 2);
    CHECK(man.logs[0].path == t.path("a.csv"));
    CHECK(man.logs[0].line == 3);
    CHECK(*man.logs[0].settings.pack == "A");
    CHECK_FALSE(man.logs[0].settings.test.has_value());  // empty field = inherit
    CHECK(*man.logs[0].settings.time_col == "my time");
    CHECK(*man.logs[0].settings.time_scale_to_s == 1e-3);
    CHECK(*man.logs[0].settings.cell_cols == std::vector<std::string>{"c1", "c2", "c3"});
    CHECK(*man.logs[0].settings.negative_discharge);
    CHECK(*man.logs[1].settings.pack == "B");
    CHECK(*man.logs[1].settings.test == "flight \"b\"");

    auto err = [&](const std::string& text) {
        const std::string p = t.write("bad.csv", text);
        return input_error([&] { load_manifest(p); });
    };
    const std::string p = t.path("bad.csv");
    CHECK(err("path,pak\n") == p + ":1:2: unknown column \"pak\" in the header; expected some of path, test, pack, config, "
                                   "estimator, format, current_source, time_col, time_unit, voltage_col, current_col, current_unit, "
                                   "cell_cols, temperature_col, negative_discharge, charged_mah, monitor, average_ms, "
                                   "no_temperature");
    CHECK(err("pack,test\nA,1\n") == p + ":1: expected a header row with a \"path\" column (the first non-comment line)");
    CHECK(err("path,charged_mah\na.csv,900mAh\n") == p + ":2:2: charged_mah: expected a positive number of mAh, found \"900mAh\"");
    CHECK(err("path,charged_mah\na.csv,0\n") == p + ":2:2: charged_mah: expected a positive number of mAh, found \"0\"");
    CHECK(*load_manifest(t.write("c.csv", "path,charged_mah\na.csv,1043.5\n")).logs[0].settings.charged_mah == 1043.5);
    CHECK(*load_manifest(t.write("d.csv", "path,monitor\na.csv,quad 7\n")).logs[0].settings.monitor == "quad 7");
    CHECK(*load_manifest(t.write("e.csv", "path,average_ms\na.csv,8\n")).logs[0].settings.average_ms == 8.0);
    CHECK(load_manifest(t.write("g.csv", "path,no_temperature\na.csv,true\n")).logs[0].settings.reader_options().ignore_temperature);
    CHECK(err("path,no_temperature\na.csv,7\n") == p + ":2:2: no_temperature: expected true or false, found \"7\"");
    // A JSON manifest named neither .json nor .csv, with an editor's byte-order mark: still JSON.
    CHECK(load_manifest(t.write("f.txt", "\xEF\xBB\xBF{\"schema\": \"battsim.manifest\", \"logs\": [{\"path\": \"a.csv\"}]}"))
              .logs.size() == 1);
    CHECK(err("path,average_ms\na.csv,fast\n") == p + ":2:2: average_ms: expected a number of ms, found \"fast\"");
    CHECK(err("path,pack\na.csv\n") == p + ":2:2: expected 2 fields as in the header, found 1");
    CHECK(err("path,current_unit\na.csv,amps\n") == p + ":2:2: current_unit: unknown current unit \"amps\"; expected A or mA");
    CHECK(err("path,negative_discharge\na.csv,maybe\n") ==
          p + ":2:2: negative_discharge: expected true or false, found \"maybe\"");
    CHECK(err("path,pack\n,A\n") == p + ":2:1: expected the path of a log, found an empty field");
    CHECK(err("path,pack\n\"a.csv,A\n") == p + ":2: expected a closing '\"' in field 1");
    CHECK(err("path,path\n") == p + ":1:2: column \"path\" appears twice in the header");
    CHECK(err("# nothing\n") == p + ": manifest is empty; expected a header row with a \"path\" column");
    CHECK(err("path\n") == p + ": manifest lists no logs; expected a row per log after the header");
}

TEST_CASE("command-line settings are validated and win over the manifest", "[batch]") {
    LogSettingStrings a;
    a.format = "auto";  // the default: not a choice
    a.time_unit = "us";
    a.current_col = "I";
    LogSettings cli = settings_from_strings(a);
    CHECK_FALSE(cli.format.has_value());
    CHECK(*cli.time_scale_to_s == 1e-6);
    LogSettings man;
    man.current_col = "battery_current";
    man.voltage_col = "battery_voltage";
    man.overlay(cli);
    CHECK(*man.current_col == "I");
    CHECK(*man.voltage_col == "battery_voltage");
    a.current_unit = "kA";
    CHECK_THROWS_WITH(settings_from_strings(a), "--current-unit: unknown current unit \"kA\"; expected A or mA");
    a.current_unit.clear();
    a.average_ms = 9;
    CHECK(settings_from_strings(a).reader_options().average_us == 9000u);
    a.average_ms = 1e6;
    CHECK_THROWS_WITH(settings_from_strings(a),
                      "--average-ms: expected an averaging window of 0.001 to 60000 ms, found 1e+06");
}

TEST_CASE("plan: manifest order, settings per file, paths matched to entries", "[batch]") {
    TempDir t;
    t.write("logs/1.csv", raw_flight(20, 0.001));
    t.write("logs/2.csv", raw_flight(25, 0.001));
    t.write("logs/3.csv", raw_flight(30, 0.001));
    const std::string cfg = std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-original.json";
    const std::string m = t.write("m.json", R"({"schema": "battsim.manifest",
      "defaults": {"pack": "P", "config": ")" + cfg + R"("},
      "logs": [{"path": "logs/3.csv", "test": "third", "pack": "Q"}, {"path": "logs/[12].csv"}]})");
    BatchPlanRequest req;
    req.manifest = m;
    auto items = plan_batch(req);
    REQUIRE(items.size() == 3);
    CHECK(items[0].test == "third");
    CHECK(items[0].pack == "Q");
    CHECK(items[1].test == "1");
    CHECK(items[2].stem == "2");
    CHECK(items[2].pack == "P");
    CHECK(items[2].index == 2);
    CHECK(items[1].replay.config.name == "reference-4s-original");
    CHECK(items[1].replay.config.monitor.estimator == battsim::core::EstimatorKind::Reference);
    const std::string digest = inputs_digest(items);

    // Paths pick entries by file, however spelt; the command line overrides the config.
    req.paths = {t.path("logs/./3.csv"), t.path("logs/../other.csv")};
    req.command_line.config = std::string(BATTSIM_SOURCE_DIR) + "/configs/reference-modified.json";
    items = plan_batch(req);
    REQUIRE(items.size() == 2);
    CHECK(items[0].test == "third");
    CHECK(items[0].replay.config.name == "reference-4s-modified");
    CHECK(items[1].pack == "P");     // not in the manifest: its defaults
    CHECK(items[1].test == "other");

    // The estimator can be chosen per log or for all; it is part of the input list's identity.
    req.paths.clear();
    req.command_line = LogSettings();
    req.command_line.estimator = battsim::core::EstimatorKind::Joint;
    items = plan_batch(req);
    CHECK(items[1].replay.config.monitor.estimator == battsim::core::EstimatorKind::Joint);
    CHECK(inputs_digest(items) != digest);
    const std::string joint = t.write("j.json", R"({"schema": "battsim.manifest",
      "logs": [{"path": "logs/1.csv", "estimator": "joint"}, {"path": "logs/2.csv"}]})");
    req = BatchPlanRequest();
    req.manifest = joint;
    items = plan_batch(req);
    CHECK(items[0].replay.config.monitor.estimator == battsim::core::EstimatorKind::Joint);
    CHECK(items[1].replay.config.monitor.estimator == battsim::core::EstimatorKind::Reference);

    const std::string bad = t.write("b.json", R"({"schema": "battsim.manifest",
      "logs": [{"path": "logs/*.csv", "test": "one"}]})");
    req = BatchPlanRequest();
    req.manifest = bad;
    CHECK(input_error([&] { plan_batch(req); }) ==
          bad + ":2:16: \"test\" labels one log, but \"" + t.path("logs/*.csv") +
              "\" names 3 files; drop the label (each row is then named after its file) or list the files");
    const std::string badcfg = t.write("c.json", R"({"schema": "battsim.manifest",
      "logs": [{"path": "logs/1.csv", "config": "missing.json"}]})");
    req.manifest = badcfg;
    // A manifest's config that cannot be read fails its logs' rows, not the fleet's run.
    const auto bad_items = plan_batch(req);
    REQUIRE(bad_items.size() == 1);
    CHECK(bad_items[0].error == "config: " + t.path("missing.json") + ": cannot open config file: no such file (named on " +
                                    badcfg + ":2:16)");
    // The command line's config is one mistake for the whole run.
    req.command_line.config = t.path("missing.json");
    CHECK_THROWS_AS(plan_batch(req), ConfigError);

    // A pattern that matches nothing names its manifest line; logs of one stem are labelled
    // as their summaries are named, unless the manifest labels them.
    t.write("a/f.csv", raw_flight(20, 0.001));
    t.write("b/f.csv", raw_flight(20, 0.001));
    req = BatchPlanRequest();
    req.manifest = t.write("s.json", R"({"schema": "battsim.manifest",
      "logs": [{"path": "a/f.csv"}, {"path": "b/f.csv"}, {"path": "b/f.csv", "test": "mine"}, {"path": "none/*.bin"}]})");
    CHECK_THROWS_AS(plan_batch(req), InputError);  // b/f.csv twice
    req.manifest = t.write("s.json", R"({"schema": "battsim.manifest",
      "logs": [{"path": "a/f.csv"}, {"path": "b/f.csv", "test": "mine"}, {"path": "nothing-*.bin"}]})");
    items = plan_batch(req);
    REQUIRE(items.size() == 3);
    CHECK(items[0].test == "a__f.csv");
    CHECK(items[1].test == "mine");
    CHECK(items[2].error == "pattern matches no file (" + req.manifest + ":2:74)");  // the entry's {
}

TEST_CASE("plan: a log listed twice is refused, naming both places", "[batch]") {
    TempDir t;
    t.write("logs/1.csv", raw_flight(20, 0.001));
    t.write("logs/2.csv", raw_flight(25, 0.001));
    BatchPlanRequest req;
    // CSV: the same file by two names (a hard link), on lines 2 and 4.
    fs::create_hard_link(t.path("logs/1.csv"), t.path("hard.csv"));
    req.manifest = t.write("m.csv", "path,pack\nlogs/1.csv,A\nlogs/2.csv,A\nhard.csv,A\n");
    CHECK(input_error([&] { plan_batch(req); }) ==
          req.manifest + ":4: \"" + t.path("hard.csv") + "\" names the same log as \"" + t.path("logs/1.csv") +
              "\" on line 2; list each log once (twice, it would count twice in the per-pack and per-monitor tables)");
    // JSON: a file that a pattern of another entry already holds.
    req.manifest = t.write("m.json", R"({"schema": "battsim.manifest",
      "logs": [{"path": "logs/*.csv"}, {"path": "logs/2.csv", "pack": "B"}]})");
    CHECK(input_error([&] { plan_batch(req); }) ==
          req.manifest + ":2:40: \"" + t.path("logs/2.csv") + "\" names the same log as \"" + t.path("logs/2.csv") +
              "\" (from \"" + t.path("logs/*.csv") + "\") on line 2, column 16; list each log once (twice, it would "
              "count twice in the per-pack and per-monitor tables)");
    // Paths on the command line: the same, as a usage error.
    req = BatchPlanRequest();
    req.paths = {t.path("logs/1.csv"), t.path("logs/2.csv"), t.path("logs/../logs/1.csv")};
    CHECK_THROWS_AS(plan_batch(req), std::invalid_argument);
    req.paths.pop_back();
    CHECK(plan_batch(req).size() == 2);
}

// ---------------------------------------------------------------------------------------
// Running, table, packs

TEST_CASE("run_batch: the same rows for any number of jobs, errors as rows", "[batch]") {
    TempDir t;
    std::vector<std::string> args;
    for (int k = 0; k < 6; ++k) args.push_back(t.write("f" + std::to_string(k) + ".csv", raw_flight(15 + 4 * k, 0.0008 * (k + 1))));
    args.insert(args.begin() + 2, t.write("bad.csv", "time_s,voltage_v,current_a\n0,16.5,1\nx,16.4,1\n"));
    BatchPlanRequest req;
    req.paths = args;
    const auto items = plan_batch(req);
    BatchRunOptions one;
    one.jobs = 1;
    one.keep_summaries = true;
    one.out_dir = t.path("out1");
    size_t calls = 0;
    one.progress = [&calls](size_t done, size_t total, size_t) {
        ++calls;
        CHECK(done <= total);
    };
    const BatchResult a = run_batch(items, one);
    BatchRunOptions two = one;
    two.jobs = 3;
    two.out_dir = t.path("out2");
    two.progress = nullptr;
    const BatchResult b = run_batch(items, two);
    CHECK(calls == items.size());
    REQUIRE(a.rows.size() == 7);
    CHECK(json(a.rows).dump() == json(b.rows).dump());
    CHECK(a.failed == 1);
    CHECK(a.rows[2]["status"] == "error");
    CHECK(a.rows[2]["error"] == t.path("bad.csv") + ":3:1: expected a number, found \"x\"");
    CHECK(a.summaries[2].is_null());
    CHECK(a.rows[0]["status"] == "ok");
    CHECK(a.rows[0]["flight"] == true);
    CHECK(a.rows[0]["capacity_mean_ah"].is_number());
    CHECK(a.rows[0]["cell_scores"].size() == 4);
    // Summaries of the good logs are on disk, identical whichever pool wrote them.
    for (const char* stem : {"f0", "f5"}) {
        std::ifstream x(t.path(std::string("out1/") + stem + ".json")), y(t.path(std::string("out2/") + stem + ".json"));
        const std::string sx((std::istreambuf_iterator<char>(x)), {}), sy((std::istreambuf_iterator<char>(y)), {});
        CHECK(!sx.empty());
        CHECK(sx == sy);
    }
    CHECK_FALSE(fs::exists(t.path("out1/bad.json")));
    CHECK(a.removed.empty());  // no earlier summary of bad.csv to remove
    // An earlier run's summary of the log that now fails is removed, and that is said.
    { std::ofstream(t.path("out1/bad.json")) << "{}\n"; }
    const BatchResult again = run_batch(items, one);
    CHECK_FALSE(fs::exists(t.path("out1/bad.json")));
    REQUIRE(again.removed.size() == 1);
    CHECK(again.removed[0] == t.path("bad.csv") + ": an earlier run's summary " + t.path("out1/bad.json") +
                                  " was removed: the log failed this run, and that summary would read as this run's");
}

TEST_CASE("least-squares slope and the pack table", "[batch]") {
    CHECK(least_squares_slope({1, 2, 3, 4}, {1.0, 0.9, 0.8, 0.7}) == Approx(-0.1));
    CHECK(std::isnan(least_squares_slope({1}, {1.0})));
    CHECK(std::isnan(least_squares_slope({2, 2}, {1.0, 3.0})));

    auto row = [](const char* pack, const char* status, json cap, json res) {
        return json{{"pack", pack ? json(pack) : json(nullptr)}, {"status", status}, {"capacity_mean_ah", cap},
                    {"resistance_mean_ohm", res}};
    };
    // Pack B's second flight failed: flights 1 and 3 still sit at x = 1 and 3.
    const std::vector<json> rows = {row("B", "ok", 1.5, 0.020), row("A", "ok", 1.0, 0.05), row("B", "error", nullptr, nullptr),
                                    row(nullptr, "ok", 9.0, 9.0), row("B", "ok", 1.3, 0.024)};
    const auto packs = pack_rows(rows);
    REQUIRE(packs.size() == 2);
    CHECK(packs[0]["pack"] == "B");  // order of first appearance
    CHECK(packs[0]["flights"] == 3);
    CHECK(packs[0]["failed"] == 1);
    CHECK(packs[0]["capacity_mean_ah"].get<double>() == Approx(1.4));
    CHECK(packs[0]["capacity_trend_ah_per_flight"].get<double>() == Approx(-0.1));
    CHECK(packs[0]["resistance_trend_ohm_per_flight"].get<double>() == Approx(0.002));
    CHECK(packs[1]["pack"] == "A");
    CHECK(packs[1]["capacity_trend_ah_per_flight"].is_null());  // one flight: no trend
    CHECK(packs[0]["capacity_final_median_ah"].is_null());      // no final capacities in these rows
    CHECK(packs[0]["capacity_scatter_ratio"].is_null());
}

TEST_CASE("the pack table follows the landing's capacity and leaves out flights read with another pack's config",
          "[batch]") {
    // A pack wearing out as the joint estimator reads it: each flight's mean is pulled up by
    // its first minutes at the rating, its landing falls (flights 30 and 34 of the dissertation
    // as one pack read a trend of +0.292 Ah/flight by the means, 1.479 → 1.043 Ah at the landings).
    auto row = [](double mean_ah, double final_ah, const char* note) {
        json r{{"pack", "W"},
               {"status", "ok"},
               {"capacity_mean_ah", mean_ah},
               {"resistance_mean_ohm", 0.02},
               {"capacity_final_ah", final_ah},
               {"capacity_final_sigma_ah", 0.03},
               {"notes", json::array()}};
        if (note) r["notes"].push_back(note);
        return r;
    };
    const std::string other =
        "the log has 4 cell voltages but the config 3 cells in series (cells_in_series): battsim make-config --from-log "
        "29.csv writes one for it (with --capacity-mah if the log does not record the capacity)";
    REQUIRE(battsim::host::is_other_pack_note(other));
    const std::vector<json> rows = {row(1.38, 1.479, nullptr), row(1.70, 1.043, nullptr), row(3.92, 4.650, other.c_str()),
                                    row(1.65, 0.95, nullptr)};
    const auto packs = pack_rows(rows);
    REQUIRE(packs.size() == 1);
    CHECK(packs[0]["flights"] == 4);
    CHECK(packs[0]["failed"] == 0);
    CHECK(packs[0]["other_pack_config"] == 1);
    // Flights 1, 2 and 4 (the third keeps its number): finals 1.479, 1.043, 0.95 at x = 1, 2, 4;
    // slope = Σ(x − 7/3)(y − ȳ) / Σ(x − 7/3)², by hand −0.736333 / 4.666667 = −0.15779 Ah/flight.
    CHECK(packs[0]["capacity_final_trend_ah_per_flight"].get<double>() == Approx(-0.15779).epsilon(1e-4));
    CHECK(packs[0]["capacity_trend_ah_per_flight"].get<double>() > 0.0);  // the means rise
    CHECK(packs[0]["capacity_final_median_ah"].get<double>() == Approx(1.043));
    CHECK(packs[0]["capacity_mean_ah"].get<double>() == Approx((1.38 + 1.70 + 1.65) / 3.0));
    const std::string md = render_packs(make_table(rows, rows.size(), "0123456789abcdef", ShardSpec()), TableFormat::Markdown);
    CHECK(md.find("| W | 4 | 0 | 1 | 1.043 | -0.158 |") != std::string::npos);
}

TEST_CASE("median and robust spread; the pack table's agreement of final capacities with their sigma", "[batch]") {
    CHECK(std::isnan(battsim::host::median({})));
    CHECK(battsim::host::median({3.0, 1.0, 2.0}) == 2.0);
    CHECK(battsim::host::median({4.0, 1.0, 3.0, 2.0}) == 2.5);
    CHECK(std::isnan(battsim::host::robust_spread({1.0, 2.0, 3.0})));  // fewer than 4
    // 1..5: quartiles at positions 1.5 and 4.5 → 1.5 and 4.5, IQR 3.
    CHECK(battsim::host::robust_spread({5.0, 1.0, 4.0, 2.0, 3.0}) == Approx(3.0 / 1.349));
    // 1..4: positions 1.25 and 3.75 → 1.25 and 3.75, IQR 2.5.
    CHECK(battsim::host::robust_spread({1.0, 2.0, 3.0, 4.0}) == Approx(2.5 / 1.349));

    // Five flights of one pack, final capacities 1.0 … 1.4 Ah with σ 0.05 … 0.09 (median 0.07):
    // spread 0.3 / 1.349 = 0.2224 Ah, 3.18 × the median σ. A failed flight and a reference
    // flight (σ null) count in neither.
    std::vector<json> rows;
    for (int k = 0; k < 5; ++k)
        rows.push_back(json{{"pack", "P"}, {"status", "ok"}, {"capacity_mean_ah", 1.2}, {"resistance_mean_ohm", 0.02},
                            {"capacity_final_ah", 1.0 + 0.1 * k}, {"capacity_final_sigma_ah", 0.05 + 0.01 * k}});
    rows.push_back(json{{"pack", "P"}, {"status", "error"}, {"capacity_mean_ah", nullptr}, {"resistance_mean_ohm", nullptr},
                        {"capacity_final_ah", nullptr}, {"capacity_final_sigma_ah", nullptr}});
    rows.push_back(json{{"pack", "Q"}, {"status", "ok"}, {"capacity_mean_ah", 1.2}, {"resistance_mean_ohm", 0.02},
                        {"capacity_final_ah", 1.1}, {"capacity_final_sigma_ah", nullptr}});
    const auto packs = pack_rows(rows);
    REQUIRE(packs.size() == 2);
    CHECK(packs[0]["capacity_final_median_ah"].get<double>() == Approx(1.2));
    CHECK(packs[0]["capacity_final_spread_ah"].get<double>() == Approx(0.3 / 1.349).epsilon(1e-5));
    CHECK(packs[0]["capacity_final_sigma_median_ah"].get<double>() == Approx(0.07));
    CHECK(packs[0]["capacity_scatter_ratio"].get<double>() == Approx(0.3 / 1.349 / 0.07).epsilon(1e-5));
    CHECK(packs[1]["capacity_final_median_ah"].get<double>() == Approx(1.1));
    CHECK(packs[1]["capacity_final_spread_ah"].is_null());  // one flight
    CHECK(packs[1]["capacity_scatter_ratio"].is_null());
    const std::string md = render_packs(make_table(rows, rows.size(), "0123456789abcdef", ShardSpec()), TableFormat::Markdown);
    CHECK(md.find("| P | 6 | 1 | 0 | 1.200 | +0.100 | 3.2 |") != std::string::npos);
    // A trend keeps its three significant figures' zeros: R 0.0200, 0.0201, 0.0202 Ω over three
    // flights is +0.000100 Ω/flight (a helper read "-0.0001" on the Matrice 100 fleet as rounded).
    std::vector<json> aging;
    for (int k = 0; k < 3; ++k)
        aging.push_back(json{{"pack", "R"}, {"status", "ok"}, {"capacity_mean_ah", 1.2},
                             {"resistance_mean_ohm", 0.02 + 0.0001 * k}, {"capacity_final_ah", 1.2 - 0.01 * k},
                             {"capacity_final_sigma_ah", nullptr}});
    const std::string trend = render_packs(make_table(aging, aging.size(), "0123456789abcdef", ShardSpec()), TableFormat::Markdown);
    CHECK(trend.find("| R | 3 | 0 | 0 | 1.190 | -0.0100 | – | 0.0201 | +0.000100 |") != std::string::npos);
}

TEST_CASE("the monitor table pools each monitor's charger checks as the median suggested gain", "[batch]") {
    auto row = [](json monitor, const char* status, json ratio, json fault, json gain, json suggested) {
        return json{{"monitor", monitor},         {"status", status},         {"charger_ratio", ratio},
                    {"charger_fault", fault},     {"charger_current_gain", gain}, {"charger_suggested_gain", suggested}};
    };
    // Monitor M: five checked flights suggesting 0.92, 0.93, 0.94, 0.95 and 0.80 (a bad
    // charger entry, outvoted): median 0.93; quartiles (positions 1.5 and 4.5 of five)
    // 0.86 and 0.945, spread 0.085 / 1.349. The gain in use is the latest suggesting
    // flight's, 1.0: the sensor counts 1 / 0.93 = 1.0753 × the charger, a fault at 3 %.
    // One more flight was flagged for an offset (no suggestion), one has no charger
    // count, one failed; rows without a monitor stay out.
    std::vector<json> rows = {row("M", "ok", 1.087, true, 1.0, 0.92),       row("M", "ok", 1.075, true, 1.0, 0.93),
                              row(nullptr, "ok", 1.2, true, 1.0, 0.83),     row("M", "ok", 1.064, true, 1.0, 0.94),
                              row("N", "ok", 0.99, false, 0.95, 0.96),      row("M", "ok", 1.12, true, 1.0, nullptr),
                              row("M", "ok", nullptr, nullptr, nullptr, nullptr), row("M", "error", nullptr, nullptr, nullptr, nullptr),
                              row("M", "ok", 1.053, true, 1.0, 0.95),       row("M", "ok", 1.25, true, 1.0, 0.80)};
    // Its sensor faults by cause: the offset flight, and one with a loose tap and a gap.
    rows[5]["sensor_fault_cause"] = {"current_offset"};
    rows[6]["sensor_fault_cause"] = {"cells", "sample_gap"};
    rows[4]["sensor_fault_cause"] = json::array();
    const auto monitors = monitor_rows(rows, 0.03);
    REQUIRE(monitors.size() == 2);
    const json& m = monitors[0];
    CHECK(m["monitor"] == "M");
    CHECK(m["flights"] == 8);
    CHECK(m["failed"] == 1);
    CHECK(m["charger_checks"] == 6);
    CHECK(m["charger_flagged"] == 6);
    CHECK(m["charger_pooled"] == 5);
    CHECK(m["suggested_current_gain"].get<double>() == Approx(0.93));
    CHECK(m["suggested_gain_spread"].get<double>() == Approx(0.085 / 1.349).epsilon(1e-5));
    CHECK(m["current_gain"].get<double>() == 1.0);
    CHECK(m["charger_ratio_pooled"].get<double>() == Approx(1.0 / 0.93).epsilon(1e-5));
    CHECK(m["charger_fault"] == true);
    CHECK(m["fault_flights_current_offset"] == 1);
    CHECK(m["fault_flights_cells"] == 1);
    CHECK(m["fault_flights_sample_gap"] == 1);
    CHECK(m["fault_flights_reading"] == 0);
    CHECK(monitors[1]["fault_flights_current_offset"] == 0);
    // Monitor N: one flight at gain 0.95 asking 0.96: 0.95 / 0.96 = 0.9896, within 3 %.
    CHECK(monitors[1]["charger_ratio_pooled"].get<double>() == Approx(0.95 / 0.96).epsilon(1e-5));
    CHECK(monitors[1]["charger_fault"] == false);
    CHECK(monitors[1]["suggested_gain_spread"].is_null());  // fewer than four
    // A monitor whose flights suggest nothing has no verdict.
    const auto none = monitor_rows({row("X", "ok", nullptr, nullptr, nullptr, nullptr)}, 0.03);
    CHECK(none[0]["charger_fault"].is_null());
    CHECK(none[0]["suggested_current_gain"].is_null());
    // In the table: JSON, the CSV alone, and a Markdown section after the rows.
    const json table = make_table(rows, rows.size(), "0123456789abcdef", ShardSpec());
    CHECK(table["monitors"].size() == 2);
    CHECK(render_monitors(table, TableFormat::Csv).rfind("monitor,flights,failed,charger_checks,charger_flagged,", 0) == 0);
    const std::string md = render_monitors(table, TableFormat::Markdown);
    CHECK(md.find("| M | 8 | 1 | 6 | 6 | 5 | 1.0753 | 0.0630 | 1.0000 | 0.9300 | yes |") != std::string::npos);
    CHECK(md.find(" | cells 1, current_offset 1, sample_gap 1 |\n") != std::string::npos);
    CHECK(md.find("| N | 1 |") != std::string::npos);
    CHECK(md.substr(md.find("| N | 1 |")).find(" | – |\n") != std::string::npos);
    CHECK(make_table(rows, rows.size(), "0123456789abcdef", ShardSpec{1, 2})["monitors"].is_null());  // a shard's: left to merge
}

TEST_CASE("the monitor table's fleet fit is exact on a long chain of monitors", "[batch]") {
    // 80 monitors, pack k flown by monitors k and k + 1: each link says only how two neighbours
    // differ. Monitor m reads capacities exp(0.002 (m − 40)) times true, no scatter, so the fit
    // is exact: terms centred on their median, 0.002 × (m − 39.5). Alternating passes had
    // stopped after 1000 rounds with M79 at −0.5 % instead of +8 %.
    std::vector<json> rows;
    for (int k = 0; k < 79; ++k) {
        for (int m : {k, k + 1}) {
            rows.push_back(json{{"pack", "P" + std::to_string(k)}, {"monitor", "M" + std::to_string(m)}, {"status", "ok"},
                                {"capacity_final_ah", (1.0 + 0.01 * k) * std::exp(0.002 * (m - 40))},
                                {"resistance_final_ohm", 0.02}});
        }
    }
    const auto t = monitor_rows(rows, 0.03);
    REQUIRE(t.size() == 80);
    int seen = 0;
    for (const json& r : t) {
        const int m = std::stoi(r["monitor"].get<std::string>().substr(1));
        INFO(m);
        CHECK(r["fleet_capacity_effect"].get<double>() == Approx(std::exp(0.002 * (m - 39.5)) - 1.0).margin(1e-9));
        ++seen;
    }
    CHECK(seen == 80);
}

TEST_CASE("the monitor table compares each monitor with the fleet on the packs they share", "[batch]") {
    // Four monitors fly the same four packs. Monitor A's current sensor reads 8 % high: every
    // capacity 1.08 times, every resistance 1 / 1.08 times. The packs differ (capacity 1.0 …
    // 1.6 Ah, resistance 20 … 35 mΩ) and every flight scatters by ±1 % (fixed pattern), which
    // the fit must not take for a monitor. The monitors' terms are centred on their median.
    const char* monitors[4] = {"A", "B", "C", "D"};
    const double scatter[16] = {0.01, -0.01, 0.004, -0.006, -0.008, 0.012, 0.0, 0.003,
                                0.006, -0.004, -0.011, 0.009, 0.002, -0.003, 0.01, -0.007};
    std::vector<json> rows;
    for (int p = 0; p < 4; ++p) {
        for (int m = 0; m < 4; ++m) {
            const double gain = m == 0 ? 1.08 : 1.0, e = scatter[4 * p + m];
            rows.push_back(json{{"pack", "P" + std::to_string(p)}, {"monitor", monitors[m]}, {"status", "ok"},
                                {"capacity_final_ah", (1.0 + 0.2 * p) * gain * (1.0 + e)},
                                {"resistance_final_ohm", (0.020 + 0.005 * p) / gain * (1.0 - e)}});
        }
    }
    // A fifth monitor flew a pack nobody else flew: nothing to compare it with.
    rows.push_back(json{{"pack", "Q"}, {"monitor", "E"}, {"status", "ok"}, {"capacity_final_ah", 1.3},
                        {"resistance_final_ohm", 0.03}});
    const auto t = monitor_rows(rows, 0.03);
    REQUIRE(t.size() == 5);
    const json& a = t[0];
    CHECK(a["fleet_flights"] == 4);
    CHECK(a["fleet_capacity_effect"].get<double>() == Approx(0.08).margin(0.012));
    CHECK(a["fleet_resistance_effect"].get<double>() == Approx(1.0 / 1.08 - 1.0).margin(0.012));
    CHECK(a["fleet_gain_error"].get<double>() == Approx(0.08).margin(0.01));
    CHECK(a["fleet_gain_error_sigma"].get<double>() > 0.0);
    CHECK(a["fleet_gain_error_sigma"].get<double>() < 0.01);
    CHECK(a["fleet_gain_fault"] == true);
    CHECK(a["fleet_capacity_source"] == "final");  // no rests in these rows
    for (int m = 1; m < 4; ++m) {
        INFO(monitors[m]);
        CHECK(std::fabs(t[m]["fleet_gain_error"].get<double>()) < 0.012);
        CHECK(t[m]["fleet_gain_fault"] == false);
    }
    CHECK(t[4]["fleet_flights"] == 0);
    CHECK(t[4]["fleet_gain_error"].is_null());
    CHECK(t[4]["fleet_gain_fault"].is_null());
    // With the capacity read off the rests as well, that is the one compared (here A's rests
    // read the gain without scatter, its in-flight capacity not at all).
    std::vector<json> rested = rows;
    for (json& r : rested) {
        r["capacity_after_rest_ah"] = r["capacity_final_ah"];
        if (r["monitor"] == "A") r["capacity_final_ah"] = r["capacity_final_ah"].get<double>() / 1.08;
    }
    const auto tr = monitor_rows(rested, 0.03);
    CHECK(tr[0]["fleet_capacity_source"] == "after_rest");
    CHECK(tr[0]["fleet_capacity_effect"].get<double>() == Approx(a["fleet_capacity_effect"].get<double>()));
    // Two monitors alone cannot say which one is off: no verdict.
    std::vector<json> two;
    for (const json& r : rows)
        if (r["monitor"] == "A" || r["monitor"] == "B") two.push_back(r);
    const auto t2 = monitor_rows(two, 0.03);
    CHECK(t2[0]["fleet_gain_error"].is_null());
    CHECK(t2[0]["fleet_gain_fault"].is_null());
    // Markdown: the fleet's reading beside the charger's.
    const std::string md = render_monitors(make_table(rows, rows.size(), "0123456789abcdef", ShardSpec()), TableFormat::Markdown);
    CHECK(md.find("| A | 4 | 0 | 0 | 0 | 0 | – | – | – | – | – | +") != std::string::npos);
    CHECK(md.find("% | yes |") != std::string::npos);
}

TEST_CASE("table rendering: Markdown escapes, CSV quotes, JSON round-trips", "[batch]") {
    BatchItem it;
    it.index = 0;
    it.path = "/d/a|b.csv";
    it.test = "t,1";
    it.pack = "P";
    it.replay.config = default_config();
    std::vector<json> rows = {make_error_row(it, "bad \"x\"\nline")};
    const json table = make_table(rows, 1, "0123456789abcdef", ShardSpec());
    const std::string md = render_table(table, TableFormat::Markdown);
    CHECK(md.find("| t,1 | a\\|b.csv | P | – |") != std::string::npos);
    CHECK(md.find("error: bad \"x\" line |") != std::string::npos);
    const std::string csv = render_table(table, TableFormat::Csv);
    CHECK(csv.rfind("index,test,log,pack,monitor,config,estimator,status,error,flight,", 0) == 0);
    CHECK(csv.find("0,\"t,1\",/d/a|b.csv,P,,reference-4s-modified,reference,error,\"bad \"\"x\"\"\nline\",false,") != std::string::npos);
    CHECK(json::parse(render_table(table, TableFormat::Json)) == table);
    CHECK(render_packs(table, TableFormat::Csv).rfind("pack,flights,failed,other_pack_config,capacity_mean_ah,", 0) == 0);
    CHECK_THROWS_WITH(parse_table_format("xlsx"), "unknown table format \"xlsx\"; expected md, csv or json");
}

TEST_CASE("table rendering: the final capacity beside the mean, no Piao scores for the joint estimator", "[batch]") {
    BatchItem it;
    it.index = 0;
    it.path = "/d/34.csv";
    it.test = "6";
    it.replay.config = default_config();
    json joint = make_error_row(it, "x");
    joint["status"] = "ok";
    joint["error"] = nullptr;
    joint["flight"] = true;
    joint["estimator"] = "joint";
    joint["capacity_mean_ah"] = 1.822;  // flight 34 with sim-4s.json: the highest mean, the lowest final
    joint["capacity_final_ah"] = 1.043;
    joint["capacity_final_sigma_ah"] = 0.085;
    joint["cell_scores"] = json::array({0.0, 0.0, 0.0, 0.0});
    joint["warnings"] = json::array({"cell_outlier"});
    joint["outlier_cell"] = 4;
    json reference = joint;
    reference["index"] = 1;
    reference["estimator"] = "reference";
    reference["capacity_final_sigma_ah"] = nullptr;
    reference["cell_scores"] = json::array({-0.92, 0.01, 0.03, -0.04});
    reference["warnings"] = json::array();
    reference["outlier_cell"] = nullptr;
    const std::string md =
        render_table(make_table({joint, reference}, 2, "0123456789abcdef", ShardSpec()), TableFormat::Markdown);
    CHECK(md.rfind("| test | log | pack | mean capacity Ah | first 20 % capacity Ah | final capacity Ah |", 0) == 0);
    CHECK(md.find("| 6 | 34.csv | – | 1.822 | – | 1.043 ± 0.085 |") != std::string::npos);
    CHECK(md.find("| – | – | cell_outlier (cell 4) | ok |") != std::string::npos);  // no cell differences; which cell
    CHECK(md.find("| 1.043 | ") != std::string::npos);            // the reference row: no σ
    CHECK(md.find("-0.92 / 0.01 / 0.03 / -0.04") != std::string::npos);
}

TEST_CASE("merge rebuilds the single run's table and refuses incomplete or foreign shards", "[batch]") {
    TempDir t;
    std::vector<json> rows;
    for (size_t i = 0; i < 5; ++i) {
        BatchItem it;
        it.index = i;
        it.path = "/l/" + std::to_string(i) + ".csv";
        it.test = std::to_string(i);
        it.pack = i % 2 ? "odd" : "even";
        rows.push_back(make_error_row(it, "e"));
        rows.back()["status"] = "ok";
        rows.back()["capacity_mean_ah"] = 1.0 + 0.1 * i;
    }
    const json whole = make_table(rows, 5, "d1", ShardSpec());
    std::vector<json> shards;
    for (size_t k = 1; k <= 2; ++k) {
        std::vector<json> part;
        for (const json& r : rows)
            if (parse_shard(std::to_string(k) + "/2").contains(r["index"].get<size_t>())) part.push_back(r);
        shards.push_back(make_table(part, 5, "d1", parse_shard(std::to_string(k) + "/2")));
    }
    CHECK(shards[0]["packs"].is_null());
    // Written and read back through files, shards in either order.
    const std::string p1 = t.write("s1.json", render_table(shards[0], TableFormat::Json));
    const std::string p2 = t.write("s2.json", render_table(shards[1], TableFormat::Json));
    const json merged = merge_tables({read_table_file(p2), read_table_file(p1)}, {p2, p1});
    for (TableFormat f : {TableFormat::Json, TableFormat::Csv, TableFormat::Markdown})
        CHECK(render_table(merged, f) == render_table(whole, f));

    CHECK(input_error([&] { merge_tables({read_table_file(p1)}, {p1}); }) ==
          p1 + ": 2 of 5 inputs are in none of the given tables (index 1, 3); expected every shard's table");
    CHECK(input_error([&] { merge_tables({read_table_file(p1), read_table_file(p1)}, {p1, p1}); }) ==
          p1 + ": holds input 0 (/l/0.csv) that " + p1 + " holds too; give each shard once");
    json foreign = shards[1];
    foreign["inputs"]["digest"] = "d2";
    CHECK(input_error([&] { merge_tables({shards[0], foreign}, {"a", "b"}); })
              .find("b: comes from a different input list than a") == 0);
    // A shard of a run split another way (here its 1/3 holds inputs 0 and 3, which no 2/2 holds).
    std::vector<json> third;
    for (const json& r : rows)
        if (parse_shard("2/3").contains(r["index"].get<size_t>())) third.push_back(r);
    CHECK(input_error([&] { merge_tables({shards[0], make_table(third, 5, "d1", parse_shard("2/3"))}, {"a", "b"}); }) ==
          "b: is split into 3 shard(s), a into 2; give the shards of one run");
    json weird = shards[0];
    weird["rows"][0]["status"] = "weird";
    const std::string pw = t.write("w.json", weird.dump());
    CHECK(input_error([&] { read_table_file(pw); }) ==
          pw + ": rows[0].status: expected \"ok\", \"error\" or \"no_valid_samples\", found \"weird\"");
    // The version under both keys, as the summaries name it and as version 2 did; either read.
    CHECK(shards[0]["schema_version"] == kBatchVersion);
    CHECK(shards[0]["version"] == kBatchVersion);
    json only_version = shards[0];
    only_version.erase("schema_version");
    CHECK_NOTHROW(read_table_file(t.write("v1.json", only_version.dump())));
    json only_schema_version = shards[0];
    only_schema_version.erase("version");
    CHECK_NOTHROW(read_table_file(t.write("v2.json", only_schema_version.dump())));
    json older = shards[0];
    older["version"] = older["schema_version"] = 2;
    const std::string pv = t.write("v3.json", older.dump());
    CHECK(input_error([&] { read_table_file(pv); }) == pv + ": unsupported table version 2; expected 3 (rerun the shards with this battsim)");
    json split = shards[0];
    split["version"] = 2;
    const std::string ps = t.write("v4.json", split.dump());
    CHECK(input_error([&] { read_table_file(ps); }) == ps + ": \"schema_version\" 3 and \"version\" 2 disagree");

    const std::string notjson = t.write("x.json", "{\"schema\": \"battsim.batch\",\n \"rows\": [}");
    CHECK(input_error([&] { read_table_file(notjson); }) ==
          notjson + ":2:11: not valid JSON (syntax error while parsing value - unexpected '}'; expected '[', '{', or a literal); "
                    "expected a table written by `battsim batch --format json`");
    const std::string summary = t.write("y.json", "{\"schema\": \"battsim.summary\"}");
    CHECK(input_error([&] { read_table_file(summary); }) ==
          summary + ": expected a JSON table with \"schema\": \"battsim.batch\" (from `battsim batch --format json`)");
    json broken = shards[0];
    broken["rows"][0].erase("warnings");
    const std::string p3 = t.write("z.json", broken.dump());
    CHECK(input_error([&] { read_table_file(p3); }) == p3 + ": rows[0]: expected the key \"warnings\"");
    json huge = shards[0];
    huge["inputs"]["count"] = 18446744073709551615ull;
    const std::string p4 = t.write("h.json", huge.dump());
    CHECK(input_error([&] { read_table_file(p4); }) ==
          p4 + ": \"inputs\".\"count\" 18446744073709551615 is more logs than a batch table holds (at most 100000000)");
}

TEST_CASE("golden comparison: changed fields listed, paths and versions ignored", "[batch]") {
    TempDir t;
    BatchItem a, b, c;
    a.stem = "a";
    a.path = "/x/a.csv";
    b.stem = "b";
    b.path = "/x/b.csv";
    c.stem = "c";
    c.path = "/x/c.csv";
    const json sa = {{"input", {{"path", "/x/a.csv"}}}, {"battsim_version", "9"}, {"flight", {{"capacity_ah", {{"mean", 1.5}}}}}};
    json golden_a = sa;
    golden_a["input"]["path"] = "elsewhere/a.csv";
    golden_a["battsim_version"] = "0.1.0";
    t.write("g/a.json", golden_a.dump(2));
    json golden_b = sa;
    golden_b["flight"]["capacity_ah"]["mean"] = 1.5 * (1 + 5e-7);  // inside the 1e-6 tolerance
    t.write("g/b.json", golden_b.dump(2));
    const GoldenComparison same = compare_to_goldens({a, b}, {sa, sa}, t.path("g"), golden_compare_options(1e-6));
    CHECK(same.ok());
    CHECK(same.compared == 2);
    CHECK(same.lines.empty());

    const GoldenComparison tight = compare_to_goldens({b}, {sa}, t.path("g"), golden_compare_options(1e-8));
    CHECK_FALSE(tight.ok());
    CHECK(tight.changed == 1);
    REQUIRE(tight.lines.size() == 1);
    CHECK(tight.lines[0] == t.path("g/b.json") + ": /flight/capacity_ah/mean: golden 1.50000075, now 1.5");

    const GoldenComparison other = compare_to_goldens({a, c, b}, {sa, sa, json()}, t.path("g"), golden_compare_options(1e-6));
    CHECK(other.missing == 1);
    CHECK(other.failed == 1);
    CHECK(other.lines == std::vector<std::string>{"/x/c.csv: no golden summary " + t.path("g/c.json"),
                                                  "/x/b.csv: not compared, the replay failed"});
}

TEST_CASE("inputs digest and duplicate stems", "[batch]") {
    std::vector<BatchItem> items(2);
    items[0].path = "a/30.csv";
    items[0].stem = "30";
    items[1].path = "b/30.csv";
    items[1].stem = "30";
    const std::string d = inputs_digest(items);
    CHECK(d.size() == 16);
    items[1].pack = "x";
    CHECK(inputs_digest(items) != d);
    // What a log is replayed with, beyond the config's name: its contents and the reader's settings.
    const std::string named = inputs_digest(items);
    const float capacity_ah = items[1].replay.config.monitor.battery.capacity_ah;
    items[1].replay.config.monitor.battery.capacity_ah = capacity_ah * 1.1f;
    CHECK(inputs_digest(items) != named);
    items[1].replay.config.monitor.battery.capacity_ah = capacity_ah;
    items[1].replay.reader.average_us = 500000;
    CHECK(inputs_digest(items) != named);
    items[1].replay.reader.average_us = 0;
    items[1].replay.reader.columns.cells = {"c1"};
    CHECK(inputs_digest(items) != named);
    items[1].replay.reader.columns.cells.clear();
    CHECK(inputs_digest(items) == named);
    // Items made by hand are named by their stems, and these two clash.
    CHECK(duplicate_summary_names(items) == std::vector<std::string>{"30: a/30.csv, b/30.csv"});
    assign_summary_names(items);
    CHECK(items[0].summary_stem() == "a__30.csv");
    CHECK(items[1].summary_stem() == "b__30.csv");
    CHECK(duplicate_summary_names(items).empty());
    CHECK(progress_line(3, 12, 1, 8) == "[##......] 3/12 logs, 1 failed");
}

TEST_CASE("summaries of logs of one stem are named by their paths, whatever the order", "[batch]") {
    // ArduPilot names its logs 00000001.BIN on every card: one folder per drone.
    const auto named = [](const std::vector<std::string>& paths) {
        std::vector<BatchItem> items(paths.size());
        for (size_t k = 0; k < paths.size(); ++k) {
            items[k].path = paths[k];
            items[k].stem = path_stem(paths[k]);
        }
        assign_summary_names(items);
        std::map<std::string, std::string> out;
        for (const BatchItem& it : items) out[it.path] = it.summary_stem();
        return out;
    };
    const std::map<std::string, std::string> fleet = named(
        {"/fleet/quad-a/00000001.BIN", "/fleet/quad-b/00000001.BIN", "/fleet/quad-b/00000002.BIN", "/fleet/hex/logs/00000001.BIN"});
    CHECK(fleet.at("/fleet/quad-a/00000001.BIN") == "quad-a__00000001.BIN");
    CHECK(fleet.at("/fleet/quad-b/00000001.BIN") == "quad-b__00000001.BIN");
    CHECK(fleet.at("/fleet/hex/logs/00000001.BIN") == "hex__logs__00000001.BIN");
    CHECK(fleet.at("/fleet/quad-b/00000002.BIN") == "00000002");  // a stem of its own keeps it
    // The same names in any order of the inputs.
    CHECK(named({"/fleet/hex/logs/00000001.BIN", "/fleet/quad-b/00000002.BIN", "/fleet/quad-b/00000001.BIN",
                 "/fleet/quad-a/00000001.BIN"}) == fleet);
    // One directory, two formats of one flight: the extension parts them.
    const auto formats = named({"/d/30.csv", "/d/30.bin"});
    CHECK(formats.at("/d/30.csv") == "30.csv");
    CHECK(formats.at("/d/30.bin") == "30.bin");
    // Relative paths are read from the working directory, made normal: "./a/../b" is "b".
    const auto relative = named({"./a/../b/7.csv", "c/7.csv"});
    CHECK(relative.at("./a/../b/7.csv") == "b__7.csv");
    CHECK(relative.at("c/7.csv") == "c__7.csv");
    // What no rule can part is left for the command to refuse: one path given twice.
    std::vector<BatchItem> twice(2);
    twice[0].path = twice[1].path = "/p/*.csv";  // a pattern that matched nothing, as error rows
    twice[0].stem = twice[1].stem = "*";
    assign_summary_names(twice);
    CHECK(duplicate_summary_names(twice) == std::vector<std::string>{"*.csv: /p/*.csv, /p/*.csv"});
}

TEST_CASE("batch counts each config's notes once, by the logs replayed with it", "[batch]") {
    LoadedConfig reference = builtin_config();
    REQUIRE(config_notes(reference.monitor).empty());
    LoadedConfig joint = reference;
    joint.monitor.estimator = battsim::core::EstimatorKind::Joint;  // no OCV table: one note
    REQUIRE(config_notes(joint.monitor).size() == 1);
    const std::string joint_note = config_notes(joint.monitor).front();

    std::vector<BatchItem> items(6);
    const auto use = [&](size_t k, LoadedConfig config, const std::string& name) {
        config.name = name;
        items[k].replay.config = config;
    };
    use(0, joint, "zeta");
    use(1, joint, "alpha");
    use(2, reference, "ref");
    use(3, joint, "alpha");
    use(4, joint, "alpha");
    items[4].error = "no file matches";  // never replayed: not counted
    use(5, joint, "zeta");

    const std::vector<CountedNote> counted = count_config_notes(items);
    REQUIRE(counted.size() == 2);
    CHECK(counted[0].note == "config alpha: " + joint_note);  // in the order of the text
    CHECK(counted[0].logs == 2);
    CHECK(counted[1].note == "config zeta: " + joint_note);
    CHECK(counted[1].logs == 2);
    CHECK(counted_note_text(counted[0]) == "note (2 logs), config alpha: " + joint_note);
    CHECK(counted_note_text({"config b: x", 1}) == "note (1 log), config b: x");

    items[5].replay.config = reference;
    CHECK(count_config_notes(items).back().logs == 1);
    CHECK(count_config_notes({}).empty());
}
