#include "host/batch/manifest.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "host/batch/inputs.h"
#include "host/io/json_text.h"
#include "host/io/line_reader.h"
#include "host/io/number_text.h"

namespace battsim {
namespace host {

namespace fs = std::filesystem;
using nlohmann::json;

void LogSettings::overlay(const LogSettings& t) {
    auto take = [](auto& mine, const auto& theirs) {
        if (theirs) mine = theirs;
    };
    take(test, t.test);
    take(pack, t.pack);
    take(monitor, t.monitor);
    take(config, t.config);
    take(estimator, t.estimator);
    take(format, t.format);
    take(current_source, t.current_source);
    take(time_col, t.time_col);
    take(voltage_col, t.voltage_col);
    take(current_col, t.current_col);
    take(temperature_col, t.temperature_col);
    take(time_scale_to_s, t.time_scale_to_s);
    take(current_scale_to_a, t.current_scale_to_a);
    take(cell_cols, t.cell_cols);
    take(negative_discharge, t.negative_discharge);
    take(no_temperature, t.no_temperature);
    take(average_ms, t.average_ms);
    take(charged_mah, t.charged_mah);
}

ReaderOptions LogSettings::reader_options(ReaderOptions r) const {
    if (format) r.format = *format;
    if (current_source) r.current_source = *current_source;
    if (time_col) r.columns.time = *time_col;
    if (voltage_col) r.columns.voltage = *voltage_col;
    if (current_col) r.columns.current = *current_col;
    if (temperature_col) r.columns.temperature = *temperature_col;
    if (time_scale_to_s) r.columns.time_scale_to_s = *time_scale_to_s;
    if (current_scale_to_a) r.columns.current_scale_to_a = *current_scale_to_a;
    if (cell_cols) r.columns.cells = *cell_cols;
    if (negative_discharge) r.columns.current_negative_is_discharge = *negative_discharge;
    if (no_temperature) r.ignore_temperature = *no_temperature;
    if (average_ms) r.average_us = static_cast<std::uint64_t>(std::llround(*average_ms * 1000.0));
    return r;
}

double time_unit_scale(const std::string& unit) {
    if (unit == "s") return 1.0;
    if (unit == "ms") return 1e-3;
    if (unit == "us") return 1e-6;
    throw std::invalid_argument("unknown time unit \"" + unit + "\"; expected s, ms or us");
}

double current_unit_scale(const std::string& unit) {
    if (unit == "A") return 1.0;
    if (unit == "mA") return 1e-3;
    throw std::invalid_argument("unknown current unit \"" + unit + "\"; expected A or mA");
}

double average_window_ms(double ms) {
    if (!(ms >= 0.001 && ms <= 60000.0)) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", ms);
        throw std::invalid_argument(std::string("expected an averaging window of 0.001 to 60000 ms, found ") + buf);
    }
    return ms;
}

CurrentSource parse_current_source(const std::string& name) {
    if (name == "auto") return CurrentSource::Auto;
    if (name == "current") return CurrentSource::Current;
    if (name == "shunt") return CurrentSource::Shunt;
    throw std::invalid_argument("unknown current source \"" + name + "\"; expected auto, current or shunt");
}

LogSettings settings_from_strings(const LogSettingStrings& a) {
    LogSettings s;
    auto set = [](std::optional<std::string>& out, const std::string& v) {
        if (!v.empty()) out = v;
    };
    set(s.config, a.config);
    set(s.time_col, a.time_col);
    set(s.voltage_col, a.voltage_col);
    set(s.current_col, a.current_col);
    set(s.temperature_col, a.temperature_col);
    auto with = [](const char* option, auto parse) {
        try {
            return parse();
        } catch (const std::invalid_argument& e) {
            throw std::invalid_argument(std::string(option) + ": " + e.what());
        }
    };
    if (!a.format.empty() && a.format != "auto")
        s.format = parse_log_format(a.format);  // its message names the log format; batch spells the option --log-format
    if (!a.current_source.empty() && a.current_source != "auto")
        s.current_source = with("--current-source", [&] { return parse_current_source(a.current_source); });
    if (!a.time_unit.empty()) s.time_scale_to_s = with("--time-unit", [&] { return time_unit_scale(a.time_unit); });
    if (!a.estimator.empty()) s.estimator = with("--estimator", [&] { return parse_estimator(a.estimator); });
    if (!a.current_unit.empty())
        s.current_scale_to_a = with("--current-unit", [&] { return current_unit_scale(a.current_unit); });
    if (!a.cell_cols.empty()) s.cell_cols = a.cell_cols;
    if (a.negative_discharge) s.negative_discharge = true;
    if (a.no_temperature) s.no_temperature = true;
    if (a.average_ms != 0.0) s.average_ms = with("--average-ms", [&] { return average_window_ms(a.average_ms); });
    return s;
}

core::EstimatorKind parse_estimator(const std::string& name) {
    if (name == "reference") return core::EstimatorKind::Reference;
    if (name == "joint") return core::EstimatorKind::Joint;
    throw std::invalid_argument("unknown estimator \"" + name + "\"; expected reference or joint");
}

const char* to_string(core::EstimatorKind kind) {
    return kind == core::EstimatorKind::Joint ? "joint" : "reference";
}

namespace {

std::string read_text(const std::string& path) {
    std::string text;
    const TextRead r = read_text_file(path, text);
    if (r != TextRead::Ok) throw InputError(path, 0, 0, text_read_message(r, "manifest"));
    return text;
}

// Relative paths in a manifest are relative to the manifest's own directory, so a
// manifest works from any working directory.
std::string resolve(const std::string& base_dir, const std::string& p) {
    if (p.empty() || fs::path(p).is_absolute() || base_dir.empty()) return p;
    return (fs::path(base_dir) / p).lexically_normal().string();
}

std::string manifest_dir(const std::string& path) {
    const std::string d = fs::path(path).parent_path().string();
    return d.empty() ? "." : d;
}


class JsonManifestParser {
public:
    JsonManifestParser(const std::string& text, const std::string& path) : text_(text), path_(path), loc_(text) {}

