// `bvhlab view` (render/viewer.hpp): the window, input, live configuration and the main loop. Frames,
// presenting and the overlay: viewer_frame.cpp; setting names and key names: viewer_settings.cpp.
#include "render/viewer.hpp"

#ifdef BVHLAB_VIEWER  // set by CMake where GLFW and Dear ImGui are linked

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "builders/builder.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "render/viewer_app.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace viewer_detail {

Viewer::Viewer(const ViewerOptions& o) : opt_(o) {
  // Validate everything before a window appears.
  findBuilder(o.builder);
  // As `bvhlab render`: an unknown layout, or a kernel of another layout, is refused naming the valid ones.
  layout_ = findLayout(o.layout).name;
  kernel_ = findKernel(layout_, o.kernel).name;
  triangles_ = findTriangleFormat(o.triangles).name;  // --robust is checked against it below (settingError)
  if (o.leafSize < 1 || o.leafSize > int(kMaxLeafSize))
    throw std::invalid_argument("--leaf-size must be in 1.." + std::to_string(kMaxLeafSize));
  if (o.depth && (*o.depth < 1 || *o.depth > kMaxDepth))
    throw std::invalid_argument("--depth must be in 1.." + std::to_string(kMaxDepth));
  if (std::find(kViews.begin(), kViews.end(), o.view) == kViews.end())
    throw std::invalid_argument("--view must be one of shaded, normal, depth, primid, visits");
  if (!(o.resolutionScale >= 0.05f && o.resolutionScale <= 1.0f))
    throw std::invalid_argument("--scale must be in 0.05..1");
  if (std::string e = settingError("aa", o.aa, layout_, triangles_); !e.empty()) throw std::invalid_argument("--aa: " + e);
  if (std::string e = settingError("robust", o.robust, layout_, triangles_); !e.empty())
    throw std::invalid_argument("--robust: " + e);
  try {
    parseTextureLod(o.textureLod);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--texture-lod: ") + e.what());
  }
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
        if (std::string error = settingError(e.key, e.value, layout_, triangles_); !error.empty())
          throw InputError(script_->file + ":" + std::to_string(e.line) + ": " + error);
  }
  if (!o.replay.empty()) replay_ = loadCameraPath(o.replay), replaying_ = true;
  if (o.update) {
    if (std::string e = settingError("update", *o.update, layout_, triangles_); !e.empty())
      throw std::invalid_argument("--update: " + e);
  }

  glfw_ = std::make_unique<GlfwSession>();  // no display: say so before loading anything
  original_ = loadInput(o.input);
  // --eye/--target are world coordinates; a far scene is stored relative to Scene::origin.
  if (o.eye) original_.camera.eye = glm::vec3(*o.eye - original_.origin);
  if (o.target) original_.camera.target = glm::vec3(*o.target - original_.origin);
  if (o.up) original_.camera.up = *o.up;
  if (o.fov) original_.camera.fovDeg = *o.fov;
  camera_.setCamera(original_.camera);
  setupClip();  // a static scene with --update is refused here, before a window opens
  for (const ScriptEvent& e : script_ ? script_->events : std::vector<ScriptEvent>{}) {
    if (e.kind != ScriptEvent::Kind::Set) continue;
    const std::string where = script_->file + ":" + std::to_string(e.line) + ": ";
    if (e.key == "update" && !animated())
      throw InputError(where + "set update: " + o.input + " is not animated (no clip to update the tree over)");
    if (e.key == "clip_frame" && *parseNumber<int>(e.value) >= clipFrames_)
      throw InputError(where + "clip_frame " + e.value + " is past the clip (" + std::to_string(clipFrames_) +
                       " frame" + (clipFrames_ == 1 ? "" : "s") + ")");
  }
  builder_ = o.builder;
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
  programs_.reset();  // after the renderers that draw with its programs
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
    case GLFW_KEY_U:
      if (animated()) cycle("update", step);
      else status_ = "static scene: no update strategy";
      break;
    case GLFW_KEY_SPACE: togglePlay(); break;
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
    const std::vector<std::string> names = choices(what, layout_, triangles_);
    const std::string& cur = what == "builder" ? builder_ : what == "kernel" ? kernel_ : what == "view" ? view_
                             : what == "aa"    ? aa_      : what == "update" ? update_ : robust_;
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
  else if (what == "update") update_ = value, needStrategy_ = true;  // a fresh strategy from the frame drawn next
  else if (what == "clip_frame") {  // a jump: drawn next (not advanced past), the strategy fresh there
    clipFrame_ = *parseNumber<int>(value), needStrategy_ = needClipFrame_ = clipJump_ = true;
    clipClock_ = 0.0;
  }  else if (what == "aa") {
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
  so.layout = layout_;
  so.triangles = triangles_;
  so.kernel = kernel_;
  so.reinhard = sc.settings.reinhard;
  // The layout's own bound (a wide node pushes W - 1); while a clip plays, the deepest tree's so far.
  so.bvhStackSize = std::max(stackSizeFor(prepared_->packed), clipStack_);
  so.countStats = countStats;
  so.ssaaGrid = ssaaGridOf(aa_);
  so.robust = parseRobustness(robust_);
  so.textureLod = parseTextureLod(opt_.textureLod);
  so.twoLevel = twoLevel_ != nullptr && prepared_->bvh.nodes.empty() && !prepared_->packed.nodes.empty();
  return so;
}

void Viewer::ensureRenderers() {
  int fbW = 0, fbH = 0;
  glfwGetFramebufferSize(window_, &fbW, &fbH);
  const int w = std::max(1, int(std::lround(fbW * scale_))), h = std::max(1, int(std::lround(fbH * scale_)));
  if (w != renderW_ || h != renderH_) needRenderer_ = true;
  if (animated() && (needRebuild_ || needStrategy_ || needClipFrame_)) {
    const bool switched = needRebuild_;
    updateClipFrame();  // the strategy (fresh after a builder or leaf-size switch) updates the tree
    if (switched && !switches_.empty()) {
      switches_.back()["build_ms"] = prepared_->stats.buildMs;
      switches_.back()["sah_cost"] = prepared_->stats.sahCost;
    }
  }
  if (needRebuild_) {
    statsGpu_.reset();
    gpu_.reset();
    BuildOptions bo;
    bo.maxLeafSize = uint32_t(leafSize_);
    bo.optimize = optimize_;
    auto start = Clock::now();
    prepared_ = prepareScene(Scene(original_), builder_, bo, layout_, triangles_);
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
    // While a clip plays every frame makes new renderers: the programs come from the cache, so only a
    // new shader source (a switch, a deeper tree) compiles, and only then is the next frame a first frame.
    const size_t compiled = programs_ ? programs_->size() : 0;
    if (uploadPending_) glFinish();
    const auto start = Clock::now();
    gpu_ = std::make_unique<GpuRenderer>(*prepared_, shaderOptions(false), fo, programs_.get());
    if (view_ == "visits") statsGpu_ = std::make_unique<GpuRenderer>(*prepared_, shaderOptions(true), fo, programs_.get());
    if (uploadPending_) {  // the clip frame's upload: its pack and the renderer's buffers, waited for
      glFinish();
      lastUploadMs_ = packMs_ + msSince(start);
      recentUploadMs_.push_back(lastUploadMs_);
      if (recentUploadMs_.size() > kRollingWindow) recentUploadMs_.pop_front();
      clipLog_.back()["upload_ms"] = lastUploadMs_;
      uploadPending_ = false;
      clipFrameRendered_ = false;
    }
    needRenderer_ = false;
    firstFramePending_ = !programs_ || programs_->size() > compiled;
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
    if (frame_ > 0) advanceClip(dt);  // the clip's next frame, if it plays (frame 0 draws clip frame 0)
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
                          {"layout", layout_},
                          {"triangle_format", triangles_},
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
                          {"bytes", b.bytes},
                          {"bytes_per_triangle",
                           prepared_->soup.size() ? double(b.bytes) / double(prepared_->soup.size()) : 0.0},
                          {"frame_ms_median", median({recentMs_.begin(), recentMs_.end()})},
                          {"aa_ms_median", median({recentAaMs_.begin(), recentAaMs_.end()})},
                          {"loop_ms_median", median({recentLoopMs_.begin(), recentLoopMs_.end()})},
                          {"present_ms_median", median({recentPresentMs_.begin(), recentPresentMs_.end()})},
                          {"node_visits_per_ray", rayStats_.visitsPerRay},
                          {"triangle_tests_per_ray", rayStats_.testsPerRay},
                          {"camera", cameraJson(camera_.camera())},
                          {"switches", switches_}};
    if (animated()) out.update(clipJson());
    std::cout << out.dump() << std::endl;
  }
  return rayStats_.overflows > 0 ? 3 : 0;
}

}  // namespace viewer_detail

bool viewerAvailable() { return true; }

int runViewer(const ViewerOptions& options) {
  viewer_detail::Viewer viewer(options);
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
