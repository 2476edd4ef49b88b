// CSV-family readers: raw predictive-bms logs, headered CSV, format detection, and
// every bad-input rule (each writes its own small file under a temp dir).
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "host/io/csv_reader.h"
#include "host/io/line_reader.h"
#include "host/io/sample_reader.h"
#include "test_files.h"

using namespace battsim;
using namespace battsim::host;

namespace {

using TempDir = testsupport::TempDir;

// Message of the InputError thrown by opening `path` and reading it to the end; "" if none.
std::string read_error(const std::string& path, const ReaderOptions& opt = ReaderOptions()) {
    try {
        auto r = open_reader(path, opt);
        core::Sample s;
        while (r->next(s)) {
        }
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

std::vector<core::Sample> read_all(const std::string& path, const ReaderOptions& opt, SourceInfo* info = nullptr) {
    auto r = open_reader(path, opt);
    std::vector<core::Sample> v;
    core::Sample s;
    while (r->next(s)) v.push_back(s);
    if (info) *info = r->info();
    return v;
}

const char* kRawRow1 = "627,16.57,4.14,4.14,4.14,4.16,47.99,0.39,\n";
const char* kRawRow2 = "694,16.57,4.14,4.14,4.14,4.16,173.53,0.44,\n";
const char* kRawRow3 = "760,16.57,4.14,4.14,4.14,4.16,67.81,0.40,\n";

}  // namespace

// ---------------------------------------------------------------------------------------
// Format names and detection

TEST_CASE("every log format in the table round-trips through its name", "[io]") {
    const std::vector<LogFormatEntry>& formats = log_formats();
    REQUIRE(formats.size() >= 2);
    // The fuzz harness's empty input and a first byte of 0 take the first entry: detection.
    CHECK(formats.front().format == LogFormat::Auto);
    std::set<std::string> names;
    std::set<LogFormat> values;
    for (const LogFormatEntry& e : formats) {
        INFO(e.name);
        CHECK(std::string(to_string(e.format)) == e.name);
        CHECK(parse_log_format(e.name) == e.format);
        CHECK(std::string(e.description).size() > 0);
        names.insert(e.name);
        values.insert(e.format);
    }
    // Each name and each value once: a copied row would make one format unreachable by name.
    CHECK(names.size() == formats.size());
    CHECK(values.size() == formats.size());
    CHECK(std::string(to_string(static_cast<LogFormat>(-1))) == "unknown");
}

TEST_CASE("the log format help and message list the table", "[io]") {
    // Names that manifests and summaries carry: they stay as they are.
    CHECK(std::string(to_string(LogFormat::Auto)) == "auto");
    CHECK(std::string(to_string(LogFormat::RawPbms)) == "raw");
    CHECK(std::string(to_string(LogFormat::Csv)) == "csv");
    CHECK(std::string(to_string(LogFormat::DataflashText)) == "dataflash-text");
    CHECK(std::string(to_string(LogFormat::Ulog)) == "ulog");
    CHECK_THAT(log_format_help(), Catch::StartsWith("Log format: auto (detected from the content), raw ("));
    CHECK_THAT(log_format_help(), Catch::EndsWith(", ulog (PX4 .ulg log)"));
    CHECK_THAT(log_format_help(), Catch::Contains("), dataflash-bin (ArduPilot .bin log), "));
    CHECK(std::string(to_string(LogFormat::DataflashBinary)) == "dataflash-bin");
    CHECK_THROWS_AS(parse_log_format("excel"), std::invalid_argument);
    CHECK_THROWS_WITH(parse_log_format("excel"), Catch::Contains("expected one of auto, raw, csv"));
}

TEST_CASE("format is detected from content, not the extension", "[io]") {
    TempDir t;
    CHECK(detect_log_format(t.write("a.log", std::string(kRawRow1) + kRawRow2)) == LogFormat::RawPbms);
    CHECK(detect_log_format(t.write("b.bin", "627,16.57,4.14,4.14,4.14,4.16,47.99,0.39\n")) == LogFormat::RawPbms);
    CHECK(detect_log_format(t.write("c.ulg", "time_s,voltage_v,current_a\n0,1,2\n")) == LogFormat::Csv);
    CHECK(detect_log_format(t.write("d.csv", std::string("ULog\x01\x12\x35\x01", 8) + "xxxx")) == LogFormat::Ulog);
    CHECK(detect_log_format(t.write("e.csv", std::string("\xA3\x95\x80\x80\x59", 5))) == LogFormat::DataflashBinary);
    CHECK(detect_log_format(t.write("f.csv", "1\n\nArduCopter V3.0.1\nAPM 2\nFMT, 128, 89, FMT, BBnNZ, Type\n")) ==
          LogFormat::DataflashText);
    // BOM and CRLF do not hide a raw log.
    CHECK(detect_log_format(t.write("g.txt", "\xEF\xBB\xBF" "627,16.57,4.14,4.14,4.14,4.16,47.99,0.39,\r\n")) ==
          LogFormat::RawPbms);
    // A NaN in the first raw row is still a raw row (the reader then reports it).
    CHECK(detect_log_format(t.write("h.txt", "627,nan,4.14,4.14,4.14,4.16,47.99,0.39,\n")) == LogFormat::RawPbms);
}

TEST_CASE("numbers without a header in an unknown layout are rejected", "[io]") {
    TempDir t;
    const std::string p = t.write("five.csv", "1,2,3,4,5\n6,7,8,9,10\n");
    CHECK(read_error(p) == p + ":1: cannot detect the log format: the first line holds 5 fields of numbers and no "
                               "header; expected a header row (CSV) or the 8 fields of a predictive-bms log "
                               "(time_ms, bus_voltage_v, cell1_v..cell4_v, current_ma, shunt_mv)");
}

TEST_CASE("unknown binary content is rejected", "[io]") {
    TempDir t;
    const std::string p = t.write("junk.bin", std::string("\x7F" "ELF\x02\x01\x01\x00\x00\x00", 10));
    CHECK(read_error(p) == p + ": unrecognised binary file (byte 0x7F at offset 0 is not text, the first NUL at offset "
                               "7): expected a ULog (.ulg), DataFlash (.bin) or text (CSV) log");
    const std::string z = t.write("zeros.bin", std::string(16, '\0'));
    CHECK(read_error(z) == z + ": unrecognised binary file (byte 0x00 at offset 0 is not text): expected a ULog (.ulg), "
                               "DataFlash (.bin) or text (CSV) log");
}

TEST_CASE("a NUL in a text log is refused where it is: line, field and byte offset", "[io]") {
    TempDir t;
    // NULs with text after them are damage; after a UTF-8 byte-order mark the offset still
    // counts from the file's start.
    const std::string p = t.write("damaged.csv", std::string("\xEF\xBB\xBF" "time_s,voltage_v,current_a\n0,12.5,1\n1,\"1,2\",")
                                                    + std::string(8, '\0') + "\n2,12.4,1\n");
    CHECK(read_error(p) == p + ":3:3: a NUL byte at byte offset 47: expected text (a CSV log holds no NUL bytes; a "
                               "logger that lost power may have padded its file with them: cut the file before this line)");
    // Past the bytes format detection peeks at, the reader says the same place.
    std::string big = "time_s,voltage_v,current_a\n";
    for (int k = 0; k < 8000; ++k) big += std::to_string(k) + ",12.5,1\n";
    const std::string q = t.write("damaged-late.csv", big + "8000," + std::string(5, '\0') + "\n8001,12.5,1\n");
    CHECK(read_error(q) == q + ":8002:2: a NUL byte: expected text (a CSV log holds no NUL bytes; text follows these, so "
                               "they are not the NUL padding a logger that lost power leaves at the end of its file)");
}

TEST_CASE("a temperature column named in kelvin is read in kelvin", "[io]") {
    // A helper's walkthrough: "Temperature (K)" had read 298 degC, and only a note asked for 273.15 off.
    TempDir t;
    ReaderOptions opt;
    opt.columns.temperature = "Temperature (K)";
    SourceInfo info;
    const auto rows = read_all(t.write("k.csv", "time_s,voltage_v,current_a,Temperature (K)\n0,12.5,1,298.15\n1,12.4,1,280.15\n"),
                               opt, &info);
    REQUIRE(rows.size() == 2);
    CHECK(rows[0].temperature_c == Approx(25.0f));
    CHECK(rows[1].temperature_c == Approx(7.0f));
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] == "the temperature column \"Temperature (K)\" is read in kelvin, as its name says, and converted to "
                           "degrees Celsius");
    // In degrees Celsius, as read.
    opt.columns.temperature = "temp";
    CHECK(read_all(t.write("c.csv", "time_s,voltage_v,current_a,temp\n0,12.5,1,25\n"), opt)[0].temperature_c == 25.0f);
}

