// The viewer's internals (`bvhlab view`, render/viewer.hpp): the Viewer class and the helpers its
// files share. Split along the class's seams: viewer.cpp (window, input, live configuration, the
// main loop), viewer_frame.cpp (rendering, presenting, the overlay, screenshots, camera paths),
// viewer_settings.cpp (setting names and values, key names, the GLFW session). Only those include it.
#pragma once

#ifdef BVHLAB_VIEWER  // set by CMake where GLFW and Dear ImGui are linked

#include <chrono>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <nlohmann/json.hpp>

#include "builders/update.hpp"
#include "layout/two_level_update.hpp"
#include "render/fly_camera.hpp"
#include "render/gpu_clip_build.hpp"
#include "render/gpu_renderer.hpp"
#include "render/program_cache.hpp"
#include "render/smaa.hpp"
#include "render/viewer.hpp"

namespace bvhlab::viewer_detail {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t);
double median(std::vector<double> v);

inline const std::vector<std::string> kViews = {"shaded", "normal", "depth", "primid", "visits"};
// The anti-aliasing modes of `bvhlab render --aa`, SMAA by preset name (render/smaa.hpp).
inline const std::vector<std::string> kAaModes = {"none",       "smaa-low", "smaa-medium", "smaa-high",
                                                  "smaa-ultra", "ssaa4",    "ssaa16"};
// The update strategies U cycles through while a clip plays (any spec parseUpdateSpec takes can be set
// with --update or a script's `set update`).
inline const std::vector<std::string> kUpdateSpecs = {"rebuild", "refit", "refit+rebuild:4", "refit+rebuild:sah>1.2",
                                                      "refit+rotate"};
inline const std::vector<float> kScales = {0.125f, 0.25f, 0.375f, 0.5f, 0.75f, 1.0f};
constexpr int kMaxDepth = 16;
constexpr int kRollingWindow = 31;      // frames in the rolling median (odd: a true middle element)
constexpr int kGraphLength = 240;       // rolling medians kept for the graph
constexpr double kScriptDt = 1.0 / 30;  // seconds per frame in scripted mode: movement is reproducible
constexpr float kLookDegPerPixel = 0.1f;

inline bool isSmaa(const std::string& aa) { return aa.rfind("smaa-", 0) == 0; }
inline int ssaaGridOf(const std::string& aa) { return aa == "ssaa4" ? 2 : aa == "ssaa16" ? 4 : 1; }

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

// The values a named setting cycles through (keys, combos); empty for numeric settings. Kernels are
// those that walk `layout` (traversal/kernels.hpp); robustness variants those the triangle format
// `triangles` can run (layout/triangle_formats.hpp: precomputed has no watertight test).
std::vector<std::string> choices(const std::string& what, const std::string& layout, const std::string& triangles);
std::string joined(const std::vector<std::string>& names);
// "" when `value` is valid for the setting (one of scriptSettings()) with the tree in `layout` and
// `triangles`, else what is wrong.
std::string settingError(const std::string& what, const std::string& value, const std::string& layout,
                         const std::string& triangles);
// Script key names -> GLFW keys (docs/viewer.md lists them).
int keyFromName(const std::string& name);
// "SHIFT+B", "CTRL+1" -> key + modifier bits; GLFW_KEY_UNKNOWN when the name is not a key.
std::pair<int, int> parseKeyChord(std::string name);
nlohmann::json cameraJson(const Camera& c);

extern std::string lastGlfwError;  // the last message GLFW's error callback got

// glfwInit/glfwTerminate as a scope.
struct GlfwSession {
  GlfwSession();
  ~GlfwSession();
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

struct RayStats {
  double visitsPerRay = 0.0, testsPerRay = 0.0;
  uint64_t overflows = 0;
  bool valid = false;
};
RayStats summarize(const std::vector<glm::uvec4>& stats);

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

  // clip playback (viewer_clip.cpp)
  bool animated() const { return clipFrames_ > 1; }
  void setupClip();                 // after the scene is loaded: clip length, strategy, program cache
  void advanceClip(double dt);      // after a frame: the next clip frame when playing
  void updateClipFrame();           // the tree of clipFrame_ by the strategy, packed: prepared_
  void togglePlay();
  void drawClipOverlay();
  nlohmann::json clipJson() const;

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
  // layout_ and triangles_ (the triangle format) are fixed for the session.
  std::string builder_, layout_, triangles_, kernel_, view_, aa_, robust_;
  int leafSize_ = 4, depth_ = 5;
  std::string optimize_;  // ViewerOptions::optimize, applied after every rebuild
  float scale_ = 1.0f;
  bool needRebuild_ = true, needRenderer_ = true, needSmaa_ = true;

  // clip playback: the strategy keeps the tree over the clip's frames; each new frame is packed and
  // uploaded into a fresh renderer whose program comes from programs_ (compiled once per source).
  std::string update_;  // the strategy's spec ("" for a static scene)
  std::unique_ptr<UpdateStrategy> strategy_;
  std::unique_ptr<TwoLevelUpdater> twoLevel_;  // instead of strategy_ while update_ is two-level[:...]
  // Instead of strategy_ while update_ is `rebuild` with a GPU builder whose layout the GPU packs: each
  // frame built and packed on the GPU and drawn from the streams left there (render/gpu_clip_build.hpp).
  std::unique_ptr<GpuClipBuilder> gpuClip_;
  std::unique_ptr<ProgramCache> programs_;  // clip playback only
  Scene clipScene_;                         // the scene at clipFrame_
  int clipFrames_ = 1, clipFrame_ = 0, clipStack_ = 0;
  double clipFps_ = 30.0, clipClock_ = 0.0;  // clipClock_: clip frames owed by elapsed time (interactive)
  bool playing_ = false, needStrategy_ = true, needClipFrame_ = true;
  bool clipJump_ = false;        // a script jumped to a clip frame: draw it before advancing
  bool uploadPending_ = false;   // this frame's renderer creation is the clip frame's upload
  bool clipFrameRendered_ = false;
  // packMs_: the part of a clip frame's upload before its renderer is made: the pack on the CPU, or with
  // gpuClip_ the triangles' upload to the GPU.
  double packMs_ = 0.0, lastUpdateMs_ = 0.0, lastUploadMs_ = 0.0;
  bool lastRebuilt_ = false;
  std::deque<double> recentUpdateMs_, recentUploadMs_;
  nlohmann::json clipLog_ = nlohmann::json::array();  // one entry per clip frame made

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

}  // namespace bvhlab::viewer_detail

#endif  // BVHLAB_VIEWER
