// Compares two summaries field by field with a numeric tolerance: the regression check
// behind golden tests and `batch --compare`.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace battsim {
namespace host {

struct JsonDifference {
    std::string path;      // JSON pointer-like: /flight/capacity_ah/mean
    std::string expected;  // dumped value, or "(missing)"
    std::string actual;
};

struct CompareOptions {
    double relative_tolerance = 1e-6;
    double absolute_tolerance = 1e-9;
    std::vector<std::string> ignore;  // paths to skip, e.g. "/input/path"
};

std::vector<JsonDifference> compare_json(const nlohmann::json& expected, const nlohmann::json& actual,
                                         const CompareOptions& options);

}  // namespace host
}  // namespace battsim
