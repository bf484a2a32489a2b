#include "render/viewer.hpp"

#ifdef BVHLAB_VIEWER  // set by CMake where GLFW and Dear ImGui are linked

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <type_traits>

#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <nlohmann/json.hpp>

#include "datasets/image_io.hpp"
#include "datasets/scene_io.hpp"
#include "render/fly_camera.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "render/heatmap.hpp"
#include "render/smaa.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

const std::vector<std::string> kViews = {"shaded", "normal", "depth", "primid", "visits"};
// The anti-aliasing modes of `bvhlab render --aa`, SMAA by preset name (render/smaa.hpp).
const std::vector<std::string> kAaModes = {"none",       "smaa-low", "smaa-medium", "smaa-high",
                                           "smaa-ultra", "ssaa4",    "ssaa16"};
const std::vector<float> kScales = {0.125f, 0.25f, 0.375f, 0.5f, 0.75f, 1.0f};
constexpr int kMaxDepth = 16;
constexpr int kRollingWindow = 31;      // frames in the rolling median (odd: a true middle element)
constexpr int kGraphLength = 240;       // rolling medians kept for the graph
constexpr double kScriptDt = 1.0 / 30;  // seconds per frame in scripted mode: movement is reproducible
constexpr float kLookDegPerPixel = 0.1f;

bool isSmaa(const std::string& aa) { return aa.rfind("smaa-", 0) == 0; }
int ssaaGridOf(const std::string& aa) { return aa == "ssaa4" ? 2 : aa == "ssaa16" ? 4 : 1; }

template <typename T>
std::string shortest(T v) {  // shortest round-trip text of a number
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, end);
}

// The whole string as a number; nullopt for anything else ("4x", "", "nan").
template <typename T>
std::optional<T> parseNumber(const std::string& text) {
  T v{};
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  if constexpr (std::is_floating_point_v<T>)
    if (!std::isfinite(v)) return std::nullopt;
  return v;
}

