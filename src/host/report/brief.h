// What `battsim replay` prints for people: a few lines about a summary, the texts a ground
// station was told, the charger check. Read off the summary JSON alone, so a summary
// written earlier reads the same.
#pragma once
#include <ostream>

#include <nlohmann/json.hpp>

namespace battsim {
namespace host {

// Human-readable few lines about a summary.
void print_brief(const nlohmann::json& summary, std::ostream& out);
// The summary's `said` (replay --said): each text with its time.
void print_said(const nlohmann::json& said, const nlohmann::json& flight, std::ostream& out);
// The summary's `charger_check` as one line for people.
void print_charger_check(const nlohmann::json& check, std::ostream& out);

}  // namespace host
}  // namespace battsim