TEST_CASE("a log padded with NULs to its end (power lost) keeps the rows before them, said", "[io]") {
    // A helper's sweep: a crash's log had been refused whole when the padding fell in the
    // bytes format detection peeks at, and read as "last line is cut off (1 of 3 fields)" past them.
    TempDir t;
    std::string big = "time_s,voltage_v,current_a\n";
    for (int k = 0; k < 8000; ++k) big += std::to_string(k) + ",12.5,1\n";
    for (const std::string& head : {std::string("time_s,voltage_v,current_a\n0,12.5,1\n1,12.4,1\n"), big}) {
        for (const std::string& tail : {std::string(), std::string("2,12.")}) {
            const std::string p = t.write("padded.csv", head + tail + std::string(4000, '\0'));
            SourceInfo info;
            const auto rows = read_all(p, ReaderOptions{}, &info);
            CHECK(rows.size() == (head == big ? 8000u : 2u));
            const std::string ln = std::to_string(head == big ? 8002 : 4);
            const std::string want = "line " + ln + ": the file ends in NUL bytes (about 4000), the padding a logger that "
                                     "lost power leaves; the rows before are kept" +
                                     (tail.empty() ? std::string() : ", the part of line " + ln + " before them skipped");
            CHECK(std::count(info.notes.begin(), info.notes.end(), want) == 1);
        }
    }
    // Nothing before a partial row: refused, saying why the row is cut.
    const std::string only = t.write("only.csv", "time_s,voltage_v,current_a\n0,12." + std::string(100, '\0'));
    CHECK(read_error(only) == only + ":2: no complete data rows: the only data line is cut off (NUL bytes in it, to the "
                                     "end of the file)");
    // A raw predictive-bms log (the dissertation logger's own) the same.
    const std::string r = t.write("raw.txt", "627,16.57,4.14,4.14,4.14,4.16,47.99,0.39,\n695,16.57,4.14,4.14,4.14,4.16,47.99,0.39,\n" +
                                                 std::string(512, '\0'));
    CHECK(read_all(r, ReaderOptions{}).size() == 2);
}

TEST_CASE("UTF-16 and UTF-32 text is refused as such, with what to save it as", "[io]") {
    TempDir t;
    const std::string text = "time_s,voltage_v,current_a\n0,12.5,1\n";
    const auto wide = [&text](bool little, size_t width) {
        std::string w;
        for (char c : text) {
            std::string unit(width, '\0');
            unit[little ? 0 : width - 1] = c;
            w += unit;
        }
        return w;
    };
    const std::string le = t.write("le.csv", "\xFF\xFE" + wide(true, 2));
    CHECK(read_error(le) == le + ": the file looks like UTF-16 (little-endian, with a byte-order mark) text; battsim "
                                 "reads text logs in UTF-8 (or ASCII): save it as UTF-8 (a spreadsheet's \"CSV UTF-8\", "
                                 "or iconv -f UTF-16 -t UTF-8)");
    const std::string be = t.write("be.csv", "\xFE\xFF" + wide(false, 2));
    CHECK_THAT(read_error(be), Catch::Contains("UTF-16 (big-endian, with a byte-order mark)"));
    const std::string bare = t.write("bare.csv", wide(true, 2));
    CHECK_THAT(read_error(bare), Catch::Contains("UTF-16 (little-endian, without a byte-order mark) text") &&
                                     Catch::Contains("iconv -f UTF-16LE -t UTF-8"));
    const std::string bare_be = t.write("bare-be.csv", wide(false, 2));
    CHECK_THAT(read_error(bare_be), Catch::Contains("iconv -f UTF-16BE -t UTF-8"));
    const std::string w32 = t.write("w32.csv", std::string("\xFF\xFE\0\0", 4) + wide(true, 4));
    CHECK_THAT(read_error(w32), Catch::Contains("UTF-32 (little-endian, with a byte-order mark)") &&
                                    Catch::Contains("iconv -f UTF-32 -t UTF-8"));
}

// ---------------------------------------------------------------------------------------
// Raw predictive-bms reader

TEST_CASE("raw reader: fields, units and trailing comma", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + kRawRow2 + "826,16.56,4.13,4.14,4.14,4.15,67.81,0.40\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 3);
    CHECK(info.format == LogFormat::RawPbms);
    CHECK(info.cell_count == 4);
    CHECK_FALSE(info.has_temperature);
    CHECK(info.notes.empty());
    CHECK(s[0].time_us == 627000u);
    CHECK(s[0].voltage_v == 16.57f);
    CHECK(s[0].current_a == Approx(0.04799).epsilon(1e-6));
    CHECK(s[0].cell_count == 4);
    CHECK(s[0].cell_voltage_v[3] == 4.16f);
    CHECK(s[1].current_a == Approx(0.17353).epsilon(1e-6));
    CHECK(s[2].time_us == 826000u);  // 8 fields, no trailing comma
    CHECK(s[2].cell_voltage_v[0] == 4.13f);
    CHECK_FALSE(s[0].has_temperature);
}

TEST_CASE("raw reader: current from the shunt voltage", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + kRawRow2);
    ReaderOptions opt;
    opt.current_source = CurrentSource::Shunt;
    const auto s = read_all(p, opt);
    REQUIRE(s.size() == 2);
    CHECK(s[0].current_a == Approx((0.39 / 3.7834625 * 10000 - 982.8158579) / 1000).margin(1e-5));
    CHECK(s[1].current_a == Approx((0.44 / 3.7834625 * 10000 - 982.8158579) / 1000).margin(1e-5));
    opt.format = LogFormat::RawPbms;
    opt.shunt.scale_mv_per_10a = 0.0f;
    CHECK(read_error(p, opt) == p + ": shunt calibration needs a finite, non-zero scale and a finite offset");
}

TEST_CASE("raw reader: CRLF, BOM, spaces and blank lines", "[io]") {
    TempDir t;
    const std::string p = t.write("crlf.csv",
                                  "\xEF\xBB\xBF" "627, 16.57 ,4.14,4.14,4.14,4.16,47.99,0.39,\r\n"
                                  "\r\n"
                                  "694,16.57,4.14,4.14,4.14,4.16,+173.53,0.44,\r\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 2);
    CHECK(s[0].voltage_v == 16.57f);
    CHECK(s[1].time_us == 694000u);
    CHECK(s[1].current_a == Approx(0.17353));
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] == "1 blank line skipped (first on line 2)");
}

// ---------------------------------------------------------------------------------------
// Bad input: each rule with its exact message

TEST_CASE("bad input: missing file", "[io]") {
    TempDir t;
    const std::string p = t.path("does_not_exist.csv");
    CHECK(read_error(p) == p + ": cannot open file: No such file or directory");
    CHECK_THROWS_AS(open_raw_pbms(p, ReaderOptions()), InputError);
    CHECK_THROWS_AS(open_csv(p, ReaderOptions()), InputError);
}

TEST_CASE("bad input: a directory", "[io]") {
    TempDir t;
    const std::string p = t.path("");
    CHECK(read_error(p) == p + ": cannot open file: it is a directory, expected a log file");
}

TEST_CASE("bad input: a FIFO is refused without blocking", "[io]") {
    TempDir t;
    const std::string p = t.path("fifo");
    REQUIRE(::mkfifo(p.c_str(), 0600) == 0);
    CHECK(read_error(p) == p + ": cannot open file: it is not a regular file (pipes and devices are not supported); "
                               "expected a log file");
}

