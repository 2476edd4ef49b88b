#include "host/config_keys.h"

#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>

#include "host/config_json.h"
#include "host/config_key_descriptions.h"

namespace battsim {
namespace host {
namespace {

using nlohmann::json;

// "$.a.b[0].c" → "a.b[].c": the key as the reference names it.
std::string key_of(const std::string& path) {
    std::string out;
    for (size_t i = path.rfind("$.", 0) == 0 ? 2 : 0; i < path.size(); ++i) {
        if (path[i] == '[') {
            out += "[]";
            i = path.find(']', i);
            if (i == std::string::npos) break;
        } else {
            out += path[i];
        }
    }
    return out;
}

// "$.a.b[0].c" → "/a/b/0/c" (config keys hold neither '/' nor '~').
json::json_pointer pointer_of(const std::string& path) {
    std::string p;
    for (size_t i = path.rfind("$.", 0) == 0 ? 2 : 0; i < path.size(); ++i) {
        if (path[i] == '.' || path[i] == '[') {
            p += '/';
        } else if (path[i] != ']') {
            p += path[i];
        }
    }
    return json::json_pointer("/" + p);
}

// `path` is `prefix` or lies below it.
bool within(const std::string& prefix, const std::string& path) {
    return path.compare(0, prefix.size(), prefix) == 0 &&
           (path.size() == prefix.size() || path[prefix.size()] == '.' || path[prefix.size()] == '[');
}

// What the probe puts at a member the reader looks for, in turn until one reads: a section,
// an array of objects, an array of numbers.
const json& probe_form(size_t k) {
    static const json forms[] = {json::object(), json::array({json::object()}), json::array({1.0, 2.0})};
    return forms[k];
}
constexpr size_t kProbeForms = 3;

struct RecorderScope {
    explicit RecorderScope(std::vector<ConfigKeyRecord>* r) { config_key_recorder() = r; }
    ~RecorderScope() { config_key_recorder() = nullptr; }
};

// The reader's records on a config holding every section it looks for: each round adds the
// members the last one met, and a member whose form fails moves on to the next form.
std::vector<ConfigKeyRecord> probe_reader(json& probe) {
    std::map<std::string, size_t> forms;  // member path → form in use
    for (int round = 0; round < 1000; ++round) {
        std::vector<ConfigKeyRecord> records;
        std::string failed;
        {
            RecorderScope scope(&records);
            try {
                config_from_json(probe, "probe");
            } catch (const ConfigError& e) {
                failed = e.where();
            }
        }
        if (!failed.empty()) {
            // A member met for the first time in this round may be what failed (a section
            // that needs one of its members): give it a form first.
            std::string member;
            for (const ConfigKeyRecord& r : records)
                if (r.type == "member" && within(r.path, failed) && r.path.size() > member.size()) member = r.path;
            if (!member.empty() && !forms.count(member)) {
                forms[member] = 0;
                probe[pointer_of(member)] = probe_form(0);
                continue;
            }
            member.clear();
            for (const auto& f : forms)
                if (within(f.first, failed) && f.first.size() > member.size()) member = f.first;
            if (member.empty()) throw std::logic_error("config keys: the default config fails at " + failed);
            size_t& form = forms[member];
            if (++form == kProbeForms) throw std::logic_error("config keys: no probe form reads at " + member);
            for (auto it = forms.begin(); it != forms.end();) {
                it = it->first != member && within(member, it->first) ? forms.erase(it) : std::next(it);
            }
            probe[pointer_of(member)] = probe_form(form);
            continue;
        }
        bool added = false;
        for (const ConfigKeyRecord& r : records) {
            if (r.type != "member" || forms.count(r.path)) continue;
            forms[r.path] = 0;
            probe[pointer_of(r.path)] = probe_form(0);
            added = true;
        }
        if (!added) return records;
    }
    throw std::logic_error("config keys: the probe does not settle");
}

std::string range_text(const ConfigKey& k) {
    if (k.type != "number" && k.type != "integer") return "";
    constexpr double kUnbounded = 1e9;  // the reader's "any" (kBig)
    const auto num = [](double x) {
        char b[32];
        std::snprintf(b, sizeof b, "%g", x);
        return std::string(b);
    };
    if (k.lo <= -kUnbounded && k.hi >= kUnbounded) return "any";
    if (k.hi >= kUnbounded) return "≥ " + num(k.lo);
    return num(k.lo) + " … " + num(k.hi);
}

// A key's own description; the health and verdict filters' EKF keys, which repeat the
// tracking filter's, may borrow the tracking filter's one.
std::string description_of(const std::string& key, const std::map<std::string, std::string>& about) {
    const auto it = about.find(key);
    if (it != about.end()) return it->second;
    for (const char* filter : {"joint.health_filter.", "joint.verdict_filter."}) {
        if (key.rfind(filter, 0) != 0) continue;
        const auto shared = about.find("joint." + key.substr(std::string(filter).size()));
        if (shared != about.end()) return "As `" + shared->first + "`, for this filter.";
    }
    return "";
}

}  // namespace

std::vector<ConfigKey> config_keys() {
    json probe = json::object();
    const std::vector<ConfigKeyRecord> records = probe_reader(probe);
    const std::map<std::string, std::string>& about = config_key_descriptions();
    std::vector<ConfigKey> keys;
    std::set<std::string> seen;
    for (const ConfigKeyRecord& r : records) {
        ConfigKey k;
        k.key = key_of(r.path);
        if (!seen.insert(k.key).second) continue;
        if (r.type == "member") {
            const json& form = probe.at(pointer_of(r.path));
            if (form.is_object()) continue;  // a section: its keys follow
            k.type = form[0].is_object() ? "array of objects" : "array of numbers";
            k.default_value = nullptr;  // arrays are empty until given
        } else {
            k.type = r.type;
            k.default_value = r.default_value;
            k.lo = r.lo;
            k.hi = r.hi;
        }
        k.about = description_of(k.key, about);
        keys.push_back(k);
    }
    return keys;
}

std::vector<std::string> config_keys_without_description() {
    std::vector<std::string> out;
    for (const ConfigKey& k : config_keys())
        if (k.about.empty()) out.push_back(k.key);
    return out;
}

std::vector<std::string> config_descriptions_without_key() {
    std::set<std::string> known;
    for (const ConfigKey& k : config_keys()) known.insert(k.key);
    std::vector<std::string> out;
    for (const auto& d : config_key_descriptions())
        if (!known.count(d.first)) out.push_back(d.first);
    return out;
}

std::string config_keys_markdown(const std::vector<ConfigKey>& keys) {
    std::string md =
        "# Config keys (schema `battsim.config` version 1)\n\n"
        "Written by `battsim make-config --list-keys`, which reads them off the config reader itself:\n"
        "every key a config may hold, its type, its default (the default config's: the dissertation's\n"
        "1.55 Ah 4S pack with the hand-modified parameters; `battsim make-config` scales the pack's own)\n"
        "and the range the reader accepts. Every key is optional; an unknown key or a value out of\n"
        "range is an error naming the file, line and key. A test keeps this file equal to the\n"
        "command's output.\n";
    // One table per section, the sections in the order the reader first meets them (it reads
    // `estimator` after `monitor`, and the filters' sections amid `joint`'s keys).
    std::vector<std::string> sections;
    std::map<std::string, std::vector<const ConfigKey*>> by_section;
    for (const ConfigKey& k : keys) {
        const size_t dot = k.key.rfind('.');
        const std::string s = dot == std::string::npos ? "" : k.key.substr(0, dot);
        if (!by_section.count(s)) sections.push_back(s);
        by_section[s].push_back(&k);
    }
    for (const std::string& s : sections) {
        md += "\n## " + (s.empty() ? std::string("Top level") : "`" + s + "`") + "\n\n";
        md += "| key | type | default | range | meaning |\n|---|---|---|---|---|\n";
        for (const ConfigKey* k : by_section[s]) {
            const std::string name = s.empty() ? k->key : k->key.substr(s.size() + 1);
            const std::string def = k->default_value.is_null() ? "none" : "`" + k->default_value.dump() + "`";
            md += "| `" + name + "` | " + k->type + " | " + def + " | " + range_text(*k) + " | " + k->about + " |\n";
        }
    }
    return md;
}

json config_keys_json(const std::vector<ConfigKey>& keys) {
    json arr = json::array();
    for (const ConfigKey& k : keys) {
        json o = {{"key", k.key}, {"type", k.type}, {"default", k.default_value}, {"about", k.about}};
        if (k.type == "number" || k.type == "integer") o["range"] = {k.lo, k.hi};
        arr.push_back(o);
    }
    // The schema fields every other report carries (the list had gone without them).
    return json{{"schema", "battsim.config_keys"}, {"schema_version", 1}, {"battsim_version", BATTSIM_VERSION},
                {"config_schema", "battsim.config"}, {"config_version", 1}, {"keys", arr}};
}

}  // namespace host
}  // namespace battsim