// The values a named setting cycles through (keys, combos); empty for numeric settings.
std::vector<std::string> choices(const std::string& what) {
  std::vector<std::string> names;
  if (what == "builder")
    for (const BuilderInfo& b : builders()) names.push_back(b.name);
  if (what == "kernel")
    for (const KernelInfo& k : kernels()) names.push_back(k.name);
  if (what == "view") names = kViews;
  if (what == "aa") names = kAaModes;
  if (what == "robust") names = robustnessNames();
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// "" when `value` is valid for the setting (one of scriptSettings()), else what is wrong.
std::string settingError(const std::string& what, const std::string& value) {
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
  const std::vector<std::string> names = choices(what);
  if (names.empty()) return "unknown setting '" + what + "' (" + joined(scriptSettings()) + ")";
  if (std::find(names.begin(), names.end(), value) == names.end())
    return "unknown " + what + " '" + value + "' (valid: " + joined(names) + ")";
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
void onGlfwError(int code, const char* description) { lastGlfwError = description ? description : "unknown"; }

const char* kNoDisplayHelp =
    "`bvhlab view` needs a display. For images without one use `bvhlab render` (headless); to use the "
    "viewer here, start an X server, e.g. `xvfb-run -a bvhlab view ...`";

// glfwInit/glfwTerminate as a scope.
struct GlfwSession {
  GlfwSession() {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland))
      throw NoDisplayError(std::string("no display (DISPLAY is not set). ") + kNoDisplayHelp);
    glfwSetErrorCallback(onGlfwError);
    if (!glfwInit()) throw NoDisplayError("cannot open the display (" + lastGlfwError + "). " + kNoDisplayHelp);
  }
  ~GlfwSession() { glfwTerminate(); }
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

struct RayStats {
  double visitsPerRay = 0.0, testsPerRay = 0.0;
  uint64_t overflows = 0;
  bool valid = false;
};

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

class Viewer {
 public:
  explicit Viewer(const ViewerOptions& o);
  ~Viewer();
  int run();

 private:
  // input
  static Viewer& self(GLFWwindow* w) { return *static_cast<Viewer*>(glfwGetWindowUserPointer(w)); }
  static void keyCallback(GLFWwindow* w, int key, int, int action, int mods);
  static void cursorCallback(GLFWwindow* w, double x, double y);
  static void scrollCallback(GLFWwindow* w, double, double y);
  void handleKey(int key, int mods);
  bool held(int key) const;
  void setCapture(bool on);
  void applyScript();
  void moveCamera(double dt);

  // configuration
  void cycle(const std::string& what, int step);
  void set(const std::string& what, const std::string& value);  // value checked by settingError
  void ensureRenderers();
  void logSwitch(const std::string& what, const std::string& value);
  ShaderOptions shaderOptions(bool countStats) const;

  // frame
  void renderFrame();
  bool heatmapShown() const { return view_ == "visits" && prepared_->soup.size() > 0; }
  unsigned displayedTexture() const;         // the frame's final GPU image (trace or SMAA output)
  std::vector<uint8_t> readDisplayed() const;  // its pixels (RGBA8, bottom-up); a GPU read-back
  void present();
  void drawOverlay();
  void saveScreenshot(const std::string& path);
  void saveWindowScreenshot(const std::string& path);
  void toggleRecording();
  void startReplay(const std::string& path);

  ViewerOptions opt_;
  Scene original_;
  std::unique_ptr<GlfwSession> glfw_;
  GLFWwindow* window_ = nullptr;
  bool imgui_ = false;
  std::string glRenderer_;

  // live configuration
  std::string builder_, kernel_, view_, aa_, robust_;
  int leafSize_ = 4, depth_ = 5;
  std::string optimize_;  // ViewerOptions::optimize, applied after every rebuild
  float scale_ = 1.0f;
  bool needRebuild_ = true, needRenderer_ = true, needSmaa_ = true;

  std::unique_ptr<PreparedScene> prepared_;
  std::unique_ptr<GpuRenderer> gpu_, statsGpu_;
  std::unique_ptr<SmaaPass> smaa_;  // only while an SMAA mode is on
  int renderW_ = 0, renderH_ = 0;
  double prepareMs_ = 0.0, firstFrameMs_ = 0.0;
  bool firstFramePending_ = false, statsStale_ = true;
  Clock::time_point lastStats_;
  RayStats rayStats_;

  // display: the frame's texture is blitted straight to the window; only the heatmap (computed on
  // the CPU from the counters) and --readback-present go through image_ and the upload texture.
  unsigned displayTex_ = 0, displayFbo_ = 0;
  int displayW_ = 0, displayH_ = 0;
  std::vector<uint8_t> image_;
  std::string pendingWindowShot_;

  // camera and input
  FlyCamera camera_;
  float speed_ = 1.0f;  // world units per second
  bool captured_ = false;
  glm::dvec2 lastCursor_{0.0};
  bool haveCursor_ = false;
  std::map<int, int> holdUntil_;  // scripted held keys: key -> last frame held
  std::optional<ViewerScript> script_;
  size_t scriptNext_ = 0;
  std::optional<Camera> bookmarks_[4];

  // camera paths
  bool recording_ = false;
  CameraPath recorded_;
  double recordStart_ = 0.0;
  CameraPath replay_;
  size_t replayNext_ = 0;
  bool replaying_ = false;

  // timing
  int frame_ = 0, rendered_ = 0;
  double time_ = 0.0;  // seconds since start (scripted: frame * kScriptDt)
  bool quit_ = false;
  std::string pendingScreenshot_;
  std::deque<double> recentMs_, recentAaMs_, recentLoopMs_;  // frame = trace + AA pass
  std::deque<double> recentPresentMs_;  // getting the frame onto the window (read-back included)
  double readbackMs_ = 0.0;
  std::vector<float> graph_;
  double lastDrawMs_ = 0.0, lastAaMs_ = 0.0, lastLoopMs_ = 0.0;
  bool frameCounted_ = false;  // this frame's times are steady-state (not the first after a change)
  nlohmann::json switches_ = nlohmann::json::array();
  std::vector<double> sinceSwitchMs_, sinceSwitchAaMs_;
  std::string status_;
};

Viewer::Viewer(const ViewerOptions& o) : opt_(o) {
  // Validate everything before a window appears.
  findBuilder(o.builder);
  findKernel(o.kernel);
  if (o.leafSize < 1 || o.leafSize > int(kMaxLeafSize))
    throw std::invalid_argument("--leaf-size must be in 1.." + std::to_string(kMaxLeafSize));
  if (o.depth && (*o.depth < 1 || *o.depth > kMaxDepth))
    throw std::invalid_argument("--depth must be in 1.." + std::to_string(kMaxDepth));
  if (std::find(kViews.begin(), kViews.end(), o.view) == kViews.end())
    throw std::invalid_argument("--view must be one of shaded, normal, depth, primid, visits");
  if (!(o.resolutionScale >= 0.05f && o.resolutionScale <= 1.0f))
    throw std::invalid_argument("--scale must be in 0.05..1");
  if (std::string e = settingError("aa", o.aa); !e.empty()) throw std::invalid_argument("--aa: " + e);
  if (std::string e = settingError("robust", o.robust); !e.empty()) throw std::invalid_argument("--robust: " + e);
  if (o.frames < 0) throw std::invalid_argument("--frames must be >= 0");
  if ((o.width && (*o.width < 1 || *o.width > 16384)) || (o.height && (*o.height < 1 || *o.height > 16384)))
    throw std::invalid_argument("--width/--height must be in 1..16384");
  if (!o.script.empty()) {
    script_ = loadViewerScript(o.script);
    for (const ScriptEvent& e : script_->events)
      if ((e.kind == ScriptEvent::Kind::Key || e.kind == ScriptEvent::Kind::Hold) &&
          parseKeyChord(e.key).first == GLFW_KEY_UNKNOWN)
        throw InputError(script_->file + ":" + std::to_string(e.line) + ": unknown key '" + e.key +
                         "' (see docs/viewer.md)");
      else if (e.kind == ScriptEvent::Kind::Set)
        if (std::string error = settingError(e.key, e.value); !error.empty())
          throw InputError(script_->file + ":" + std::to_string(e.line) + ": " + error);
  }
  if (!o.replay.empty()) replay_ = loadCameraPath(o.replay), replaying_ = true;

  glfw_ = std::make_unique<GlfwSession>();  // no display: say so before loading anything
  original_ = loadInput(o.input);
  // --eye/--target are world coordinates; a far scene is stored relative to Scene::origin.
  if (o.eye) original_.camera.eye = glm::vec3(*o.eye - original_.origin);
  if (o.target) original_.camera.target = glm::vec3(*o.target - original_.origin);
  if (o.up) original_.camera.up = *o.up;
  if (o.fov) original_.camera.fovDeg = *o.fov;
  camera_.setCamera(original_.camera);
  builder_ = o.builder;
  kernel_ = o.kernel;
  view_ = o.view;
  aa_ = o.aa;
  robust_ = o.robust;
  leafSize_ = o.leafSize;
  optimize_ = o.optimize;
  depth_ = o.depth.value_or(original_.settings.maxDepth);
  scale_ = o.resolutionScale;

  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  const int w = o.width.value_or(original_.settings.width), h = o.height.value_or(original_.settings.height);
  window_ = glfwCreateWindow(w, h, ("bvhlab view: " + o.input).c_str(), nullptr, nullptr);
  if (!window_) throw std::runtime_error("cannot create an OpenGL 4.5 core window: " + lastGlfwError);
  glfwMakeContextCurrent(window_);
  int version = gladLoadGL(reinterpret_cast<GLADloadfunc>(glfwGetProcAddress));
  if (version == 0 || GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 45)
    throw std::runtime_error("the window's context does not provide OpenGL 4.5 core");
  glfwSwapInterval(0);  // frame times, not the monitor's refresh rate
  const GLubyte* r = glGetString(GL_RENDERER);
  glRenderer_ = r ? reinterpret_cast<const char*>(r) : "unknown";

  glfwSetWindowUserPointer(window_, this);
  glfwSetKeyCallback(window_, keyCallback);  // installed before ImGui so its backend chains to them
  glfwSetCursorPosCallback(window_, cursorCallback);
  glfwSetScrollCallback(window_, scrollCallback);
  if (o.overlay) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // never write imgui.ini into the working directory
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 450");
    imgui_ = true;
  }
  glCreateFramebuffers(1, &displayFbo_);
  lastStats_ = Clock::now();
}