TEST_CASE("a reader that threw stays failed", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + "694,x,4.14,4.14,4.14,4.16,173.53,0.44,\n" + kRawRow3);
    auto r = open_reader(p, ReaderOptions());
    core::Sample s;
    CHECK(r->next(s));
    CHECK_THROWS_WITH(r->next(s), p + ":2:2: expected a number, found \"x\"");
    CHECK_THROWS_WITH(r->next(s), p + ":2:2: expected a number, found \"x\"");
}

TEST_CASE("bad input: empty file", "[io]") {
    TempDir t;
    const std::string p = t.write("empty.csv", "");
    CHECK(read_error(p) == p + ": file is empty");
    CHECK_THROWS_WITH(open_raw_pbms(p, ReaderOptions()), p + ": file is empty");
    CHECK_THROWS_WITH(open_csv(p, ReaderOptions()), p + ": file is empty");
    const std::string b = t.write("blank.csv", "\n  \n\n");
    CHECK_THROWS_WITH(open_csv(b, ReaderOptions()), b + ": file holds only blank lines; expected a header row");
    CHECK_THROWS_WITH(open_raw_pbms(b, ReaderOptions()), b + ": no data rows (the file holds only blank lines)");
    const std::string c = t.write("comments.csv", "# pack 3\n\n  # 2026-12-07\n");
    CHECK_THROWS_WITH(open_csv(c, ReaderOptions()),
                      c + ": file holds only comment lines ('#') and blank lines; expected a header row");
    CHECK_THROWS_WITH(open_raw_pbms(c, ReaderOptions()),
                      c + ": no data rows (the file holds only comment lines ('#') and blank lines)");
}

TEST_CASE("comment lines ('#') are skipped before the header and between rows, and counted", "[io]") {
    // A lab rig's preamble and a note between runs; the samples are those of the file without them.
    TempDir t;
    const std::string p = t.write("lab.csv",
                                  "# cell B3, 25 C\n  # charger: 4.20 V CV\ntime_s,voltage_v,current_a\n0,16.8,0.5\n"
                                  "# load switched\n1,16.7,10\n2,16.6,10\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 3);
    CHECK(s[1].time_us == 1000000u);
    CHECK(s[1].current_a == 10.0f);
    CHECK(s[2].voltage_v == 16.6f);
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] == "3 comment lines (starting with '#') skipped (first on line 1)");
    // A raw log too; detection looks past the comment.
    const std::string r = t.write("raw.csv", std::string("# flight 7\n") + kRawRow1 + kRawRow2);
    CHECK(detect_log_format(r) == LogFormat::RawPbms);
    SourceInfo raw_info;
    CHECK(read_all(r, ReaderOptions(), &raw_info).size() == 2);
    CHECK(raw_info.notes == std::vector<std::string>{"1 comment line (starting with '#') skipped (first on line 1)"});
    // A first column named "#" (an index) is a header, not a comment.
    const std::string idx = t.write("index.csv", "#,time_s,voltage_v,current_a\n1,0,16.8,0.5\n2,1,16.7,10\n");
    SourceInfo idx_info;
    CHECK(read_all(idx, ReaderOptions(), &idx_info).size() == 2);
    CHECK(idx_info.notes.empty());
    // A header written as a comment is said to be one.
    const std::string h = t.write("hashed.csv", "#time_s,voltage_v,current_a\n0,16.8,0.5\n1,16.7,10\n");
    CHECK(read_error(h) == h + ":2: cannot detect the log format: the first line after the comments holds 3 fields of "
                               "numbers and no header; expected a header row (CSV) or the 8 fields of a predictive-bms "
                               "log (time_ms, bus_voltage_v, cell1_v..cell4_v, current_ma, shunt_mv) (line 1 starts "
                               "with '#' and is skipped as a comment: if it is the header, remove the '#')");
}

TEST_CASE("bad input: header only", "[io]") {
    TempDir t;
    const std::string p = t.write("hdr.csv", "time_s,voltage_v,current_a\n");
    CHECK(read_error(p) == p + ": no data rows after the header on line 1");
    const std::string q = t.write("hdr2.csv", "time_s,voltage_v,current_a\n\n\n");
    CHECK(read_error(q) == q + ": no data rows after the header on line 1");
}

TEST_CASE("bad input: wrong column count", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + "694,16.57,4.14,4.14,4.14,4.16,173.53\n" + kRawRow3);
    CHECK(read_error(p) == p + ":2:8: expected 8 fields (9 with a trailing comma): time_ms, bus_voltage_v, "
                               "cell1_v..cell4_v, current_ma, shunt_mv, found 7");
    const std::string q = t.write("raw10.csv", std::string(kRawRow1) + "694,16.57,4.14,4.14,4.14,4.16,173.53,0.44,1,\n");
    CHECK(read_error(q) == q + ":2:9: expected 8 fields (9 with a trailing comma): time_ms, bus_voltage_v, "
                               "cell1_v..cell4_v, current_ma, shunt_mv, found 10");
    const std::string c = t.write("hdr.csv", "time_s,voltage_v,current_a\n0,12.0,1.0\n0.1,12.0,1.0,5\n");
    CHECK(read_error(c) == c + ":3:4: expected 3 fields (as in the header on line 1), found 4");
}

TEST_CASE("bad input: non-numeric field", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + kRawRow2 + "760,abc,4.14,4.14,4.14,4.16,67.81,0.40,\n");
    CHECK(read_error(p) == p + ":3:2: expected a number, found \"abc\"");
    const std::string e = t.write("emptyfield.csv", std::string(kRawRow1) + "694,16.57,,4.14,4.14,4.16,173.53,0.44,\n");
    CHECK(read_error(e) == e + ":2:3: expected a number, found \"\"");
    // Locale-style decimal comma and a number with junk after it.
    const std::string c = t.write("hdr.csv", "time_s,voltage_v,current_a\n0,12.5V,1.0\n");
    CHECK(read_error(c) == c + ":2:2: expected a number, found \"12.5V\"");
    const std::string h = t.write("hex.csv", "time_s,voltage_v,current_a\n0,0x10,1.0\n");
    CHECK(read_error(h) == h + ":2:2: expected a number, found \"0x10\"");
}

TEST_CASE("bad input: NaN and infinity in any field", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + "694,16.57,nan,4.14,4.14,4.16,173.53,0.44,\n");
    CHECK(read_error(p) == p + ":2:3: expected a finite number, found \"nan\"");
    const std::string q = t.write("raw2.csv", std::string(kRawRow1) + "694,16.57,4.14,4.14,4.14,4.16,173.53,-inf,\n");
    CHECK(read_error(q) == q + ":2:8: expected a finite number, found \"-inf\"");
    const std::string r = t.write("raw3.csv", "inf,16.57,4.14,4.14,4.14,4.16,173.53,0.44,\n");
    CHECK(read_error(r) == r + ":1:1: expected a finite number, found \"inf\"");
    const std::string c = t.write("hdr.csv", "time_s,voltage_v,current_a,temperature_c\n0,NaN,1,20\n");
    CHECK(read_error(c) == c + ":2:2: expected a finite number, found \"NaN\"");
    const std::string big = t.write("big.csv", "time_s,voltage_v,current_a\n0,1e999,1\n");
    CHECK(read_error(big) == big + ":2:2: expected a number within range, found \"1e999\"");
    const std::string fl = t.write("float.csv", "time_s,voltage_v,current_a\n0,1e300,1\n");
    CHECK(read_error(fl) == fl + ":2:2: expected a number that fits a 32-bit float, found \"1e300\"");
}

