// The viewer's settings and names: what each live setting accepts, script key names, the GLFW
// session (render/viewer_app.hpp).
#include "render/viewer_app.hpp"

#ifdef BVHLAB_VIEWER

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "builders/builder.hpp"
#include "layout/layouts.hpp"
#include "layout/pack_two_level.hpp"
#include "layout/triangle_formats.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab::viewer_detail {

double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The values a named setting cycles through (keys, combos); empty for numeric settings.
std::vector<std::string> choices(const std::string& what, const std::string& layout, const std::string& triangles) {
  std::vector<std::string> names;
  if (what == "builder")
    for (const BuilderInfo& b : builders()) names.push_back(b.name);
  if (what == "kernel")
    for (const KernelInfo& k : kernelsFor(layout)) names.push_back(k.name);
  if (what == "view") names = kViews;
  if (what == "aa") names = kAaModes;
  if (what == "update") {
    names = kUpdateSpecs;
    // Two-level trees: with a layout that has a two-level walk and raw triangles (blas=refit takes
    // every scene: rigid objects' BLASes are built once whatever the policy).
    if (twoLevelLayoutSupported(findLayout(layout).name) && findTriangleFormat(triangles).name == "raw")
      names.push_back("two-level:blas=refit");
  }
  if (what == "robust") {
    // Only the variants the session's triangle format can run (precomputed: no watertight test).
    const bool watertightOk = findTriangleFormat(triangles).watertight;
    for (const std::string& n : robustnessNames())
      if (watertightOk || parseRobustness(n).triangle != TriangleTest::Watertight) names.push_back(n);
  }
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// "" when `value` is valid for the setting (one of scriptSettings()), else what is wrong.
std::string settingError(const std::string& what, const std::string& value, const std::string& layout,
                         const std::string& triangles) {
  if (what == "leaf_size") {
    std::optional<int> v = parseNumber<int>(value);
    return v && *v >= 1 && *v <= int(kMaxLeafSize) ? "" : "leaf_size must be in 1.." + std::to_string(kMaxLeafSize);
  }
  if (what == "depth") {
    std::optional<int> v = parseNumber<int>(value);
    return v && *v >= 1 && *v <= kMaxDepth ? "" : "depth must be in 1.." + std::to_string(kMaxDepth);
  }
  if (what == "scale") {
    std::optional<float> v = parseNumber<float>(value);
    return v && *v >= 0.05f && *v <= 1.0f ? "" : "scale must be in 0.05..1";
  }
  if (what == "update") {  // any spec the strategies take, not only those U cycles through
    try {
      if (parseUpdateSpec(value).name != "two-level") return "";
      if (!twoLevelLayoutSupported(findLayout(layout).name))
        return "update '" + value + "': layout '" + layout + "' has no two-level walk (layouts with one: v1, bvh2-cb)";
      if (findTriangleFormat(triangles).name != "raw")
        return "update '" + value + "': a two-level tree takes raw triangles, not " + triangles;
      return "";
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
  }
  if (what == "clip_frame") {  // checked against the clip's length once the scene is loaded
    std::optional<int> v = parseNumber<int>(value);
    return v && *v >= 0 ? "" : "clip_frame must be a frame number >= 0";
  }
  const std::vector<std::string> names = choices(what, layout, triangles);
  if (names.empty()) return "unknown setting '" + what + "' (" + joined(scriptSettings()) + ")";
  if (std::find(names.begin(), names.end(), value) == names.end()) {
    const std::vector<std::string> all = robustnessNames();
    if (what == "robust" && std::find(all.begin(), all.end(), value) != all.end())
      return "robust '" + value + "' uses the watertight triangle test, which triangle format '" + triangles +
             "' cannot run (valid: " + joined(names) + ")";
    return "unknown " + what + " '" + value + "' (valid: " + joined(names) + ")";
  }
  return "";
}

// Script key names -> GLFW keys (docs/viewer.md lists them).
int keyFromName(const std::string& name) {
  if (name.size() == 1 && name[0] >= 'A' && name[0] <= 'Z') return GLFW_KEY_A + (name[0] - 'A');
  if (name.size() == 1 && name[0] >= '0' && name[0] <= '9') return GLFW_KEY_0 + (name[0] - '0');
  if (name.size() >= 2 && name[0] == 'F' && std::all_of(name.begin() + 1, name.end(), ::isdigit)) {
    int n = std::stoi(name.substr(1));
    if (n >= 1 && n <= 12) return GLFW_KEY_F1 + n - 1;
  }
  static const std::map<std::string, int> named = {
      {"TAB", GLFW_KEY_TAB},         {"ESCAPE", GLFW_KEY_ESCAPE},       {"SPACE", GLFW_KEY_SPACE},
      {"LBRACKET", GLFW_KEY_LEFT_BRACKET}, {"RBRACKET", GLFW_KEY_RIGHT_BRACKET},
      {"COMMA", GLFW_KEY_COMMA},     {"PERIOD", GLFW_KEY_PERIOD},       {"MINUS", GLFW_KEY_MINUS},
      {"EQUAL", GLFW_KEY_EQUAL}};
  auto it = named.find(name);
  return it == named.end() ? GLFW_KEY_UNKNOWN : it->second;
}

// "SHIFT+B", "CTRL+1" -> key + modifier bits; GLFW_KEY_UNKNOWN when the name is not a key.
std::pair<int, int> parseKeyChord(std::string name) {
  int mods = 0;
  for (;;) {
    if (name.rfind("SHIFT+", 0) == 0) mods |= GLFW_MOD_SHIFT, name.erase(0, 6);
    else if (name.rfind("CTRL+", 0) == 0) mods |= GLFW_MOD_CONTROL, name.erase(0, 5);
    else break;
  }
  return {keyFromName(name), mods};
}

nlohmann::json cameraJson(const Camera& c) {
  return {{"eye", {c.eye.x, c.eye.y, c.eye.z}},
          {"target", {c.target.x, c.target.y, c.target.z}},
          {"up", {c.up.x, c.up.y, c.up.z}},
          {"fov", c.fovDeg}};
}

std::string lastGlfwError;

namespace {

void onGlfwError(int code, const char* description) { lastGlfwError = description ? description : "unknown"; }

const char* kNoDisplayHelp =
    "`bvhlab view` needs a display. For images without one use `bvhlab render` (headless); to use the "
    "viewer here, start an X server, e.g. `xvfb-run -a bvhlab view ...`";

}  // namespace

GlfwSession::GlfwSession() {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland))
    throw NoDisplayError(std::string("no display (DISPLAY is not set). ") + kNoDisplayHelp);
  glfwSetErrorCallback(onGlfwError);
  if (!glfwInit()) throw NoDisplayError("cannot open the display (" + lastGlfwError + "). " + kNoDisplayHelp);
}

GlfwSession::~GlfwSession() { glfwTerminate(); }

RayStats summarize(const std::vector<glm::uvec4>& stats) {
  uint64_t visits = 0, tests = 0, rays = 0;
  RayStats s;
  for (const glm::uvec4& p : stats) {  // encoding as in render_command.cpp: z = rays | overflow << 31
    visits += p.x;
    tests += p.y;
    rays += p.z & 0x7FFFFFFFu;
    s.overflows += p.z >> 31;
  }
  s.visitsPerRay = rays ? double(visits) / double(rays) : 0.0;
  s.testsPerRay = rays ? double(tests) / double(rays) : 0.0;
  s.valid = true;
  return s;
}

}  // namespace bvhlab::viewer_detail

#endif  // BVHLAB_VIEWER