    [[noreturn]] void fail(const std::string& where, const std::string& what) const {
        const auto lc = loc_.location(where);
        throw InputError(path_, lc.first, lc.second, where + ": " + what);
    }
    std::pair<long, long> location(const std::string& where) const { return loc_.location(where); }

    // Fails on keys outside `allowed`, so a typo never silently falls back to a default.
    void check_keys(const json& obj, const std::string& where, const std::set<std::string>& allowed) const {
        if (!obj.is_object()) fail(where, "expected an object");
        for (auto it = obj.begin(); it != obj.end(); ++it) {
            if (!allowed.count(it.key())) {
                std::string list;
                for (const std::string& k : allowed) list += (list.empty() ? "" : ", ") + k;
                const std::string w = where + "." + it.key();
                const auto lc = loc_.key_location(w);
                throw InputError(path_, lc.first, lc.second, w + ": unknown key; expected one of " + list);
            }
        }
    }
    std::string string_value(const json& v, const std::string& where) const {
        if (!v.is_string()) fail(where, "expected a string, found " + json_brief(v));
        return v.get<std::string>();
    }
    // Test labels and pack ids are text; whole numbers are accepted and written as text.
    std::string label(const json& v, const std::string& where) const {
        if (v.is_number_integer() || v.is_number_unsigned()) return json_text(v);
        if (!v.is_string()) fail(where, "expected a string or a whole number, found " + json_brief(v));
        return v.get<std::string>();
    }
    std::string path_value(const json& v, const std::string& where, const std::string& base) const {
        const std::string s = string_value(v, where);
        if (s.empty()) fail(where, "expected a path, found an empty string");
        try {
            return resolve(base, expand_variables(s));
        } catch (const std::invalid_argument& e) {
            fail(where, e.what());
        }
    }