TEST_CASE("a temperature sensor's dropout (nan, inf, empty) loses that sample's temperature, not the log", "[io]") {
    TempDir t;
    SourceInfo info;
    const std::string p = t.write("drop.csv",
                                  "time_s,voltage_v,current_a,temperature_c\n"
                                  "0,12.5,1,21.5\n"
                                  "1,12.4,1,nan\n"
                                  "2,12.4,1,\n"
                                  "3,12.3,1,-inf\n"
                                  "4,12.3,1,22\n");
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 5);
    CHECK(info.has_temperature);
    CHECK(s[0].has_temperature);
    CHECK(s[0].temperature_c == 21.5f);
    for (int k = 1; k <= 3; ++k) CHECK_FALSE(s[k].has_temperature);
    CHECK(s[2].voltage_v == 12.4f);  // the rest of the row as read
    CHECK(s[4].has_temperature);
    CHECK(s[4].temperature_c == 22.0f);
    // --average-ms: a window keeps the mean of the temperatures it has, and has none only
    // when none of its samples has one (windows of 2 s: rows 0-1, 2-3, 4).
    ReaderOptions averaged;
    averaged.average_us = 2000000;
    const auto w = read_all(p, averaged);
    REQUIRE(w.size() == 3);
    CHECK(w[0].has_temperature);
    CHECK(w[0].temperature_c == 21.5f);
    CHECK_FALSE(w[1].has_temperature);
    CHECK(w[2].temperature_c == 22.0f);
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] == "3 rows have no temperature (\"nan\", \"inf\" or an empty field in column 4 "
                           "\"temperature_c\", first on line 3): kept, without a temperature");
    // A column with no reading at all: a log without a temperature, as a ULog's all-NaN one.
    SourceInfo none;
    const std::string q = t.write("none.csv", "time_s,temperature_c,voltage_v,current_a\n0,NaN,12,1\n1,nan,12,1\n");
    const auto n = read_all(q, ReaderOptions(), &none);
    REQUIRE(n.size() == 2);
    CHECK_FALSE(none.has_temperature);
    CHECK(none.notes == std::vector<std::string>{"2 rows have no temperature (\"nan\", \"inf\" or an empty field in "
                                                 "column 2 \"temperature_c\", first on line 2): read as a log "
                                                 "without a temperature"});
    // In the required columns NaN stays an error, and in the temperature column any other text.
    CHECK(read_error(t.write("t.csv", "time_s,voltage_v,current_a,temperature_c\nnan,12,1,20\n")) ==
          t.path("t.csv") + ":2:1: expected a finite number, found \"nan\"");
    CHECK(read_error(t.write("a.csv", "time_s,voltage_v,current_a,temperature_c\n0,12,inf,20\n")) ==
          t.path("a.csv") + ":2:3: expected a finite number, found \"inf\"");
    CHECK(read_error(t.write("x.csv", "time_s,voltage_v,current_a,temperature_c\n0,12,1,hot\n")) ==
          t.path("x.csv") + ":2:4: expected a number, found \"hot\"");
    // The empty last field of a cut-off last line is still the cut, not a dropout.
    SourceInfo cut;
    const auto c = read_all(t.write("cut.csv", "time_s,voltage_v,current_a,temperature_c\n0,12,1,20\n1,12,1,"),
                            ReaderOptions(), &cut);
    CHECK(c.size() == 1);
    REQUIRE(cut.notes.size() == 1);
    CHECK_THAT(cut.notes[0], Catch::Contains("last line is cut off"));
}

TEST_CASE("bad input: time going backwards and negative time", "[io]") {
    TempDir t;
    const std::string p = t.write("raw.csv", std::string(kRawRow1) + kRawRow3 + kRawRow2);
    CHECK(read_error(p) == p + ":3:1: time goes backwards: 0.694000 s is earlier than 0.760000 s on line 2");
    const std::string c = t.write("hdr.csv", "voltage_v,current_a,time_ms\n12,1,5\n12,1,4\n");
    CHECK(read_error(c) == c + ":3:3: time goes backwards: 0.004000 s is earlier than 0.005000 s on line 2");
    const std::string n = t.write("neg.csv", "time_s,voltage_v,current_a\n-0.5,12,1\n");
    CHECK(read_error(n) == n + ":2:1: expected a time that is not negative, found \"-0.5\"");
    const std::string huge = t.write("huge.csv", "time_s,voltage_v,current_a\n1e20,12,1\n");
    CHECK(read_error(huge) == huge + ":2:1: expected a time below 2^63 microseconds, found \"1e20\"");
    const std::string huge2 = t.write("huge2.csv", "time_ms,voltage_v,current_a\n9999999999999999999,12,1\n");
    CHECK(read_error(huge2) == huge2 + ":2:1: expected a time below 2^63 microseconds, found \"9999999999999999999\"");
}

TEST_CASE("bad input: truncated last line is skipped with a note", "[io]") {
    TempDir t;
    ReaderOptions opt;
    SECTION("fewer fields, no newline") {
        const std::string p = t.write("a.csv", std::string(kRawRow1) + kRawRow2 + "760,16.57,4.1");
        SourceInfo info;
        const auto s = read_all(p, opt, &info);
        CHECK(s.size() == 2);
        REQUIRE(info.notes.size() == 1);
        CHECK(info.notes[0] == "line 3: last line is cut off (no newline at the end, it has 3 of 8 fields); skipped");
    }
    SECTION("a number cut off") {
        const std::string p = t.write("b.csv", std::string(kRawRow1) + kRawRow2 + "760,16.57,4.14,4.14,4.14,4.16,67.81,0.4");
        SourceInfo info;
        CHECK(read_all(p, opt, &info).size() == 2);
        REQUIRE(info.notes.size() == 1);
        CHECK(info.notes[0] == "line 3: last line is cut off (no newline at the end, it lacks the trailing comma "
                               "every earlier row has, so its last number may be cut off); skipped");
    }
    SECTION("an exponent cut off in a headered CSV") {
        const std::string p = t.write("c.csv", "time_s,voltage_v,current_a\n0,12,1\n0.1,12,1e");
        SourceInfo info;
        CHECK(read_all(p, opt, &info).size() == 1);
        REQUIRE(info.notes.size() == 1);
        CHECK(info.notes[0] == "line 3: last line is cut off (no newline at the end, its last field \"1e\" is "
                               "incomplete); skipped");
    }
    SECTION("a complete last line without newline is kept") {
        const std::string p = t.write("d.csv", "time_s,voltage_v,current_a\n0,12,1\n0.1,12,1.5");
        SourceInfo info;
        const auto s = read_all(p, opt, &info);
        REQUIRE(s.size() == 2);
        CHECK(s[1].current_a == 1.5f);
        CHECK(info.notes.empty());
        const std::string r = t.write("e.csv", std::string(kRawRow1) + "694,16.57,4.14,4.14,4.14,4.16,173.53,0.44,");
        CHECK(read_all(r, opt).size() == 2);
    }
    SECTION("a fixed format's decimals lost: the last number cut") {
        // A helper's sweep: "1.3" for a cut "1.35" had been read as whole.
        const std::string p = t.write("h.csv", "time_s,voltage_v,current_a\n0,16.50,1.25\n1,16.40,1.30\n2,16.30,1.3");
        SourceInfo info;
        CHECK(read_all(p, opt, &info).size() == 2);
        REQUIRE(info.notes.size() == 1);
        CHECK(info.notes[0] == "line 4: last line is cut off (no newline at the end, its last number has 1 decimals "
                               "where every earlier row's has 2); skipped");
        // Decimals that vary row to row (a writer that drops trailing zeros) prove nothing: kept.
        const std::string v = t.write("i.csv", "time_s,voltage_v,current_a\n0,16.50,1.25\n1,16.40,1.3\n2,16.30,1.3");
        CHECK(read_all(v, opt).size() == 3);
    }
    SECTION("the same short line WITH a newline is an error") {
        const std::string p = t.write("f.csv", std::string(kRawRow1) + kRawRow2 + "760,16.57,4.1\n");
        CHECK(read_error(p) == p + ":3:4: expected 8 fields (9 with a trailing comma): time_ms, bus_voltage_v, "
                                   "cell1_v..cell4_v, current_ma, shunt_mv, found 3");
    }
    SECTION("a bad number in the middle of the last line is still an error") {
        const std::string p = t.write("g.csv", "time_s,voltage_v,current_a\n0,12,1\n0.1,x,1");
        CHECK(read_error(p) == p + ":3:2: expected a number, found \"x\"");
    }
    SECTION("a file whose only data line is cut off has no data") {
        const std::string p = t.write("h.csv", "time_s,voltage_v,current_a\n0,12");
        CHECK(read_error(p) == p + ":2: no complete data rows: the only data line is cut off (no newline at the end)");
    }
}