Viewer::~Viewer() {
  if (!window_) return;
  glfwMakeContextCurrent(window_);
  smaa_.reset();  // GL objects go before the context
  statsGpu_.reset();
  gpu_.reset();
  if (displayTex_) glDeleteTextures(1, &displayTex_);
  if (displayFbo_) glDeleteFramebuffers(1, &displayFbo_);
  if (imgui_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  glfwDestroyWindow(window_);
}

// ---- input ----------------------------------------------------------------------

void Viewer::keyCallback(GLFWwindow* w, int key, int, int action, int mods) {
  Viewer& v = self(w);
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  if (v.imgui_ && !v.captured_ && ImGui::GetIO().WantCaptureKeyboard) return;
  v.handleKey(key, mods);
}

void Viewer::cursorCallback(GLFWwindow* w, double x, double y) {
  Viewer& v = self(w);
  glm::dvec2 p(x, y);
  if (v.captured_ && v.haveCursor_) {
    glm::dvec2 d = p - v.lastCursor_;
    v.camera_.turn(float(d.x) * kLookDegPerPixel, -float(d.y) * kLookDegPerPixel);
  }
  v.lastCursor_ = p;
  v.haveCursor_ = true;
}

void Viewer::scrollCallback(GLFWwindow* w, double, double y) {
  Viewer& v = self(w);
  if (v.imgui_ && !v.captured_ && ImGui::GetIO().WantCaptureMouse) return;
  v.speed_ *= std::pow(1.25f, float(y));
}

void Viewer::setCapture(bool on) {
  captured_ = on;
  haveCursor_ = false;  // the first event after a mode change is a jump, not a look
  if (!script_) glfwSetInputMode(window_, GLFW_CURSOR, on ? GLFW_CURSOR_DISABLED : GLFW_CURSOR_NORMAL);
}

void Viewer::handleKey(int key, int mods) {
  const int step = (mods & GLFW_MOD_SHIFT) ? -1 : 1;
  switch (key) {
    case GLFW_KEY_B: cycle("builder", step); break;
    case GLFW_KEY_K: cycle("kernel", step); break;
    case GLFW_KEY_L: cycle("leaf_size", step); break;
    case GLFW_KEY_M: cycle("aa", step); break;
    case GLFW_KEY_T: cycle("robust", step); break;
    case GLFW_KEY_RIGHT_BRACKET: cycle("depth", 1); break;
    case GLFW_KEY_LEFT_BRACKET: cycle("depth", -1); break;
    case GLFW_KEY_V: cycle("view", step); break;
    case GLFW_KEY_PERIOD: cycle("scale", 1); break;
    case GLFW_KEY_COMMA: cycle("scale", -1); break;
    case GLFW_KEY_F:
      camera_.setFov(std::clamp(camera_.camera().fovDeg + 5.0f * float(step), 10.0f, 150.0f));
      break;
    case GLFW_KEY_P:
    case GLFW_KEY_F12: {
      char name[64];
      std::snprintf(name, sizeof name, "bvhlab_view_%05d.png", frame_);
      pendingScreenshot_ = name;
      break;
    }
    case GLFW_KEY_R: toggleRecording(); break;
    case GLFW_KEY_O: startReplay(opt_.replay.empty() ? (opt_.record.empty() ? "camera_path.txt" : opt_.record)
                                                     : opt_.replay);
      break;
    case GLFW_KEY_H: opt_.overlay = !opt_.overlay; break;
    case GLFW_KEY_TAB: setCapture(!captured_); break;
    case GLFW_KEY_ESCAPE:
      if (captured_) setCapture(false);
      else quit_ = true;
      break;
    case GLFW_KEY_1: case GLFW_KEY_2: case GLFW_KEY_3: case GLFW_KEY_4: {
      const int i = key - GLFW_KEY_1;
      if (mods & GLFW_MOD_CONTROL) {
        bookmarks_[i] = camera_.camera();
        const Camera& c = *bookmarks_[i];
        std::fprintf(stderr, "bookmark %d: --eye %g,%g,%g --target %g,%g,%g --up %g,%g,%g --fov %g\n", i + 1,
                     c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z,
                     c.fovDeg);
        status_ = "stored bookmark " + std::to_string(i + 1);
      } else if (bookmarks_[i]) {
        camera_.setCamera(*bookmarks_[i]);
        status_ = "bookmark " + std::to_string(i + 1);
      }
      break;
    }
    default: break;
  }
}

bool Viewer::held(int key) const {
  auto it = holdUntil_.find(key);
  if (it != holdUntil_.end() && frame_ <= it->second) return true;
  return !script_ && glfwGetKey(window_, key) == GLFW_PRESS;
}

void Viewer::applyScript() {
  if (!script_) return;
  const std::vector<ScriptEvent>& events = script_->events;
  for (; scriptNext_ < events.size() && events[scriptNext_].frame <= frame_; ++scriptNext_) {
    const ScriptEvent& e = events[scriptNext_];
    switch (e.kind) {
      case ScriptEvent::Kind::Key: {
        auto [key, mods] = parseKeyChord(e.key);
        handleKey(key, mods);
        break;
      }
      case ScriptEvent::Kind::Hold: holdUntil_[parseKeyChord(e.key).first] = frame_ + e.holdFrames - 1; break;
      case ScriptEvent::Kind::Mouse: camera_.turn(e.delta.x * kLookDegPerPixel, -e.delta.y * kLookDegPerPixel); break;
      case ScriptEvent::Kind::Scroll: speed_ *= std::pow(1.25f, e.delta.y); break;
      case ScriptEvent::Kind::Pose: {
        Camera c = e.pose;
        if (c.fovDeg < 0.0f) c.fovDeg = camera_.camera().fovDeg;
        camera_.setCamera(c);
        break;
      }
      case ScriptEvent::Kind::Set: set(e.key, e.value); break;
      case ScriptEvent::Kind::Screenshot: pendingScreenshot_ = e.path; break;
      case ScriptEvent::Kind::WindowScreenshot: pendingWindowShot_ = e.path; break;
      case ScriptEvent::Kind::Quit: quit_ = true; break;
    }
  }
}

void Viewer::moveCamera(double dt) {
  glm::vec3 local(0.0f);
  if (held(GLFW_KEY_W)) local.z += 1;
  if (held(GLFW_KEY_S)) local.z -= 1;
  if (held(GLFW_KEY_D)) local.x += 1;
  if (held(GLFW_KEY_A)) local.x -= 1;
  if (held(GLFW_KEY_E)) local.y += 1;
  if (held(GLFW_KEY_Q)) local.y -= 1;
  if (local != glm::vec3(0.0f)) camera_.move(glm::normalize(local), speed_ * float(dt));
}

// ---- configuration --------------------------------------------------------------

void Viewer::cycle(const std::string& what, int step) {
  if (what == "leaf_size") {
    set(what, std::to_string(std::clamp(step > 0 ? leafSize_ * 2 : leafSize_ / 2, 1, int(kMaxLeafSize))));
  } else if (what == "depth") {
    set(what, std::to_string(std::clamp(depth_ + step, 1, kMaxDepth)));
  } else if (what == "scale") {
    auto it = std::lower_bound(kScales.begin(), kScales.end(), scale_ - 1e-4f);  // 1e-4: below any step gap
    int i = std::clamp(int(it - kScales.begin()) + step, 0, int(kScales.size()) - 1);
    set(what, shortest(kScales[size_t(i)]));
  } else {
    const std::vector<std::string> names = choices(what);
    const std::string& cur = what == "builder" ? builder_ : what == "kernel" ? kernel_ : what == "view" ? view_
                             : what == "aa"    ? aa_      : robust_;
    auto it = std::find(names.begin(), names.end(), cur);
    const int n = int(names.size()), i = it == names.end() ? 0 : int(it - names.begin());
    set(what, names[size_t(((i + step) % n + n) % n)]);
  }
}

void Viewer::set(const std::string& what, const std::string& value) {
  if (what == "builder") builder_ = value, needRebuild_ = true;
  else if (what == "kernel") kernel_ = value, needRenderer_ = true;
  else if (what == "leaf_size") leafSize_ = *parseNumber<int>(value), needRebuild_ = true;
  else if (what == "depth") depth_ = *parseNumber<int>(value), needRenderer_ = true;
  else if (what == "view") view_ = value, needRenderer_ = true;
  else if (what == "scale") scale_ = *parseNumber<float>(value);  // ensureRenderers sees the new size
  else if (what == "robust") robust_ = value, needRenderer_ = true;
  else if (what == "aa") {
    // SSAA lives in the tracer (recompile); SMAA is a post pass on the same traced frame.
    if (ssaaGridOf(value) != ssaaGridOf(aa_)) needRenderer_ = true;
    aa_ = value;
    needSmaa_ = true;
  }
  logSwitch(what, value);
}

void Viewer::logSwitch(const std::string& what, const std::string& value) {
  if (!switches_.empty()) {
    switches_.back()["frame_ms_after"] = median(sinceSwitchMs_);
    switches_.back()["aa_ms_after"] = median(sinceSwitchAaMs_);
  }
  switches_.push_back({{"frame", frame_},
                       {"switch", what},
                       {"value", value},
                       {"frame_ms_before", median(sinceSwitchMs_)},
                       {"frames_before", sinceSwitchMs_.size()},
                       {"aa_ms_before", median(sinceSwitchAaMs_)}});
  sinceSwitchMs_.clear();
  sinceSwitchAaMs_.clear();
  // The rolling median restarts with the new setting (the graph keeps the history, so the step shows):
  // otherwise a slow setting's median would show the old one's time for half a window.
  recentMs_.clear();
  recentAaMs_.clear();
  status_ = what + " -> " + value;
}

ShaderOptions Viewer::shaderOptions(bool countStats) const {
  const Scene& sc = prepared_->scene;
  ShaderOptions so;
  so.maxDepth = depth_;
  so.view = view_ == "visits" ? View::Shaded : parseView(view_);
  so.kernel = kernel_;
  so.reinhard = sc.settings.reinhard;
  so.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, prepared_->packed.depth));
  so.countStats = countStats;
  so.ssaaGrid = ssaaGridOf(aa_);
  so.robust = parseRobustness(robust_);
  return so;
}