    LogSettings settings(const json& obj, const std::string& where, bool entry, const std::string& log_base,
                         std::string* log_path) const {
        std::set<std::string> allowed = {"pack",   "monitor",        "config",  "estimator",
                                         "format", "current_source", "columns", "average_ms", "no_temperature"};
        // A test label and a charger's count belong to one log: in the defaults they would
        // label every log alike.
        if (entry) allowed.insert({"path", "test", "charged_mah"});
        for (const char* one : {"test", "charged_mah"}) {
            if (!entry && obj.is_object() && obj.contains(one)) {
                const auto lc = loc_.key_location(where + "." + one);
                throw InputError(path_, lc.first, lc.second,
                                 where + "." + one + ": \"" + one +
                                     "\" belongs to one log: give it in that log's entry (in the defaults it would "
                                     "apply to every log alike)");
            }
        }
        check_keys(obj, where, allowed);
        LogSettings s;
        const std::string dir = manifest_dir(path_);
        if (entry) {
            if (!obj.contains("path")) fail(where, "expected a \"path\" key naming the log");
            *log_path = path_value(obj["path"], where + ".path", log_base);
        }
        if (obj.contains("test")) s.test = label(obj["test"], where + ".test");
        if (obj.contains("pack")) s.pack = label(obj["pack"], where + ".pack");
        if (obj.contains("monitor")) s.monitor = label(obj["monitor"], where + ".monitor");
        if (obj.contains("charged_mah")) {
            const json& v = obj["charged_mah"];
            if (!v.is_number() || !(v.get<double>() > 0.0))
                fail(where + ".charged_mah", "expected a positive number of mAh, found " + json_brief(v));
            s.charged_mah = v.get<double>();
        }
        if (obj.contains("config")) s.config = path_value(obj["config"], where + ".config", dir);
        if (obj.contains("average_ms")) {
            const json& v = obj["average_ms"];
            try {
                if (!v.is_number()) throw std::invalid_argument("expected a number of ms, found " + json_brief(v));
                s.average_ms = average_window_ms(v.get<double>());
            } catch (const std::invalid_argument& e) {
                fail(where + ".average_ms", e.what());
            }
        }
        if (obj.contains("no_temperature")) {
            if (!obj["no_temperature"].is_boolean())
                fail(where + ".no_temperature", "expected true or false, found " + json_brief(obj["no_temperature"]));
            s.no_temperature = obj["no_temperature"].get<bool>();
        }
        if (obj.contains("estimator")) {
            try {
                s.estimator = parse_estimator(string_value(obj["estimator"], where + ".estimator"));
            } catch (const std::invalid_argument& e) {
                fail(where + ".estimator", e.what());
            }
        }
        if (obj.contains("format")) {
            try {
                s.format = parse_log_format(string_value(obj["format"], where + ".format"));
            } catch (const std::invalid_argument& e) {
                fail(where + ".format", e.what());
            }
        }
        if (obj.contains("current_source")) {
            try {
                s.current_source = parse_current_source(string_value(obj["current_source"], where + ".current_source"));
            } catch (const std::invalid_argument& e) {
                fail(where + ".current_source", e.what());
            }
        }
        if (obj.contains("columns")) {
            const std::string w = where + ".columns";
            const json& c = obj["columns"];
            check_keys(c, w, {"time", "time_unit", "voltage", "current", "current_unit", "cells", "temperature",
                              "negative_is_discharge"});
            if (c.contains("time")) s.time_col = string_value(c["time"], w + ".time");
            if (c.contains("voltage")) s.voltage_col = string_value(c["voltage"], w + ".voltage");
            if (c.contains("current")) s.current_col = string_value(c["current"], w + ".current");
            if (c.contains("temperature")) s.temperature_col = string_value(c["temperature"], w + ".temperature");
            try {
                if (c.contains("time_unit")) s.time_scale_to_s = time_unit_scale(string_value(c["time_unit"], w + ".time_unit"));
            } catch (const std::invalid_argument& e) {
                fail(w + ".time_unit", e.what());
            }
            try {
                if (c.contains("current_unit"))
                    s.current_scale_to_a = current_unit_scale(string_value(c["current_unit"], w + ".current_unit"));
            } catch (const std::invalid_argument& e) {
                fail(w + ".current_unit", e.what());
            }
            if (c.contains("cells")) {
                const json& cells = c["cells"];
                if (!cells.is_array()) fail(w + ".cells", "expected an array of column names, cell 1 first");
                std::vector<std::string> names;
                for (size_t i = 0; i < cells.size(); ++i)
                    names.push_back(string_value(cells[i], w + ".cells[" + std::to_string(i) + "]"));
                s.cell_cols = names;
            }
            if (c.contains("negative_is_discharge")) {
                if (!c["negative_is_discharge"].is_boolean())
                    fail(w + ".negative_is_discharge", "expected true or false, found " + json_brief(c["negative_is_discharge"]));
                s.negative_discharge = c["negative_is_discharge"].get<bool>();
            }
        }
        return s;
    }