TEST_CASE("bad input: duplicate time stamps are kept and noted once; a repeated row is read once", "[io]") {
    TempDir t;
    // Rows at one time with other readings are measurements of their own; a row that repeats
    // the one before it in every field is one measurement written twice.
    const std::string p = t.write("dup.csv", "time_ms,voltage_v,current_a\n1,12,1\n2,12,1\n2,12,2\n2,12,3\n3,12,1\n"
                                             "3,12,1\n3,12.0,1.0\n4,12,1\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 6);
    CHECK(s[3].current_a == 3.0f);
    CHECK(s[4].time_us == 3000u);
    CHECK(s[5].time_us == 4000u);
    REQUIRE(info.notes.size() == 2);
    CHECK(info.notes[0] == "2 rows repeat the row before, time and every reading (first on line 7): read once");
    CHECK(info.notes[1] == "2 rows repeat the time stamp of the row before (first on line 4); kept");
    // Cells and temperature count as readings: a row differing only there is kept.
    const std::string c = t.write("cells.csv", "time_s,voltage_v,current_a,cell1_v,cell2_v,temperature_c\n"
                                               "0,8,1,4,4,20\n0,8,1,4,4.01,20\n0,8,1,4,4.01,21\n0,8,1,4,4.01,21\n");
    SourceInfo cell_info;
    CHECK(read_all(c, ReaderOptions(), &cell_info).size() == 3);
    CHECK(cell_info.notes == std::vector<std::string>{
                                 "1 row repeats the row before, time and every reading (first on line 5): read once",
                                 "2 rows repeat the time stamp of the row before (first on line 3); kept"});
}

TEST_CASE("bad input: headered CSV missing the voltage or current column", "[io]") {
    TempDir t;
    const std::string p = t.write("nov.csv", "time_s,current_a,temp\n0,1,2\n");
    CHECK(read_error(p) == p + ":1: missing voltage column (expected voltage_v or voltage_mv); columns found: time_s, current_a, temp");
    const std::string q = t.write("noi.csv", "time_s,voltage_v\n0,1\n");
    CHECK(read_error(q) ==
          q + ":1: missing current column (expected current_a or current_ma); columns found: time_s, voltage_v");
    const std::string r = t.write("not.csv", "t,voltage_v,current_a\n0,1,2\n");
    CHECK(read_error(r) == r + ":1: missing time column (expected time_s, time_ms or time_us); columns found: t, "
                               "voltage_v, current_a");
    ReaderOptions opt;
    opt.columns.voltage = "battery_voltage";
    CHECK(read_error(p, opt) ==
          p + ":1: missing voltage column \"battery_voltage\"; columns found: time_s, current_a, temp");
    // Forcing CSV on a header-less file says what the first line looks like.
    const std::string raw = t.write("raw.csv", kRawRow1);
    opt = ReaderOptions();
    opt.format = LogFormat::Csv;
    CHECK_THROWS_WITH(read_all(raw, opt), Catch::Contains("(the first line looks like data, not a header row)"));
}

TEST_CASE("bad input: unit of a mapped column cannot be inferred", "[io]") {
    TempDir t;
    const std::string p = t.write("m.csv", "time,battery_voltage,battery_current\n0,24,1\n");
    ReaderOptions opt;
    opt.columns.time = "time";
    opt.columns.voltage = "battery_voltage";
    opt.columns.current = "battery_current";
    opt.columns.current_scale_to_a = 1.0;
    CHECK(read_error(p, opt) == p + ":1:1: cannot tell the unit of time column \"time\": expected a name ending in "
                                    "_s, _ms or _us (or (s), (ms), (us)), or give the unit: --time-unit s, ms or us (manifest: columns.time_unit or time_unit)");
    opt.columns.time_scale_to_s = 1.0;
    opt.columns.current_scale_to_a = 0.0;
    CHECK(read_error(p, opt) == p + ":1:3: cannot tell the unit of current column \"battery_current\": expected a "
                                    "name ending in _a or _ma (or (a), (ma)), or give the unit: --current-unit A or mA (manifest: columns.current_unit or current_unit)");
    opt.columns.current_scale_to_a = 1.0;
    opt.columns.time_scale_to_s = -1.0;
    CHECK(read_error(p, opt) == p + ": time scale must be a positive number of seconds per unit, got -1");
}

TEST_CASE("bad input: duplicate column, unclosed quote, bare CR, cell gap, long line", "[io]") {
    TempDir t;
    const std::string d = t.write("dup.csv", "time_s,voltage_v,Voltage_V,current_a\n0,1,2,3\n");
    CHECK(read_error(d) ==
          d + ":1:3: column \"voltage_v\" appears twice in the header (fields 2 and 3); expected unique column names");
    const std::string q = t.write("q.csv", "time_s,voltage_v,current_a\n0,\"12,1\n0.1,12,1\n");
    CHECK(read_error(q) == q + ":2:2: expected a closing '\"' and then a comma or the end of the line");
    const std::string cr = t.write("cr.csv", "time_s,voltage_v,current_a\r0,12,1\r");
    CHECK(read_error(cr) ==
          cr + ":1: the header contains a bare carriage return; expected \"\\n\" or \"\\r\\n\" line ends");
    const std::string g = t.write("gap.csv", "time_s,voltage_v,current_a,cell1_v,cell3_v\n0,8,1,4,4\n");
    CHECK(read_error(g) == g + ":1: cell voltage columns must be numbered cell1_v..cellN_v without gaps; cell2_v is "
                               "missing; columns found: time_s, voltage_v, current_a, cell1_v, cell3_v");
    const std::string l = t.write("long.csv", "time_s,voltage_v,current_a\n" + std::string(3 * 1024 * 1024, '1') + "\n");
    CHECK(read_error(l) == l + ":2: line is longer than 1048576 bytes; expected a text log with one record per line");
}

TEST_CASE("bad input: two columns of one quantity by the default names need the choice mapped", "[io]") {
    TempDir t;
    const std::string p = t.write("two.csv", "time_s,voltage_v,time_ms,current_a\n0,16.5,0,1\n1,16.4,1000,1\n");
    CHECK(read_error(p) == p + ":1:3: columns \"time_s\" (field 1) and \"time_ms\" (field 3) both give the time; "
                               "expected one, or choose it with --time-col NAME (in a manifest, columns.time or time_col)");
    ReaderOptions opt;
    opt.columns.time = "time_ms";
    const auto s = read_all(p, opt);
    REQUIRE(s.size() == 2);
    CHECK(s[1].time_us == 1000000u);
    const std::string c = t.write("amps.csv", "time_s,voltage_v,current_ma,current_a\n0,16.5,1000,2\n");
    CHECK(read_error(c) == c + ":1:4: columns \"current_ma\" (field 3) and \"current_a\" (field 4) both give the "
                               "current; expected one, or choose it with --current-col NAME (in a manifest, "
                               "columns.current or current_col)");
    opt = ReaderOptions();
    opt.columns.current = "current_a";
    CHECK(read_all(c, opt)[0].current_a == 2.0f);
}

// ---------------------------------------------------------------------------------------
// Headered CSV

TEST_CASE("headered CSV: default names, units, cells, temperature", "[io]") {
    TempDir t;
    const std::string p = t.write("h.csv",
                                  "\xEF\xBB\xBF \"time_ms\" , \"voltage_v\",current_ma,cell2_v,cell1_v,temperature_c,"
                                  "\"note, with comma\"\r\n"
                                  "1000, 8.1 ,1500,4.06,4.04,21.5,\"a, b\"\r\n"
                                  "1067,8.0,-250,4.0,4.0,21.6,x\r\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 2);
    CHECK(info.format == LogFormat::Csv);
    CHECK(info.cell_count == 2);
    CHECK(info.has_temperature);
    CHECK(info.notes.empty());
    CHECK(s[0].time_us == 1000000u);
    CHECK(s[1].time_us == 1067000u);
    CHECK(s[0].voltage_v == 8.1f);
    CHECK(s[0].current_a == Approx(1.5));
    CHECK(s[1].current_a == Approx(-0.25));
    CHECK(s[0].cell_count == 2);
    CHECK(s[0].cell_voltage_v[0] == 4.04f);  // cell1_v, although it comes second
    CHECK(s[0].cell_voltage_v[1] == 4.06f);
    CHECK(s[0].has_temperature);
    CHECK(s[0].temperature_c == 21.5f);
}

TEST_CASE("headered CSV: cell columns in millivolts by name, and one column per cell", "[io]") {
    TempDir t;
    const std::string p = t.write("mv.csv", "time_s,voltage_v,current_a,cell1_mv,cell2_mv,cell3_v\n0,12.3,1,4100,4096,4.104\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 1);
    CHECK(info.cell_count == 3);
    CHECK(s[0].cell_voltage_v[0] == Approx(4.1));
    CHECK(s[0].cell_voltage_v[1] == Approx(4.096));
    CHECK(s[0].cell_voltage_v[2] == Approx(4.104));  // units may differ per column
    // The pack voltage by name in millivolts too, as a logger writing cell1_mv writes it.
    const std::string pack_mv = t.write("pmv.csv", "time_s,voltage_mv,current_ma,cell1_mv\n0,4100,1500,4100\n");
    REQUIRE(read_all(pack_mv, ReaderOptions()).size() == 1);
    CHECK(read_all(pack_mv, ReaderOptions())[0].voltage_v == Approx(4.1));
    const std::string both = t.write("vv.csv", "time_s,voltage_v,voltage_mv,current_a\n0,4.1,4100,1\n");
    CHECK(read_error(both) == both + ":1:3: columns \"voltage_v\" (field 2) and \"voltage_mv\" (field 3) both give the "
                                     "voltage; expected one, or choose it with --voltage-col NAME (in a manifest, "
                                     "columns.voltage or voltage_col)");
    const std::string two = t.write("two.csv", "time_s,voltage_v,current_a,cell1_v,cell1_mv\n0,4.1,1,4.1,4100\n");
    CHECK(read_error(two) == two + ":1:5: cell 1 has two columns (cell1_v, cell1_mv); expected one per cell, or choose with --cell-cols");
}

TEST_CASE("headered CSV: time units and sign flip", "[io]") {
    TempDir t;
    const std::string p = t.write("s.csv", "time_s,voltage_v,current_a\n0.1,4.1,-2.5\n1.000001,4.0,0.5\n");
    ReaderOptions opt;
    opt.columns.current_negative_is_discharge = true;
    const auto s = read_all(p, opt);
    REQUIRE(s.size() == 2);
    CHECK(s[0].time_us == 100000u);
    CHECK(s[1].time_us == 1000001u);
    CHECK(s[0].current_a == 2.5f);
    CHECK(s[1].current_a == -0.5f);
    const std::string u = t.write("u.csv", "time_us,voltage_v,current_a\n1234567890123456789,4.1,1\n");
    CHECK(read_all(u, ReaderOptions())[0].time_us == 1234567890123456789ull);
    const std::string mv = t.write("mv.csv", "time_s,pack_mv,current_a\n0,16570,1\n");
    opt = ReaderOptions();
    opt.columns.voltage = "pack_mv";
    CHECK(read_all(mv, opt)[0].voltage_v == Approx(16.57));
}

TEST_CASE("headered CSV: shunt current source needs a shunt_mv column", "[io]") {
    TempDir t;
    ReaderOptions opt;
    opt.current_source = CurrentSource::Shunt;
    const std::string p = t.write("s.csv", "time_ms,voltage_v,shunt_mv\n627,16.57,0.39\n");
    CHECK(read_all(p, opt)[0].current_a == Approx((0.39 / 3.7834625 * 10000 - 982.8158579) / 1000).margin(1e-5));
    const std::string q = t.write("q.csv", "time_ms,voltage_v,current_a\n627,16.57,0.39\n");
    CHECK(read_error(q, opt) ==
          q + ":1: current source \"shunt\" needs a shunt_mv column; columns found: time_ms, voltage_v, current_a");
}

TEST_CASE("headered CSV: unused columns are not parsed", "[io]") {
    TempDir t;
    const std::string p = t.write("n.csv", "time_s,voltage_v,current_a,chamber_temperature_c\n0,4.1,1,nan\n1,4.1,1,\n");
    CHECK(read_all(p, ReaderOptions()).size() == 2);
}

// ---------------------------------------------------------------------------------------
// Other programs' logs, recognised by their columns

TEST_CASE("EdgeTX radio log: wall-clock time across midnight, VFAS before RxBt, rows without telemetry", "[io]") {
    TempDir t;
    const std::string p = t.write("Quad-2026-05-01-235959.csv",
                                  "Date,Time,1RSS(dB),RxBt(V),Curr(A),Capa(mAh),VFAS(V),GPS,Hdg(\xC2\xB0)\n"
                                  "2026-05-01,23:59:59.800,-60,5.1,,0,,12.000000 -45.000000,0\n"
                                  "2026-05-01,23:59:59.900,-60,5.1,0.0,0,0.0,12.000000 -45.000000,0\n"
                                  "2026-05-01,23:59:59.950,-60,5.1,12.3,40,16.4,12.000000 -45.000000,0\n"
                                  "2026-05-02,00:00:00.150,-60,5.1,12.5,41,16.3,12.000000 -45.000000,0\n"
                                  "2026-05-02,00:00:01,-60,5.1,0.4,41,16.6,,0\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 3);
    const std::uint64_t t0 = ((23ull * 60 + 59) * 60 + 59) * 1000000ull + 950000ull;
    CHECK(s[0].time_us == t0);
    CHECK(s[1].time_us == 86400000000ull + 150000ull);  // the next day
    CHECK(s[2].time_us == 86401000000ull);
    CHECK(s[0].voltage_v == 16.4f);  // VFAS (the pack), not RxBt (a FrSky receiver's own supply)
    CHECK(s[0].current_a == 12.3f);
    CHECK(s[0].cell_count == 0);
    REQUIRE(info.notes.size() == 2);
    CHECK(info.notes[0] ==
          "columns read as an EdgeTX/OpenTX radio log: time from \"Date\" and \"Time\", voltage \"VFAS(V)\", current "
          "\"Curr(A)\"; rows without battery telemetry (empty or 0 V) are skipped");
    CHECK(info.notes[1] == "2 rows without battery telemetry skipped (first on line 2)");

    // Crossfire / ExpressLRS: the pack is RxBt.
    const std::string q = t.write("crsf.csv", "Date,Time,RxBt(V),Curr(A)\n2026-05-01,10:00:00.000,25.2,1.5\n");
    CHECK(read_all(q, ReaderOptions())[0].voltage_v == 25.2f);
    // No row with telemetry at all: said so, not only "no data rows".
    const std::string none = t.write("none.csv", "Date,Time,RxBt(V),Curr(A)\n2026-05-01,10:00:00.100,0,0\n"
                                                 "2026-05-01,10:00:00.300,0.0,\n");
    CHECK(read_error(none) == none + ": no data rows after the header on line 1: all 2 rows are without battery "
                                     "telemetry (0 V, or an empty voltage or current; the first on line 2), as a radio "
                                     "logs before the receiver sends the pack's readings");
}

TEST_CASE("EdgeTX radio log: bad dates and times name the field", "[io]") {
    TempDir t;
    const char* head = "Date,Time,RxBt(V),Curr(A)\n2026-05-01,10:00:00.000,16.8,1\n";
    const auto err = [&](const char* row) { return read_error(t.write("r.csv", std::string(head) + row)); };
    const std::string p = t.path("r.csv");
    CHECK(err("2026-02-30,10:00:01.000,16.8,1\n") ==
          p + ":3:1: expected a date as YYYY-MM-DD, found \"2026-02-30\"");
    CHECK(err("2026-05-01,10:00:1.000,16.8,1\n") ==
          p + ":3:2: expected a time of day as HH:MM:SS or HH:MM:SS.fff, found \"10:00:1.000\"");
    CHECK(err("2026-05-01,24:00:00,16.8,1\n") ==
          p + ":3:2: expected a time of day as HH:MM:SS or HH:MM:SS.fff, found \"24:00:00\"");
    CHECK(err("2026-04-30,10:00:01.000,16.8,1\n") ==
          p + ":3:1: time goes backwards: date \"2026-04-30\" is earlier than the first row's");
    CHECK(err("2026-05-01,09:59:59.000,16.8,1\n") ==
          p + ":3:2: time goes backwards: 35999.000000 s is earlier than 36000.000000 s on line 2");
    // A cut-off last line is skipped as in any CSV.
    SourceInfo info;
    const auto s = read_all(t.write("c.csv", std::string(head) + "2026-05-01,10:00:0"), ReaderOptions(), &info);
    CHECK(s.size() == 1);
    REQUIRE(info.notes.size() == 2);
    CHECK(info.notes[1].find("last line is cut off") != std::string::npos);
    // 2024 is a leap year, 2100 is not.
    CHECK(read_error(t.write("l.csv", "Date,Time,RxBt(V),Curr(A)\n2024-02-29,10:00:00,16.8,1\n")).empty());
    CHECK(read_error(t.write("m.csv", "Date,Time,RxBt(V),Curr(A)\n2100-02-29,10:00:00,16.8,1\n")) ==
          t.path("m.csv") + ":2:1: expected a date as YYYY-MM-DD, found \"2100-02-29\"");
}

TEST_CASE("blackbox_decode log and units in parentheses", "[io]") {
    TempDir t;
    const std::string p = t.write("LOG00001.01.csv",
                                  "loopIteration, time (us), axisP[0], vbatLatest (V), amperageLatest (A)\n"
                                  "0, 1000000, 3, 16.42, 1.25\n"
                                  "1, 1000500, 4, 16.41, 1.27\n");
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 2);
    CHECK(s[1].time_us == 1000500u);
    CHECK(s[0].voltage_v == 16.42f);
    CHECK(s[1].current_a == 1.27f);
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] == "columns read as a blackbox_decode log: time \"time (us)\", voltage \"vbatLatest (V)\", "
                           "current \"amperageLatest (A)\"");
    // A unit in parentheses counts like a suffix for mapped columns too.
    const std::string q = t.write("q.csv", "t (ms),pack (mV),load (mA)\n1500,16420,2500\n");
    ReaderOptions opt;
    opt.columns.time = "t (ms)";
    opt.columns.voltage = "pack (mV)";
    opt.columns.current = "load (mA)";
    const auto r = read_all(q, opt);
    CHECK(r[0].time_us == 1500000u);
    CHECK(r[0].voltage_v == Approx(16.42));
    CHECK(r[0].current_a == Approx(2.5));
    // A column option turns recognition off: the named columns are what is read.
    opt = ReaderOptions();
    opt.columns.voltage = "vbatLatest (V)";
    CHECK(read_error(p, opt) ==
          p + ":1: missing time column (expected time_s, time_ms or time_us); columns found: loopIteration, time (us), "
              "axisP[0], vbatLatest (V), amperageLatest (A)");
}

TEST_CASE("a recognised log's layout short of one column names that column", "[io]") {
    TempDir t;
    // A quad without a current sensor: "missing time column" had been said of this header.
    const std::string bb = t.write("bb.csv", "loopIteration, time (us), vbatLatest (V)\n0, 1000000, 16.42\n");
    CHECK(read_error(bb) ==
          bb + ":1: the columns look like a blackbox_decode log (time \"time (us)\", voltage \"vbatLatest (V)\") but "
               "have no current column (amperageLatest; a craft without a current sensor logs none, and no monitor can "
               "weigh a pack without its current); battsim needs the pack's time, voltage and current, or name them with "
               "--time-col, --voltage-col and --current-col; columns found: loopIteration, time (us), vbatLatest (V)");
    const std::string m100 = t.write("m100.csv", "time,batt_volt,battery_current\n0,24.1,2\n");
    CHECK_THAT(read_error(m100), Catch::Contains("m100.csv:1: the columns look like a DJI Matrice 100 log (CMU) (time "
                                                 "\"time\", current \"battery_current\") but have no voltage column "
                                                 "(battery_voltage); "));
    const std::string radio = t.write("radio.csv", "Date,Time,RxBt(V),RSSI(dB)\n2024-05-01,10:00:00.000,16.4,-60\n");
    CHECK_THAT(read_error(radio), Catch::Contains("like an EdgeTX/OpenTX radio log (time \"Time\", voltage \"RxBt(V)\") "
                                                  "but have no current column (Curr); "));
    // A header like none of them is still told which names battsim reads.
    const std::string other = t.write("other.csv", "time,volts\n0,16\n");
    CHECK_THAT(read_error(other), Catch::Contains("missing time column (expected time_s, time_ms or time_us)"));
}

TEST_CASE("line reader streams across block boundaries", "[io]") {
    TempDir t;
    // ~6 MB, so lines straddle many 256 KiB blocks; the last line has no newline.
    std::string content = "time_us,voltage_v,current_ma\n";
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        content += std::to_string(i * 10) + "," + std::to_string(10 + i % 7) + ".123456789," + std::to_string(i) + "\n";
    }
    content.pop_back();
    const std::string p = t.write("big.csv", content);
    auto r = open_reader(p, ReaderOptions());
    core::Sample s;
    int count = 0;
    bool ok = true;
    while (r->next(s)) {
        ok = ok && s.time_us == static_cast<uint64_t>(count) * 10u &&
             s.current_a == static_cast<float>(count / 1000.0) &&
             s.voltage_v == static_cast<float>(10 + count % 7 + 0.123456789);
        ++count;
    }
    CHECK(ok);
    CHECK(count == n);
    CHECK(r->info().notes.empty());

    LineReader lines(p);
    std::string_view line;
    long last = 0;
    while (lines.next(line)) last = lines.line_number();
    CHECK(last == n + 1);
    CHECK_FALSE(lines.line_had_newline());
    CHECK(lines.bytes_consumed() == content.size());
}

