// The pieces of --json's error object (cli/json_errors.h): which command lines ask for JSON,
// the reason picked out of standard error, and a stream passed through unchanged.
#include <catch2/catch.hpp>

#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "json_errors.h"

using battsim::cli::error_json;
using battsim::cli::json_requested;
using battsim::cli::RecordingBuf;
using battsim::cli::writes_error_object;

TEST_CASE("the error object is written for a failure that printed nothing; batch's and merge's exit 1 is a finding",
          "[exit][json]") {
    CHECK_FALSE(writes_error_object("replay", 0, 0));
    CHECK_FALSE(writes_error_object("batch", 1, 0));  // its failed rows are in its table, maybe a file
    CHECK_FALSE(writes_error_object("merge", 1, 0));
    CHECK(writes_error_object("calibrate", 1, 0));  // nothing to calibrate from: nothing written
    CHECK(writes_error_object("replay", 2, 0));
    CHECK(writes_error_object("batch", 3, 0));
    CHECK(writes_error_object("fit", 70, 0));
    CHECK_FALSE(writes_error_object("replay", 3, 10));  // something was printed: left as it is
}

TEST_CASE("--json asks for JSON; after -- it is a file's name; batch's --format json does too", "[exit][json]") {
    CHECK(json_requested({"battsim", "replay", "log.csv", "--json"}));
    CHECK_FALSE(json_requested({"battsim", "replay", "log.csv"}));
    CHECK_FALSE(json_requested({"battsim", "replay", "--", "--json"}));
    CHECK(json_requested({"battsim", "batch", "-m", "f.csv", "--format", "json"}));
    CHECK(json_requested({"battsim", "batch", "-m", "f.csv", "--format=json"}));
    CHECK_FALSE(json_requested({"battsim", "batch", "-m", "f.csv", "--format", "csv"}));
    CHECK_FALSE(json_requested({"battsim", "replay", "--format", "json"}));  // replay's --format is the log's
    CHECK_FALSE(json_requested({"battsim"}));
    CHECK(json_requested({"battsim", "merge", "a.json", "--format", "json"}));
    CHECK(json_requested({"battsim", "--json", "replay", "log.csv"}));
    CHECK(battsim::cli::command_word({"battsim", "--json", "replay", "log.csv"}) == "replay");
    CHECK(battsim::cli::command_word({"battsim", "--json"}) == "");
}

TEST_CASE("the error object's message is battsim's last line that is not a note", "[exit][json]") {
    const std::string err =
        "battsim replay: note: the log has 4 cell voltages but the config 6 cells in series\n"
        "battsim replay: x.csv:3:2: expected a number, found \"abc\"\n"
        "battsim replay: note: nothing written\n";
    const nlohmann::json j = error_json("replay", 3, err, "9.9");
    CHECK(j["schema"] == "battsim.error");
    CHECK(j["schema_version"] == 1);
    CHECK(j["battsim_version"] == "9.9");
    CHECK(j["command"] == "replay");
    CHECK(j["exit_code"] == 3);
    CHECK(j["message"] == "battsim replay: x.csv:3:2: expected a number, found \"abc\"");
    CHECK(j["stderr"].size() == 3);
    CHECK(j["stderr_truncated"] == false);
    // The help hint, another program's lines (gnuplot's) and a tally are not the reason.
    const nlohmann::json usage = error_json("fit", 2, "battsim fit: --starts: expected a whole number\n(battsim fit --help)\n", "1");
    CHECK(usage["message"] == "battsim fit: --starts: expected a whole number");
    const nlohmann::json plot =
        error_json("replay", 5, "battsim replay: gnuplot failed drawing p.png (exit 1):\nset term png\n         ^\n", "1");
    CHECK(plot["message"] == "battsim replay: gnuplot failed drawing p.png (exit 1):");
    const nlohmann::json compare =
        error_json("batch", 5, "battsim batch: /dev/full: write failed (No space left on device)\ncompare: 4 compared, 0 changed\n", "1");
    CHECK(compare["message"] == "battsim batch: /dev/full: write failed (No space left on device)");
    // A progress bar drawn with carriage returns and an erase sequence shows as its last state.
    const nlohmann::json bar = error_json("batch", 5, "\r[###   ] 1/4 logs\r\033[Kbattsim batch: x: write failed\n", "1");
    CHECK(bar["message"] == "battsim batch: x: write failed");
    CHECK(bar["stderr"] == nlohmann::json::array({"battsim batch: x: write failed"}));
    // The command the message names (a subcommand's own), else the command line's, else null.
    CHECK(error_json("bench", 3, "battsim bench monitor: LOG is required\n", "1")["command"] == "bench monitor");
    CHECK(error_json("", 2, "battsim: unknown command \"x\"\n", "1")["command"].is_null());
    const nlohmann::json notes = error_json("fit", 5, "battsim fit: note: a\n", "1");
    CHECK(notes["message"] == "battsim fit: note: a");  // nothing else said: the last line
    CHECK(error_json("fit", 70, "", "1")["message"] == "");
    CHECK(error_json("fit", 70, "x\n", "1", true)["stderr_truncated"] == true);
}

TEST_CASE("the error object stays valid JSON when a message holds a file name that is not UTF-8", "[exit][json]") {
    const std::string latin1 = "battsim replay: lat\xe9n.csv: cannot open file\n";
    const std::string text = battsim::cli::dump_error_json(error_json("replay", 3, latin1, "1"));
    const nlohmann::json back = nlohmann::json::parse(text);  // throws on invalid UTF-8
    CHECK_THAT(back["message"].get<std::string>(), Catch::Contains("lat\xef\xbf\xbdn.csv"));
}

TEST_CASE("the recording stream passes everything on, counts it, keeps the last lines, and takes threads", "[exit][json]") {
    std::ostringstream target;
    RecordingBuf buf(target.rdbuf(), 16);
    std::ostream out(&buf);
    out << "hello " << 42 << '\n';
    out.flush();
    CHECK(target.str() == "hello 42\n");
    CHECK(buf.bytes() == 9);
    CHECK(buf.text() == "hello 42\n");
    CHECK_FALSE(buf.truncated());
    out << "first line\nthe reason\n";
    out.flush();
    CHECK(buf.bytes() == 31);
    CHECK(buf.truncated());
    CHECK(buf.text() == "the reason\n");  // the last 16 bytes, from the line break kept
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&out] {
            for (int k = 0; k < 1000; ++k) out.write("xy", 2);
        });
    for (std::thread& t : threads) t.join();
    out.flush();
    CHECK(buf.bytes() == 31 + 8000);
    CHECK(target.str().size() == 31 + 8000);
}
