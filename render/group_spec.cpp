#include "render/group_spec.hpp"

#include <fstream>
#include <set>

#include "datasets/scene.hpp"  // InputError
#include "render/frame_stats.hpp"

namespace bvhlab {

using nlohmann::json;

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& what) {
  throw InputError(source + ": " + key + ": " + what);
}

int intField(const json& spec, const std::string& source, const char* name, int fallback, int lo, int hi) {
  if (!spec.contains(name)) return fallback;
  const json& v = spec[name];
  // An integral JSON number only (5.0 is read as a float by the parser and refused too). The parser
  // keeps every non-negative integer as unsigned: those are compared as unsigned (lo >= 1 here),
  // before a conversion could wrap one past int64's range.
  if (!v.is_number_integer()) fail(source, name, "not an integer");
  const bool outside = v.is_number_unsigned() ? v.get<uint64_t>() > uint64_t(hi) || v.get<uint64_t>() < uint64_t(lo)
                                              : v.get<int64_t>() < lo || v.get<int64_t>() > hi;
  if (outside) fail(source, name, v.dump() + " outside " + std::to_string(lo) + ".." + std::to_string(hi));
  const int64_t x = v.get<int64_t>();
  return int(x);
}

double numberField(const json& spec, const std::string& source, const char* name, double fallback) {
  if (!spec.contains(name)) return fallback;
  if (!spec[name].is_number()) fail(source, name, "not a number");
  return spec[name].get<double>();
}

bool boolField(const json& spec, const std::string& source, const char* name, bool fallback) {
  if (!spec.contains(name)) return fallback;
  if (!spec[name].is_boolean()) fail(source, name, "not true or false");
  return spec[name].get<bool>();
}

std::string stringField(const json& spec, const std::string& source, const std::string& name, const std::string& fallback) {
  if (!spec.contains(name)) return fallback;
  if (!spec[name].is_string()) fail(source, name, "not a string");
  return spec[name].get<std::string>();
}

}  // namespace

GroupSpec parseGroupSpec(const json& spec, const std::string& source) {
  if (!spec.is_object()) throw InputError(source + ": a group file is a JSON object");
  if (!spec.contains("runs") || !spec["runs"].is_array() || spec["runs"].empty())
    fail(source, "runs", "needs a non-empty list of runs");
  GroupSpec out;
  GroupSettings& g = out.settings;
  g.minFrames = intField(spec, source, "min_frames", 10, 1, 100000);
  g.maxFrames = intField(spec, source, "max_frames", g.minFrames, g.minFrames, 100000);
  g.targetPct = numberField(spec, source, "target_ci_pct", 2.0);
  if (!(g.targetPct > 0.0 && g.targetPct <= 100.0)) fail(source, "target_ci_pct", "outside (0, 100]");
  // A time budget for the rounds: a group of few or fast runs gets more rounds than a big one.
  g.maxSeconds = numberField(spec, source, "max_seconds", 0.0);
  if (!(g.maxSeconds >= 0.0)) fail(source, "max_seconds", "must be >= 0");
  g.clipControl = boolField(spec, source, "aa_control", true);
  g.wantControl = g.clipControl && g.maxFrames >= int(kMinValuesForInterval);
  // One program per distinct shader text (render/program_cache.hpp); false: every run compiles its own.
  out.sharePrograms = boolField(spec, source, "share_programs", true);
  // Each run drawn by this many separately compiled copies of its program (each copy shared by the
  // runs of one shader text): the findings' intervals then span code placements (6 or more copies).
  g.programCopies = intField(spec, source, "program_copies", 1, 1, 64);
  g.session = stringField(spec, source, "session", "unnamed");
  out.command = stringField(spec, source, "command", "render");
  if (out.command != "render" && out.command != "trace")
    fail(source, "command", "\"" + out.command + "\" (render | trace)");

  std::set<std::string> keys;
  const json& runs = spec["runs"];
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::string at = "runs[" + std::to_string(i) + "]";
    const json& run = runs[i];
    if (!run.is_object()) fail(source, at, "not an object");
    GroupRunSpec r;
    r.key = stringField(run, source + ": " + at, "key", "");
    if (r.key.empty()) fail(source, at, "a run without a \"key\"");
    if (!keys.insert(r.key).second) fail(source, at + ".key", "\"" + r.key + "\" names two runs");
    const json* args = run.contains("args") ? &run["args"] : nullptr;
    bool ok = args && args->is_array();
    if (ok)
      for (const json& a : *args) ok = ok && a.is_string();
    if (ok)
      for (const json& a : *args) r.args.push_back(a.get<std::string>());
    else
      r.error = source + ": " + at + ".args: " + (args ? "not a list of strings" : "missing");
    out.runs.push_back(std::move(r));
  }
  return out;
}

GroupSpec readGroupSpec(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FileError(file + ": cannot open the group file");
  json spec;
  try {
    spec = json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(file + ": not valid JSON (" + e.what() + ")");
  }
  return parseGroupSpec(spec, file);
}

}  // namespace bvhlab