// ---------------------------------------------------------------------------------------
// Real data

TEST_CASE("raw reader on predictive-bms flight 30", "[io][data]") {
    const std::string p = std::string(BATTSIM_DATA_DIR) + "/predictive-bms/flights/30.csv";
    REQUIRE(detect_log_format(p) == LogFormat::RawPbms);
    SourceInfo info;
    const auto s = read_all(p, ReaderOptions(), &info);
    REQUIRE(s.size() == 5285);
    CHECK(info.notes.empty());
    CHECK(info.cell_count == 4);
    CHECK(s[0].time_us == 627000u);
    CHECK(s[0].voltage_v == Approx(16.57));
    CHECK(s[0].current_a == Approx(0.04799).margin(1e-7));
    CHECK(s[0].cell_voltage_v[0] == Approx(4.14));
    CHECK(s[0].cell_voltage_v[1] == Approx(4.14));
    CHECK(s[0].cell_voltage_v[2] == Approx(4.14));
    CHECK(s[0].cell_voltage_v[3] == Approx(4.16));
    CHECK(s.back().time_us == 354835000u);
    CHECK(s.back().voltage_v == Approx(13.92));
    CHECK(s.back().cell_voltage_v[3] == Approx(2.71));

    ReaderOptions shunt;
    shunt.current_source = CurrentSource::Shunt;
    const auto t = read_all(p, shunt);
    REQUIRE(t.size() == 5285);
    CHECK(t[0].current_a == Approx((0.39 / 3.7834625 * 10000 - 982.8158579) / 1000).margin(1e-5));
    // The logged current and the shunt formula agree to the 0.01 mV rounding (<= 13 mA).
    float worst = 0.0f;
    for (std::size_t i = 0; i < s.size(); ++i) worst = std::max(worst, std::fabs(s[i].current_a - t[i].current_a));
    CHECK(worst <= 0.0135f);
}

