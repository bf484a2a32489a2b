// `bvhlab findings DIR [--check]`: the comparisons of a result directory computed again from its
// rows (DIR/results.json: the per-round times, the config's axis order and baselines) with the
// current rules (experiments/findings.hpp, docs/measurement.md).
//   without --check  DIR/findings.json is rewritten (atomically); the report is left as it was;
//   with --check     nothing is written; exit 1 naming the first place where DIR/findings.json differs
//                    from what the rows give now (numbers compared to a relative 1e-9), 0 when it
//                    follows from them. docs/results/ uses this so no interval quoted in docs/ is
//                    more than what its committed rows give.
#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace bvhlab {

int findingsCommand(const std::filesystem::path& dir, bool check);

// The first place where `have` differs from `want` ("comparisons[3].ci_low: 0.98 != 0.97"), or
// nullopt when they agree: same keys, same strings and booleans, numbers within `relTol` of each other.
std::optional<std::string> firstJsonDifference(const nlohmann::json& have, const nlohmann::json& want,
                                               double relTol, const std::string& path = "");

}  // namespace bvhlab