void Viewer::ensureRenderers() {
  int fbW = 0, fbH = 0;
  glfwGetFramebufferSize(window_, &fbW, &fbH);
  const int w = std::max(1, int(std::lround(fbW * scale_))), h = std::max(1, int(std::lround(fbH * scale_)));
  if (w != renderW_ || h != renderH_) needRenderer_ = true;
  if (needRebuild_) {
    statsGpu_.reset();
    gpu_.reset();
    BuildOptions bo;
    bo.maxLeafSize = uint32_t(leafSize_);
    bo.optimize = optimize_;
    auto start = Clock::now();
    prepared_ = prepareScene(Scene(original_), builder_, bo);
    prepareMs_ = msSince(start);
    if (!switches_.empty()) {
      switches_.back()["build_ms"] = prepared_->stats.buildMs;
      switches_.back()["sah_cost"] = prepared_->stats.sahCost;
    }
    if (frame_ == 0) speed_ = 0.5f * prepared_->data.sceneRadius;  // half the scene per second
    needRebuild_ = false;
    needRenderer_ = true;
  }
  if (needRenderer_) {
    statsGpu_.reset();
    gpu_.reset();
    FrameOptions fo;
    fo.width = renderW_ = w;
    fo.height = renderH_ = h;
    fo.camera = camera_.camera();
    fo.exposure = prepared_->scene.settings.exposure;
    gpu_ = std::make_unique<GpuRenderer>(*prepared_, shaderOptions(false), fo);
    if (view_ == "visits") statsGpu_ = std::make_unique<GpuRenderer>(*prepared_, shaderOptions(true), fo);
    needRenderer_ = false;
    firstFramePending_ = true;
    statsStale_ = true;
  }
  if (!isSmaa(aa_)) {
    smaa_.reset();
  } else if (needSmaa_ || !smaa_ || smaa_->width() != renderW_ || smaa_->height() != renderH_) {
    smaa_.reset();
    smaa_ = std::make_unique<SmaaPass>(renderW_, renderH_, SmaaSettings::preset(parseSmaaPreset(aa_.substr(5))));
    firstFramePending_ = true;  // its passes compile at their first draw too
  }
  needSmaa_ = false;
}

