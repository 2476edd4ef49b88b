#include "host/report/json_compare.h"

#include <algorithm>
#include <cmath>

namespace battsim {
namespace host {

namespace {

using nlohmann::json;

void walk(const json& e, const json& a, const std::string& path, const CompareOptions& o,
          std::vector<JsonDifference>& out) {
    if (std::find(o.ignore.begin(), o.ignore.end(), path) != o.ignore.end()) return;
    if (e.is_number() && a.is_number()) {
        const double x = e.get<double>(), y = a.get<double>();
        if (std::fabs(x - y) > o.absolute_tolerance + o.relative_tolerance * std::max(std::fabs(x), std::fabs(y))) {
            out.push_back({path, e.dump(), a.dump()});
        }
        return;
    }
    if (e.type() != a.type()) {
        out.push_back({path, e.dump(), a.dump()});
        return;
    }
    if (e.is_object()) {
        for (auto it = e.begin(); it != e.end(); ++it) {
            const std::string p = path + "/" + it.key();
            auto f = a.find(it.key());
            if (f == a.end()) {
                if (std::find(o.ignore.begin(), o.ignore.end(), p) == o.ignore.end())
                    out.push_back({p, it.value().dump(), "(missing)"});
            } else {
                walk(it.value(), *f, p, o, out);
            }
        }
        for (auto it = a.begin(); it != a.end(); ++it) {
            const std::string p = path + "/" + it.key();
            if (!e.contains(it.key()) && std::find(o.ignore.begin(), o.ignore.end(), p) == o.ignore.end())
                out.push_back({p, "(missing)", it.value().dump()});
        }
        return;
    }
    if (e.is_array()) {
        const size_t n = std::max(e.size(), a.size());
        for (size_t i = 0; i < n; ++i) {
            const std::string p = path + "/" + std::to_string(i);
            if (i >= e.size()) out.push_back({p, "(missing)", a[i].dump()});
            else if (i >= a.size()) out.push_back({p, e[i].dump(), "(missing)"});
            else walk(e[i], a[i], p, o, out);
        }
        return;
    }
    if (e != a) out.push_back({path, e.dump(), a.dump()});
}

}  // namespace

std::vector<JsonDifference> compare_json(const json& expected, const json& actual, const CompareOptions& options) {
    std::vector<JsonDifference> out;
    walk(expected, actual, "", options, out);
    return out;
}

}  // namespace host
}  // namespace battsim