TEST_CASE("headered reader with the CMU M100 mapping on flight 1", "[io][data]") {
    const std::string p = std::string(BATTSIM_DATA_DIR) + "/cmu-m100/flights/1.csv";
    ReaderOptions opt;
    opt.columns.time = "time";
    opt.columns.time_scale_to_s = 1.0;
    opt.columns.voltage = "battery_voltage";
    opt.columns.current = "battery_current";
    opt.columns.current_scale_to_a = 1.0;
    REQUIRE(detect_log_format(p) == LogFormat::Csv);
    SourceInfo info;
    const auto s = read_all(p, opt, &info);
    REQUIRE(s.size() == 1339);
    CHECK(info.notes.empty());
    CHECK(info.cell_count == 0);
    CHECK_FALSE(info.has_temperature);
    CHECK(s[0].time_us == 0u);
    CHECK(s[0].voltage_v == Approx(24.22217369));
    CHECK(s[0].current_a == Approx(0.087469511));
    CHECK(s[0].cell_count == 0);
    CHECK(s[1].time_us == 200000u);
    CHECK(s[1].voltage_v == Approx(24.22718048));
    CHECK(s.back().time_us == 200700000u);
    CHECK(s.back().voltage_v == Approx(23.07279015));
    CHECK(s.back().current_a == Approx(0.143131927));
    // Without the mapping the columns are recognised, with a note, and read the same.
    SourceInfo auto_info;
    const auto a = read_all(p, ReaderOptions(), &auto_info);
    REQUIRE(a.size() == s.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        CHECK(a[i].time_us == s[i].time_us);
        CHECK(a[i].voltage_v == s[i].voltage_v);
        CHECK(a[i].current_a == s[i].current_a);
    }
    REQUIRE(auto_info.notes.size() == 1);
    CHECK(auto_info.notes[0] ==
          "columns read as a DJI Matrice 100 log (CMU): time \"time\" in s, voltage \"battery_voltage\" in V, "
          "current \"battery_current\" in A");
}