// ---- frames -----------------------------------------------------------------------

void Viewer::renderFrame() {
  ensureRenderers();
  const Camera& cam = camera_.camera();
  gpu_->setCamera(cam);
  const double traceMs = gpu_->drawFrame();
  const bool heatmap = heatmapShown();
  double aaMs = 0.0;
  if (smaa_ && !heatmap) {  // timed like `bvhlab render`: the three passes, waited for
    auto start = Clock::now();
    smaa_->apply(gpu_->colorTexture());
    glFinish();
    aaMs = msSince(start);
  }
  const double ms = traceMs + aaMs;
  lastDrawMs_ = traceMs;
  lastAaMs_ = aaMs;
  frameCounted_ = !firstFramePending_;
  if (firstFramePending_) {  // llvmpipe compiles the shaders here: not a frame time
    firstFrameMs_ = ms;
    firstFramePending_ = false;
    if (!switches_.empty() && !switches_.back().contains("first_frame_ms")) switches_.back()["first_frame_ms"] = ms;
  } else {
    recentMs_.push_back(ms);
    recentAaMs_.push_back(aaMs);
    if (recentMs_.size() > kRollingWindow) recentMs_.pop_front(), recentAaMs_.pop_front();
    graph_.push_back(float(median({recentMs_.begin(), recentMs_.end()})));
    if (graph_.size() > kGraphLength) graph_.erase(graph_.begin());
    sinceSwitchMs_.push_back(ms);
    sinceSwitchAaMs_.push_back(aaMs);
  }

  // Statistics come from a separately compiled, instrumented renderer (as in `bvhlab render`): every
  // frame in the visits view; otherwise, only while someone looks at them (the overlay, --json),
  // after a change and then once a second.
  const bool visits = view_ == "visits";
  const bool wanted = (imgui_ && opt_.overlay) || opt_.json;
  const bool refresh = visits || (wanted && (statsStale_ || (!script_ && msSince(lastStats_) > 1000.0)));
  if (refresh && prepared_->soup.size() > 0) {
    if (!statsGpu_) {
      FrameOptions fo;
      fo.width = renderW_;
      fo.height = renderH_;
      fo.camera = cam;
      fo.exposure = prepared_->scene.settings.exposure;
      statsGpu_ = std::make_unique<GpuRenderer>(*prepared_, shaderOptions(true), fo);
    }
    statsGpu_->setCamera(cam);
    statsGpu_->drawFrame();
    std::vector<glm::uvec4> stats = statsGpu_->readStats();
    rayStats_ = summarize(stats);
    if (visits) image_ = visitsHeatmap(stats, renderW_, renderH_);
    statsStale_ = false;
    lastStats_ = Clock::now();
    if (!visits) statsGpu_.reset();  // keep instrumentation out of memory between refreshes
  }
  readbackMs_ = 0.0;
  if (opt_.readbackPresent && !heatmap) {  // the old display path, for comparison
    auto start = Clock::now();
    image_ = readDisplayed();
    readbackMs_ = msSince(start);
  }
  if (recording_) recorded_.push_back({time_ - recordStart_, cam});
}

