#include "experiments/sweep_checks.hpp"

#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "datasets/scene.hpp"  // InputError
#include "experiments/config.hpp"  // RunSpec

namespace bvhlab {

using nlohmann::json;

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& what) {
  throw InputError(source + ": " + key + ": " + what);
}

void needObject(const json& parent, const char* key, const std::string& source, const std::string& at) {
  if (!parent.contains(key)) fail(source, at, "missing");
  if (!parent[key].is_object()) fail(source, at, "not an object");
}

}  // namespace

void checkNesting(const json& value, const std::string& source, int maxDepth) {
  std::vector<std::pair<const json*, int>> todo{{&value, 1}};
  while (!todo.empty()) {
    const auto [v, depth] = todo.back();
    todo.pop_back();
    if (!v->is_structured()) continue;
    if (depth > maxDepth)
      throw InputError(source + ": JSON nested deeper than " + std::to_string(maxDepth) + " levels");
    for (const json& child : *v) todo.push_back({&child, depth + 1});
  }
}

void checkPlan(const json& plan, const std::string& source) {
  if (!plan.is_object() || !plan.contains("format") || plan["format"] != 1)
    throw InputError(source + ": not a bvhlab sweep plan (format 1)");
  needObject(plan, "experiment", source, "experiment");
  const json& experiment = plan["experiment"];
  if (experiment.contains("axes")) {
    if (!experiment["axes"].is_object()) fail(source, "experiment.axes", "not an object");
    for (const auto& [axis, values] : experiment["axes"].items())
      if (!values.is_array()) fail(source, "experiment.axes." + axis, "not a list");
  }
  needObject(plan, "config", source, "config");
  if (!plan["config"].contains("hash") || !plan["config"]["hash"].is_string())
    fail(source, "config.hash", "missing or not a string");
  if (!plan.contains("runs") || !plan["runs"].is_array()) fail(source, "runs", "missing or not a list");
  std::set<std::string> keys;
  const json& runs = plan["runs"];
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::string at = "runs[" + std::to_string(i) + "]";
    if (!runs[i].is_object()) fail(source, at, "not an object");
    // RunSpec::fromJson converts these to C++ integers with a cast, which is undefined for a
    // floating-point value outside the integer's range (UBSan: float-cast-overflow): every one of
    // them must be a number of int's magnitude (no setting means anything beyond).
    auto checkCast = [&](const json& v, const std::string& key) {
      if (v.is_number_float() && !(std::fabs(v.get<double>()) < 2147483648.0)) fail(source, key, v.dump() + " out of range");
    };
    if (runs[i].contains("index")) checkCast(runs[i]["index"], at + ".index");
    if (runs[i].contains("index") && runs[i]["index"].is_number() && runs[i]["index"].get<double>() < 0)
      fail(source, at + ".index", "negative");
    if (runs[i].contains("render") && runs[i]["render"].is_object())
      for (const auto& [k, v] : runs[i]["render"].items()) checkCast(v, at + ".render." + k);
    RunSpec spec;
    try {
      spec = RunSpec::fromJson(runs[i]);
    } catch (const json::exception& e) {
      // nlohmann's text names the missing key or the wrong type (e.g. "key 'render' not found").
      fail(source, at, std::string("not a run spec: ") + e.what());
    }
    if (spec.key.empty()) fail(source, at + ".key", "empty");
    if (!keys.insert(spec.key).second) fail(source, at + ".key", "\"" + spec.key + "\" names two runs");
  }
}

void checkRecord(const json& record, const std::string& source) {
  if (!record.is_object()) throw InputError(source + ": not a run record (not a JSON object)");
  if (!record.contains("key") || !record["key"].is_string() || record["key"].get<std::string>().empty())
    fail(source, "key", "missing, empty or not a string");
  if (!record.contains("status") || !record["status"].is_string()) fail(source, "status", "missing or not a string");
  for (const char* k : {"result", "machine"})
    if (record.contains(k) && !record[k].is_object()) fail(source, k, "not an object");
  for (const char* k : {"image", "visits_image"})
    if (record.contains(k) && !record[k].is_string() && !record[k].is_null()) fail(source, k, "not a string");
  // A row's replicate number (experiments/replicates.hpp): the record's, or one its result reports.
  if (record.contains("replicate") && !record["replicate"].is_number_integer())
    fail(source, "replicate", "not an integer");
  if (record.contains("result") && record["result"].contains("replicate") &&
      !record["result"]["replicate"].is_number_integer())
    fail(source, "result.replicate", "not an integer");
}

}  // namespace bvhlab
