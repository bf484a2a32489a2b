#include "experiments/findings_command.hpp"

#include <cmath>
#include <fstream>
#include <iostream>
#include <set>

#include "datasets/scene.hpp"
#include "experiments/findings.hpp"
#include "experiments/sweep_dir.hpp"
#include "render/exit_status.hpp"

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json readJsonFile(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw FileError(file.string() + ": cannot be read");
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded()) throw InputError(file.string() + ": not valid JSON");
  return j;
}

std::string shortValue(const json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

}  // namespace

std::optional<std::string> firstJsonDifference(const json& have, const json& want, double relTol,
                                               const std::string& path) {
  const std::string where = path.empty() ? "(top)" : path;
  if (have.is_number() && want.is_number()) {
    const double a = have.get<double>(), b = want.get<double>();
    // Both written by one code path in doubles: they differ only where a C library's log/exp differs
    // in its last bits, far below relTol. A NaN never agrees (the comparison below is false for it).
    if (a == b || std::abs(a - b) <= relTol * std::max(std::abs(a), std::abs(b))) return std::nullopt;
    return where + ": " + shortValue(have) + " != " + shortValue(want);
  }
  if (have.type() != want.type()) return where + ": " + shortValue(have) + " != " + shortValue(want);
  if (have.is_object()) {
    std::set<std::string> keys;
    for (const auto& [k, v] : have.items()) keys.insert(k);
    for (const auto& [k, v] : want.items()) keys.insert(k);
    for (const std::string& k : keys) {
      const std::string sub = path.empty() ? k : path + "." + k;
      if (!have.contains(k)) return sub + ": missing (the rows give " + shortValue(want[k]) + ")";
      if (!want.contains(k)) return sub + ": not given by the rows (" + shortValue(have[k]) + ")";
      if (auto d = firstJsonDifference(have[k], want[k], relTol, sub)) return d;
    }
    return std::nullopt;
  }
  if (have.is_array()) {
    if (have.size() != want.size())
      return where + ": " + std::to_string(have.size()) + " entries, the rows give " + std::to_string(want.size());
    for (size_t i = 0; i < have.size(); ++i)
      if (auto d = firstJsonDifference(have[i], want[i], relTol, path + "[" + std::to_string(i) + "]")) return d;
    return std::nullopt;
  }
  if (have != want) return where + ": " + shortValue(have) + " != " + shortValue(want);
  return std::nullopt;
}

int findingsCommand(const fs::path& dir, bool check) {
  try {
    const fs::path resultsFile = dir / "results.json";
    const json results = readJsonFile(resultsFile);
    if (!results.contains("rows") || !results["rows"].is_array())
      throw InputError(resultsFile.string() + ": rows: missing or not a list");
    const json experiment = results.value("experiment", json::object());
    if (!experiment.is_object()) throw InputError(resultsFile.string() + ": experiment: not an object");
    const json axes = experiment.value("axes", json::object());
    const json findingsCfg = experiment.value("findings", json::object());
    const json baselines = findingsCfg.is_object() ? findingsCfg.value("baseline", json::object()) : json::object();
    const json now = computeFindings(results["rows"], axes, baselines);
    const fs::path findingsFile = dir / "findings.json";
    if (!check) {
      writeFileAtomic(findingsFile, now.dump(1) + "\n", false);
      std::cout << findingsFile.string() << "\n";
      return 0;
    }
    const json committed = readJsonFile(findingsFile);
    // The same relative tolerance docs/results/ always used for re-derived figures: far above a last-bit
    // difference of log/exp between C libraries, far below the three significant digits docs print.
    if (auto d = firstJsonDifference(committed, now, 1e-9)) {
      std::cerr << "bvhlab: error: " << findingsFile.string() << " does not follow from " << resultsFile.string()
                << " with the current rules: " << *d << " (rewrite it: bvhlab findings " << dir.string() << ")\n";
      return kExitFailure;
    }
    std::cout << findingsFile.string() << ": follows from its rows (" << now["comparisons"].size()
              << " comparisons)\n";
    return 0;
  } catch (const std::exception& e) {
    return reportError(e);
  }
}

}  // namespace bvhlab