unsigned Viewer::displayedTexture() const { return smaa_ ? smaa_->outputTexture() : gpu_->colorTexture(); }

std::vector<uint8_t> Viewer::readDisplayed() const {
  if (heatmapShown()) return image_;
  return smaa_ ? smaa_->readOutput() : gpu_->readColor();
}

void Viewer::present() {
  // The frame's texture goes to the window by one scaling blit, without leaving the GPU. The heatmap
  // (built on the CPU from the counters) and --readback-present go up through displayTex_ first.
  unsigned source = 0;
  if (heatmapShown() || opt_.readbackPresent) {
    if (displayW_ != renderW_ || displayH_ != renderH_) {
      if (displayTex_) glDeleteTextures(1, &displayTex_);
      glCreateTextures(GL_TEXTURE_2D, 1, &displayTex_);
      glTextureStorage2D(displayTex_, 1, GL_RGBA8, renderW_, renderH_);
      displayW_ = renderW_;
      displayH_ = renderH_;
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(displayTex_, 0, 0, 0, renderW_, renderH_, GL_RGBA, GL_UNSIGNED_BYTE, image_.data());
    source = displayTex_;
  } else {
    source = displayedTexture();
  }
  // Attached every frame: a renderer or SMAA pass recreated since the last frame owns a new texture.
  glNamedFramebufferTexture(displayFbo_, GL_COLOR_ATTACHMENT0, source, 0);
  int fbW = 0, fbH = 0;
  glfwGetFramebufferSize(window_, &fbW, &fbH);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, fbW, fbH);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  const GLenum filter = (renderW_ == fbW && renderH_ == fbH) ? GL_NEAREST : GL_LINEAR;
  glBlitNamedFramebuffer(displayFbo_, 0, 0, 0, renderW_, renderH_, 0, 0, fbW, fbH, GL_COLOR_BUFFER_BIT, filter);
  // A renderer destroyed this frame may leave its deleted program current; ImGui restores the current
  // program after drawing, which would then be an invalid name.
  glUseProgram(0);
  if (imgui_) drawOverlay();
  if (!pendingWindowShot_.empty()) saveWindowScreenshot(pendingWindowShot_), pendingWindowShot_.clear();
  checkGl("viewer present");
  glfwSwapBuffers(window_);
}

