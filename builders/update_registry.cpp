// The update-strategy registry, the spec parser and makeUpdateStrategy (builders/update.hpp).
// Adding a strategy: write builders/update_NAME.cpp with its factory, declare it here and add one line
// to the table.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "builders/builder.hpp"
#include "builders/update.hpp"

namespace bvhlab {

// Defined in builders/update_<name>.cpp.
std::unique_ptr<UpdateStrategy> makeRebuildStrategy(const UpdateSpec&, const UpdateOptions&);
std::unique_ptr<UpdateStrategy> makeRefitStrategy(const UpdateSpec&, const UpdateOptions&);
std::unique_ptr<UpdateStrategy> makeRefitRebuildEveryStrategy(const UpdateSpec&, const UpdateOptions&);
std::unique_ptr<UpdateStrategy> makeRefitRebuildSahStrategy(const UpdateSpec&, const UpdateOptions&);
std::unique_ptr<UpdateStrategy> makeRefitRotateStrategy(const UpdateSpec&, const UpdateOptions&);

namespace {

// two-level keeps a tree per object instance: the scene's instances drive it (layout/two_level_update.hpp),
// a flat triangle list cannot.
std::unique_ptr<UpdateStrategy> makeTwoLevelFlatRefusal(const UpdateSpec& spec, const UpdateOptions&) {
  throw std::invalid_argument("update strategy '" + spec.text +
                              "' keeps a tree per object instance and runs over an animated scene's instances "
                              "(`bvhlab trace --update`); render --update and a flat triangle list take the "
                              "single-tree strategies");
}

}  // namespace

const std::vector<UpdateStrategyInfo>& updateStrategies() {
  static const std::vector<UpdateStrategyInfo> table = {
      {"rebuild", "a new tree every frame with the chosen builder", makeRebuildStrategy},
      {"refit", "the first frame's tree, boxes refit bottom-up every frame", makeRefitStrategy},
      {"refit+rebuild:K", "rebuild on frames 0, K, 2K, ..., refit between (K >= 1)", makeRefitRebuildEveryStrategy},
      {"refit+rebuild:sah>R", "refit; rebuild when the SAH exceeds R x the last rebuild's (R >= 1)",
       makeRefitRebuildSahStrategy},
      {"refit+rotate", "refit with tree rotations that lower the SAH (Kopta et al. 2012)", makeRefitRotateStrategy},
      {"two-level", "a TLAS rebuilt every frame over per-object BLASes kept static, refit or rebuilt",
       makeTwoLevelFlatRefusal, "[:blas=static|refit|rebuild][,tlas=BUILDER]"},
  };
  return table;
}

namespace {

std::string validForms() {
  std::string list;
  for (const UpdateStrategyInfo& info : updateStrategies()) list += (list.empty() ? "" : ", ") + info.name + info.options;
  return list;
}

[[noreturn]] void refuse(const std::string& text, const std::string& why) {
  throw std::invalid_argument("update strategy '" + text + "': " + why + "; valid: " + validForms());
}

}  // namespace

// two-level[:key=value,...] (builders/update.hpp).
static UpdateSpec parseTwoLevel(const std::string& text) {
  UpdateSpec spec;
  spec.text = text;
  spec.name = "two-level";
  if (text == "two-level") return spec;
  const std::string prefix = "two-level:";
  if (text.rfind(prefix, 0) != 0) refuse(text, "unknown strategy");
  std::string rest = text.substr(prefix.size());
  bool sawBlas = false, sawTlas = false;
  while (true) {
    const size_t comma = rest.find(',');
    const std::string item = rest.substr(0, comma);
    const size_t eq = item.find('=');
    const std::string key = item.substr(0, eq), value = eq == std::string::npos ? "" : item.substr(eq + 1);
    if (eq == std::string::npos || value.empty())
      refuse(text, "two-level option '" + item + "' is not key=value (keys: blas, tlas)");
    if (key == "blas") {
      if (sawBlas) refuse(text, "two-level option blas given twice");
      if (value != "static" && value != "refit" && value != "rebuild")
        refuse(text, "blas=" + value + ": the BLAS policy is static, refit or rebuild");
      spec.blas = value;
      sawBlas = true;
    } else if (key == "tlas") {
      if (sawTlas) refuse(text, "two-level option tlas given twice");
      try {
        findBuilder(value);
      } catch (const std::invalid_argument& e) {
        refuse(text, std::string("tlas=") + value + ": " + e.what());
      }
      spec.tlasBuilder = value;
      sawTlas = true;
    } else {
      refuse(text, "unknown two-level option '" + key + "' (keys: blas, tlas)");
    }
    if (comma == std::string::npos) break;
    rest = rest.substr(comma + 1);
  }
  return spec;
}

UpdateSpec parseUpdateSpec(const std::string& text) {
  UpdateSpec spec;
  spec.text = text;
  if (text == "rebuild" || text == "refit" || text == "refit+rotate") {
    spec.name = text;
    return spec;
  }
  if (text.rfind("two-level", 0) == 0) return parseTwoLevel(text);
  const std::string prefix = "refit+rebuild:";
  if (text.rfind(prefix, 0) != 0) refuse(text, "unknown strategy");
  const std::string arg = text.substr(prefix.size());
  if (arg.rfind("sah>", 0) == 0) {
    const std::string number = arg.substr(4);
    // strtod accepts leading spaces, "inf" and "nan": only a plain finite number is taken.
    char* end = nullptr;
    const double ratio = number.empty() || std::isspace(static_cast<unsigned char>(number[0]))
                             ? 0.0 : std::strtod(number.c_str(), &end);
    if (number.empty() || end != number.c_str() + number.size() || !std::isfinite(ratio))
      refuse(text, "R in sah>R must be a number, got '" + number + "'");
    // R < 1 would rebuild whenever the refit tree is not better than the last rebuild's, i.e. about
    // every frame: "rebuild" says that.
    if (!(ratio >= 1.0)) refuse(text, "R in sah>R must be >= 1 (the refit tree's SAH over the last rebuild's)");
    spec.name = "refit+rebuild:sah>R";
    spec.sahRatio = ratio;
    return spec;
  }
  uint32_t every = 0;
  const auto [end, error] = std::from_chars(arg.data(), arg.data() + arg.size(), every);
  if (arg.empty() || error != std::errc() || end != arg.data() + arg.size())
    refuse(text, "K in refit+rebuild:K must be a whole number of frames (1 to 4294967295), got '" + arg + "'");
  if (every < 1) refuse(text, "K in refit+rebuild:K must be >= 1 (a rebuild every K frames)");
  spec.name = "refit+rebuild:K";
  spec.every = every;
  return spec;
}

std::unique_ptr<UpdateStrategy> makeUpdateStrategy(const std::string& text, const UpdateOptions& options) {
  const UpdateSpec spec = parseUpdateSpec(text);
  reviewBuildOptions(options.builder, options.build);  // throws for an unknown builder or bad options
  for (const UpdateStrategyInfo& info : updateStrategies())
    if (info.name == spec.name) return info.make(spec, options);
  refuse(text, "no registered strategy");  // parseUpdateSpec names only registered ones
}

}  // namespace bvhlab
