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

const std::vector<UpdateStrategyInfo>& updateStrategies() {
  static const std::vector<UpdateStrategyInfo> table = {
      {"rebuild", "a new tree every frame with the chosen builder", makeRebuildStrategy},
      {"refit", "the first frame's tree, boxes refit bottom-up every frame", makeRefitStrategy},
      {"refit+rebuild:K", "rebuild on frames 0, K, 2K, ..., refit between (K >= 1)", makeRefitRebuildEveryStrategy},
      {"refit+rebuild:sah>R", "refit; rebuild when the SAH exceeds R x the last rebuild's (R >= 1)",
       makeRefitRebuildSahStrategy},
      {"refit+rotate", "refit with tree rotations that lower the SAH (Kopta et al. 2012)", makeRefitRotateStrategy},
  };
  return table;
}

namespace {

std::string validForms() {
  std::string list;
  for (const UpdateStrategyInfo& info : updateStrategies()) list += (list.empty() ? "" : ", ") + info.name;
  return list;
}

[[noreturn]] void refuse(const std::string& text, const std::string& why) {
  throw std::invalid_argument("update strategy '" + text + "': " + why + "; valid: " + validForms());
}

}  // namespace

UpdateSpec parseUpdateSpec(const std::string& text) {
  UpdateSpec spec;
  spec.text = text;
  if (text == "rebuild" || text == "refit" || text == "refit+rotate") {
    spec.name = text;
    return spec;
  }
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