void Viewer::drawOverlay() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  if (opt_.overlay) {
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.6f);
    ImGui::Begin("bvhlab", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    const double med = recentMs_.empty() ? lastDrawMs_ + lastAaMs_ : median({recentMs_.begin(), recentMs_.end()});
    const double aaMed = recentAaMs_.empty() ? lastAaMs_ : median({recentAaMs_.begin(), recentAaMs_.end()});
    ImGui::Text("%.1f FPS  frame %.2f ms, of it AA %.2f ms (medians of %zu)", med > 0 ? 1000.0 / med : 0.0, med,
                aaMed, recentMs_.size());
    const double presentMed = median({recentPresentMs_.begin(), recentPresentMs_.end()});
    ImGui::Text("loop %.2f ms, to the window %.2f ms (%s)", lastLoopMs_, presentMed,
                opt_.readbackPresent ? "read back + upload" : "blit");
    if (!graph_.empty())
      ImGui::PlotLines("##ms", graph_.data(), int(graph_.size()), 0, "rolling median ms", 0.0f,
                       *std::max_element(graph_.begin(), graph_.end()) * 1.2f, ImVec2(320, 60));
    // The last switch's effect: the median before it against the median of the frames since.
    if (!switches_.empty()) {
      const nlohmann::json& s = switches_.back();
      const double before = s.value("frame_ms_before", 0.0), after = median(sinceSwitchMs_);
      if (before > 0.0 && !sinceSwitchMs_.empty())
        ImGui::Text("last switch %s -> %s: %.2f -> %.2f ms (%.2fx; medians of %zu and %zu frames)",
                    s.value("switch", "").c_str(), s.value("value", "").c_str(), before, after, after / before,
                    s.value("frames_before", size_t(0)), sinceSwitchMs_.size());
      else
        ImGui::Text("last switch %s -> %s: measuring", s.value("switch", "").c_str(), s.value("value", "").c_str());
    }
    ImGui::Separator();
    const BuildStats& b = prepared_->stats;
    // One combo per named setting (the same values its key cycles through); choosing one switches live.
    auto combo = [&](const char* label, const std::string& what, const std::string& current) {
      ImGui::SetNextItemWidth(130);
      if (ImGui::BeginCombo(label, current.c_str())) {
        for (const std::string& c : choices(what)) {
          const bool selected = c == current;
          if (ImGui::Selectable(c.c_str(), selected) && !selected) set(what, c);
          if (selected) ImGui::SetItemDefaultFocus();
        }
        ImGui::EndCombo();
      }
    };
    combo("[B] builder", "builder", builder_);
    ImGui::SameLine();
    ImGui::Text("build %.1f ms (prepare %.1f ms)", b.buildMs, prepareMs_);
    combo("[K] kernel", "kernel", kernel_);
    ImGui::SameLine();
    ImGui::Text("first frame %.0f ms", firstFrameMs_);
    combo("[M] AA", "aa", aa_);
    ImGui::SameLine();
    ImGui::Text("AA pass %.2f ms", aaMed);
    combo("[T] robust", "robust", robust_);
    ImGui::SameLine();
    ImGui::Text("frame %.2f ms", med);
    combo("[V] view", "view", view_);
    ImGui::Text("[L] leaf %d   [ ] depth %d", leafSize_, depth_);
    ImGui::Text("[,.] scale %.3f -> %dx%d", scale_, renderW_, renderH_);
    ImGui::Text("SAH %.2f  nodes %zu  leaves %zu  tree depth %u", b.sahCost, b.nodes, b.leaves, b.depth);
    if (rayStats_.valid)
      ImGui::Text("per ray: %.1f node visits, %.1f triangle tests%s", rayStats_.visitsPerRay, rayStats_.testsPerRay,
                  rayStats_.overflows ? "  STACK OVERFLOW" : "");
    ImGui::Separator();
    const Camera& c = camera_.camera();
    ImGui::Text("eye %.3f %.3f %.3f  fov %.0f [F]  speed %.3g/s", c.eye.x, c.eye.y, c.eye.z, c.fovDeg, speed_);
    ImGui::Text("%s%s%s", recording_ ? "REC  " : "", replaying_ ? "REPLAY  " : "", status_.c_str());
    ImGui::TextDisabled("%s", glRenderer_.c_str());
    ImGui::TextDisabled("Tab mouse look, WASD/QE move, wheel speed, P shot, R rec, O replay, Ctrl+1-4 mark");
    ImGui::TextDisabled("Shift+key cycles backwards");
    ImGui::End();
  }
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void Viewer::saveScreenshot(const std::string& path) {
  saveImageRgba8(path, renderW_, renderH_, readDisplayed());
  status_ = "saved " + path;
}