    Manifest parse() {
        json j;
        JsonSyntaxError se;
        if (!parse_json_text(text_, j, se)) throw InputError(path_, se.line, se.column, "not valid JSON: " + se.what);
        check_keys(j, "$", {"schema", "version", "description", "base_dir", "defaults", "logs"});
        if (!j.contains("schema")) fail("$", "expected \"schema\": \"" + std::string(kManifestSchema) + "\"");
        if (j["schema"] != kManifestSchema)
            fail("$.schema", "expected \"" + std::string(kManifestSchema) + "\", found " + json_brief(j["schema"]));
        if (j.contains("version") && j["version"] != kManifestVersion)
            fail("$.version", "unsupported version " + json_brief(j["version"]) + "; expected " + std::to_string(kManifestVersion));
        Manifest m;
        m.path = path_;
        if (j.contains("description")) m.description = string_value(j["description"], "$.description");
        const std::string dir = manifest_dir(path_);
        std::string log_base = dir;
        if (j.contains("base_dir")) log_base = path_value(j["base_dir"], "$.base_dir", dir);
        if (j.contains("defaults")) m.defaults = settings(j["defaults"], "$.defaults", false, log_base, nullptr);
        if (!j.contains("logs")) fail("$", "expected a \"logs\" array");
        const json& logs = j["logs"];
        if (!logs.is_array()) fail("$.logs", "expected an array of log entries");
        if (logs.empty()) fail("$.logs", "expected at least one log entry");
        for (size_t i = 0; i < logs.size(); ++i) {
            const std::string w = "$.logs[" + std::to_string(i) + "]";
            ManifestEntry e;
            e.settings = settings(logs[i], w, true, log_base, &e.path);
            const auto lc = location(w);
            e.line = lc.first;
            e.column = lc.second;
            m.logs.push_back(std::move(e));
        }
        return m;
    }

private:
    const std::string& text_;
    const std::string& path_;
    JsonLocator loc_;
};

// Splits one manifest row (RFC 4180 quoting, no embedded newlines); on failure `error`
// says what was expected.
bool split_csv_line(const std::string& line, std::vector<std::string>& fields, std::string& error) {
    fields.clear();
    std::string f;
    size_t i = 0;
    while (true) {
        f.clear();
        if (i < line.size() && line[i] == '"') {
            ++i;
            while (true) {
                if (i >= line.size()) {
                    error = "expected a closing '\"' in field " + std::to_string(fields.size() + 1);
                    return false;
                }
                if (line[i] == '"') {
                    if (i + 1 < line.size() && line[i + 1] == '"') {
                        f += '"';
                        i += 2;
                        continue;
                    }
                    ++i;
                    break;
                }
                f += line[i++];
            }
            if (i < line.size() && line[i] != ',') {
                error = "expected a comma after the closing '\"' of field " + std::to_string(fields.size() + 1);
                return false;
            }
        } else {
            while (i < line.size() && line[i] != ',') f += line[i++];
            // Surrounding blanks are layout, not content.
            const size_t b = f.find_first_not_of(" \t");
            const size_t e = f.find_last_not_of(" \t");
            f = b == std::string::npos ? std::string() : f.substr(b, e - b + 1);
        }
        fields.push_back(f);
        if (i >= line.size()) return true;
        ++i;  // the comma
    }
}

bool parse_bool(const std::string& s, bool& out) {
    if (s == "true" || s == "yes" || s == "1") {
        out = true;
        return true;
    }
    if (s == "false" || s == "no" || s == "0") {
        out = false;
        return true;
    }
    return false;
}

}  // namespace

Manifest parse_manifest_json(const std::string& text, const std::string& path) {
    return JsonManifestParser(text, path).parse();
}

Manifest parse_manifest_csv(const std::string& text, const std::string& path) {
    static const std::vector<std::string> kColumns = {
        "path",     "test",        "pack",         "config",    "estimator",   "format",          "current_source", "time_col",
        "time_unit", "voltage_col", "current_col", "current_unit", "cell_cols", "temperature_col", "negative_discharge",
        "charged_mah", "monitor", "average_ms", "no_temperature"};
    Manifest m;
    m.path = path;
    const std::string dir = manifest_dir(path);
    std::vector<std::string> header;
    std::vector<std::string> fields;
    std::istringstream in(text);
    std::string line;
    long ln = 0;
    while (std::getline(in, line)) {
        ++ln;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (ln == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // editors' BOM
        const size_t first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        std::string error;
        if (!split_csv_line(line, fields, error)) throw InputError(path, ln, 0, error);
        if (header.empty()) {
            std::set<std::string> seen;
            for (size_t k = 0; k < fields.size(); ++k) {
                const std::string& name = fields[k];
                bool known = false;
                for (const std::string& c : kColumns) known = known || c == name;
                if (!known) {
                    std::string list;
                    for (const std::string& c : kColumns) list += (list.empty() ? "" : ", ") + c;
                    throw InputError(path, ln, static_cast<long>(k) + 1,
                                     "unknown column \"" + name + "\" in the header; expected some of " + list);
                }
                if (!seen.insert(name).second)
                    throw InputError(path, ln, static_cast<long>(k) + 1, "column \"" + name + "\" appears twice in the header");
            }
            if (!seen.count("path"))
                throw InputError(path, ln, 0, "expected a header row with a \"path\" column (the first non-comment line)");
            header = fields;
            continue;
        }
        if (fields.size() != header.size()) {
            throw InputError(path, ln, static_cast<long>(std::min(fields.size(), header.size())) + 1,
                             "expected " + std::to_string(header.size()) + " fields as in the header, found " +
                                 std::to_string(fields.size()));
        }
        ManifestEntry e;
        e.line = ln;
        LogSettings& s = e.settings;
        for (size_t k = 0; k < fields.size(); ++k) {
            const std::string& name = header[k];
            const std::string& v = fields[k];
            const long col = static_cast<long>(k) + 1;
            if (v.empty()) {
                if (name == "path") throw InputError(path, ln, col, "expected the path of a log, found an empty field");
                continue;  // empty = inherit
            }
            try {
                if (name == "path") e.path = resolve(dir, expand_variables(v));
                else if (name == "test") s.test = v;
                else if (name == "pack") s.pack = v;
                else if (name == "monitor") s.monitor = v;
                else if (name == "config") s.config = resolve(dir, expand_variables(v));
                else if (name == "estimator") s.estimator = parse_estimator(v);
                else if (name == "format") s.format = parse_log_format(v);
                else if (name == "current_source") s.current_source = parse_current_source(v);
                else if (name == "time_col") s.time_col = v;
                else if (name == "time_unit") s.time_scale_to_s = time_unit_scale(v);
                else if (name == "voltage_col") s.voltage_col = v;
                else if (name == "current_col") s.current_col = v;
                else if (name == "current_unit") s.current_scale_to_a = current_unit_scale(v);
                else if (name == "temperature_col") s.temperature_col = v;
                else if (name == "cell_cols") {
                    // ';' between names: ',' already separates the manifest's fields.
                    std::vector<std::string> names;
                    std::string cur;
                    for (char c : v + ";") {
                        if (c != ';') {
                            cur += c;
                            continue;
                        }
                        if (cur.empty()) throw std::invalid_argument("expected cell column names separated by ';', found an empty name");
                        names.push_back(cur);
                        cur.clear();
                    }
                    s.cell_cols = names;
                } else if (name == "negative_discharge") {
                    bool b = false;
                    if (!parse_bool(v, b)) throw std::invalid_argument("expected true or false, found \"" + v + "\"");
                    s.negative_discharge = b;
                } else if (name == "no_temperature") {
                    bool b = false;
                    if (!parse_bool(v, b)) throw std::invalid_argument("expected true or false, found \"" + v + "\"");
                    s.no_temperature = b;
                } else if (name == "average_ms") {
                    double ms = 0.0;
                    if (!parse_finite_number(v, &ms)) throw std::invalid_argument("expected a number of ms, found \"" + v + "\"");
                    s.average_ms = average_window_ms(ms);
                } else if (name == "charged_mah") {
                    double mah = 0.0;
                    if (!parse_finite_number(v, &mah) || !(mah > 0.0))
                        throw std::invalid_argument("expected a positive number of mAh, found \"" + v + "\"");
                    s.charged_mah = mah;
                }
            } catch (const std::invalid_argument& ex) {
                throw InputError(path, ln, col, name + ": " + ex.what());
            }
        }
        m.logs.push_back(std::move(e));
    }
    if (header.empty()) throw InputError(path, 0, 0, "manifest is empty; expected a header row with a \"path\" column");
    if (m.logs.empty()) throw InputError(path, 0, 0, "manifest lists no logs; expected a row per log after the header");
    return m;
}

Manifest load_manifest(const std::string& path) {
    const std::string text = read_text(path);
    const std::string ext = fs::path(path).extension().string();
    if (ext == ".json") return parse_manifest_json(text, path);
    if (ext == ".csv") return parse_manifest_csv(text, path);
    // Sniffed past a UTF-8 byte-order mark (an editor's), which had sent a JSON manifest to the CSV reader.
    const size_t bom = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
    const size_t first = text.find_first_not_of(" \t\r\n", bom);
    if (first != std::string::npos && text[first] == '{') return parse_manifest_json(text, path);
    return parse_manifest_csv(text, path);
}

}  // namespace host
}  // namespace battsim