// ---------------------------------------------------------------------------------------
// A step of the log's clock, told from a logging gap by the charge it would take

TEST_CASE("a clock step the pack could not have flown through is moved back; a gap stays", "[io]") {
    TempDir t;
    // 10 A either side of a 3600 s jump: at least 10 Ah over it, more than 1.55 Ah.
    const std::string stepped = t.write("step.csv",
                                        "time_s,voltage_v,current_a\n0,16,10\n0.1,16,10\n0.2,16,10\n3600.2,16,10\n3600.3,16,10\n");
    ReaderOptions opt;
    opt.clock_step_capacity_ah = 1.55;
    SourceInfo info;
    std::vector<core::Sample> v = read_all(stepped, opt, &info);
    REQUIRE(v.size() == 5);
    CHECK(v[3].time_us == 300000u);  // one usual interval (0.1 s) after the last before the step
    CHECK(v[4].time_us == 400000u);
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] ==
          "the log's clock steps 3600 s ahead at 0.2 s into the log, with 10 A before and 10 A after: over a logging gap "
          "that long the pack would have delivered at least 10 Ah, more than one and a half times the config's 1.55 Ah, so "
          "the clock stepped (a radio's clock set by GPS, two files joined); the samples after it are read 3599.9 s "
          "earlier, to follow on");
    // Off unless asked: the jump is kept as it is.
    CHECK(read_all(stepped, ReaderOptions())[3].time_us == 3600200000u);
    // At 0.4 A on the ground the same jump is 0.4 Ah: a pack could sit through it, a gap.
    const std::string ground = t.write("ground.csv",
                                       "time_s,voltage_v,current_a\n0,16,0.4\n0.1,16,0.4\n3600.1,16,0.4\n3600.2,16,10\n");
    info = SourceInfo();
    v = read_all(ground, opt, &info);
    CHECK(v[2].time_us == 3600100000u);
    CHECK(info.notes.empty());
    // So is a jump the smaller current either side could have flown: 100 s at 10 A then 0.5 A.
    const std::string landed = t.write("landed.csv", "time_s,voltage_v,current_a\n0,16,10\n0.1,16,10\n100.1,16,0.5\n");
    CHECK(read_all(landed, opt)[2].time_us == 100100000u);
    // And one within half again the capacity (a label's rating can be low): 10 Ah over the
    // hour on an 8 Ah pack, which sagged the pack 16 -> 14 V.
    opt.clock_step_capacity_ah = 8.0;
    const std::string sagged = t.write("sagged.csv",
                                       "time_s,voltage_v,current_a\n0,16,10\n0.1,16,10\n0.2,16,10\n3600.2,14,10\n");
    CHECK(read_all(sagged, opt)[3].time_us == 3600200000u);
    // The same hour with the voltage where it was: the pack did not deliver 10 Ah over it.
    info = SourceInfo();
    v = read_all(stepped, opt, &info);
    CHECK(v[3].time_us == 300000u);
    REQUIRE(info.notes.size() == 1);
    CHECK(info.notes[0] ==
          "the log's clock steps 3600 s ahead at 0.2 s into the log, with 10 A before and 10 A after and the pack at 16 V "
          "before and 16 V after: a gap that long at that load would have drawn at least 10 Ah of the config's 8 Ah and "
          "lowered the voltage, so no charge was drawn over it (the clock stepped, or the logger paused); the samples "
          "after it are read 3599.9 s earlier, to follow on");
}

TEST_CASE("a gap at a steady load that left the voltage where it was drew no charge", "[io]") {
    TempDir t;
    ReaderOptions opt;
    opt.clock_step_capacity_ah = 1.55;
    // A hover log paused for 600 s at 8.4 A: 1.4 Ah, within half again 1.55 Ah, but the
    // pack reads 15.9 V on both sides. (Counted, it had read a 3.1 Ah pack.)
    const std::string paused = t.write("paused.csv", "time_s,voltage_v,current_a\n0,15.92,8.4\n0.1,15.91,8.4\n"
                                                     "0.2,15.91,8.4\n600.2,15.90,8.3\n600.3,15.9,8.4\n");
    SourceInfo info;
    std::vector<core::Sample> v = read_all(paused, opt, &info);
    CHECK(v[3].time_us == 300000u);
    CHECK(v[4].time_us == 400000u);
    CHECK(info.notes.size() == 1);
    // Kept as a gap: the voltage 0.5 % lower after it (15.91 -> 15.83 V) ...
    const std::string flown = t.write("flown.csv", "time_s,voltage_v,current_a\n0,15.92,8.4\n0.1,15.91,8.4\n"
                                                   "0.2,15.91,8.4\n600.2,15.83,8.4\n");
    CHECK(read_all(flown, opt)[3].time_us == 600200000u);
    // ... another load after it (8.4 -> 6 A: the drone may have landed and rested) ...
    const std::string other = t.write("other.csv", "time_s,voltage_v,current_a\n0,15.92,8.4\n0.1,15.91,8.4\n"
                                                   "0.2,15.91,8.4\n600.2,15.95,6\n");
    CHECK(read_all(other, opt)[3].time_us == 600200000u);
    // ... a ground load (an hour at 1 A, under 1 C) ...
    const std::string ground = t.write("ground.csv", "time_s,voltage_v,current_a\n0,15.92,1\n0.1,15.91,1\n"
                                                     "0.2,15.91,1\n3600.2,15.91,1\n");
    CHECK(read_all(ground, opt)[3].time_us == 3600200000u);
    // ... or a quarter of the capacity or less (40 s at 8.4 A is 0.093 Ah).
    const std::string short_gap = t.write("short.csv", "time_s,voltage_v,current_a\n0,15.92,8.4\n0.1,15.91,8.4\n"
                                                       "0.2,15.91,8.4\n40.2,15.91,8.4\n");
    CHECK(read_all(short_gap, opt)[3].time_us == 40200000u);
}

TEST_CASE("bad input: a compressed log and standard input say so", "[io]") {
    TempDir t;
    const std::string gz = t.write("log.csv.gz", std::string("\x1F\x8B\x08\x00\x00\x00\x00\x00\x00\x03", 10));
    CHECK(read_error(gz) == gz + ": the file is gzip-compressed; expected a log itself: unpack it first (gunzip)");
    const std::string zip = t.write("logs.zip", std::string("PK\x03\x04\x14\x00\x00\x00", 8));
    CHECK(read_error(zip) == zip + ": the file is a zip archive; expected a log itself: unpack it first (unzip)");
    const std::string xz = t.write("log.csv.xz", std::string("\xFD" "7zXZ\x00\x00\x04", 8));
    CHECK(read_error(xz) == xz + ": the file is xz-compressed; expected a log itself: unpack it first (unxz)");
    // A text log that happens to begin with "PK" is still text.
    const std::string pk = t.write("pk.csv", "PK_time_s,voltage_v,current_a\n0,16.5,1\n");
    CHECK_THROWS_WITH(read_all(pk, ReaderOptions()), Catch::Contains("missing time column"));
    CHECK(read_error("-") ==
          "-: a log is not read from standard input (its format is detected before it is read); expected a log "
          "file: save the stream to a file first (a file named -: give ./-)");
}