void Viewer::saveWindowScreenshot(const std::string& path) {
  // The back buffer as it will be shown (upscaled frame + overlay), before the swap makes it undefined.
  int fbW = 0, fbH = 0;
  glfwGetFramebufferSize(window_, &fbW, &fbH);
  std::vector<uint8_t> pixels(size_t(fbW) * size_t(fbH) * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, fbW, fbH, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  saveImageRgba8(path, fbW, fbH, pixels);
  status_ = "saved " + path;
}

void Viewer::toggleRecording() {
  if (!recording_) {
    recorded_.clear();
    recordStart_ = time_;
    recording_ = true;
    status_ = "recording";
    return;
  }
  recording_ = false;
  const std::string path = opt_.record.empty() ? "camera_path.txt" : opt_.record;
  saveCameraPath(path, recorded_);
  status_ = "saved " + std::to_string(recorded_.size()) + " poses to " + path;
}

void Viewer::startReplay(const std::string& path) {
  try {
    replay_ = loadCameraPath(path);
  } catch (const InputError& e) {
    status_ = e.what();  // interactive: a bad file is a message, not the end of the session
    return;
  }
  replayNext_ = 0;
  replaying_ = true;
}

int Viewer::run() {
  if (!opt_.record.empty()) toggleRecording();
  const bool automatic = script_ || !opt_.replay.empty();
  setCapture(!automatic);  // interactive: mouse look from the start (Tab releases the cursor)
  auto last = Clock::now();
  for (; !quit_ && !glfwWindowShouldClose(window_); ++frame_) {
    auto start = Clock::now();
    glfwPollEvents();
    const double dt = script_ ? kScriptDt : std::min(0.1, std::chrono::duration<double>(start - last).count());
    last = start;
    applyScript();
    moveCamera(dt);
    if (replaying_) {
      if (replayNext_ < replay_.size()) camera_.setCamera(replay_[replayNext_++].camera);
      if (replayNext_ >= replay_.size()) replaying_ = false;  // the last pose is this frame's
    }
    renderFrame();
    auto presentStart = Clock::now();
    present();
    const double presentMs = readbackMs_ + msSince(presentStart);
    ++rendered_;
    if (!pendingScreenshot_.empty()) saveScreenshot(pendingScreenshot_), pendingScreenshot_.clear();
    time_ = script_ ? (frame_ + 1) * kScriptDt : time_ + dt;
    lastLoopMs_ = msSince(start);
    if (frameCounted_) {
      recentLoopMs_.push_back(lastLoopMs_);
      recentPresentMs_.push_back(presentMs);
      if (recentLoopMs_.size() > kRollingWindow) recentLoopMs_.pop_front(), recentPresentMs_.pop_front();
    }
    if (opt_.frames > 0 && frame_ + 1 >= opt_.frames) break;
    if (opt_.frames == 0 && automatic && frame_ >= (script_ ? script_->lastFrame() : 0) && !replaying_) break;
  }
  if (!opt_.screenshot.empty() && rendered_ > 0) saveScreenshot(opt_.screenshot);
  if (recording_) toggleRecording();
  if (!switches_.empty()) {
    switches_.back()["frame_ms_after"] = median(sinceSwitchMs_);
    switches_.back()["aa_ms_after"] = median(sinceSwitchAaMs_);
  }

  if (opt_.json) {
    const BuildStats& b = prepared_->stats;
    nlohmann::json out = {{"input", opt_.input},
                          {"renderer", glRenderer_},
                          {"frames", rendered_},
                          {"builder", builder_},
                          {"kernel", kernel_},
                          {"leaf_size", leafSize_},
                          {"depth", depth_},
                          {"view", view_},
                          {"aa", aa_},
                          {"robust", robust_},
                          {"scale", scale_},
                          {"present", opt_.readbackPresent ? "readback" : "blit"},
                          {"width", renderW_},
                          {"height", renderH_},
                          {"build_ms", b.buildMs},
                          {"sah_cost", b.sahCost},
                          {"frame_ms_median", median({recentMs_.begin(), recentMs_.end()})},
                          {"aa_ms_median", median({recentAaMs_.begin(), recentAaMs_.end()})},
                          {"loop_ms_median", median({recentLoopMs_.begin(), recentLoopMs_.end()})},
                          {"present_ms_median", median({recentPresentMs_.begin(), recentPresentMs_.end()})},
                          {"node_visits_per_ray", rayStats_.visitsPerRay},
                          {"triangle_tests_per_ray", rayStats_.testsPerRay},
                          {"camera", cameraJson(camera_.camera())},
                          {"switches", switches_}};
    std::cout << out.dump() << std::endl;
  }
  return rayStats_.overflows > 0 ? 3 : 0;
}

}  // namespace

bool viewerAvailable() { return true; }

int runViewer(const ViewerOptions& options) {
  Viewer viewer(options);
  return viewer.run();
}

}  // namespace bvhlab

#else  // built without GLFW / Dear ImGui

namespace bvhlab {

bool viewerAvailable() { return false; }

int runViewer(const ViewerOptions&) {
  throw std::runtime_error(
      "this bvhlab was built without the viewer (GLFW and Dear ImGui were not linked); use `bvhlab render`");
}

}  // namespace bvhlab

#endif
