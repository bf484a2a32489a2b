// The viewer's frames: rendering (and the instrumented statistics frame), presenting to the window,
// the overlay, screenshots and camera paths (render/viewer_app.hpp).
#include "render/viewer_app.hpp"

#ifdef BVHLAB_VIEWER

#include <algorithm>
#include <cstdio>

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "datasets/image_io.hpp"
#include "render/gl_context.hpp"
#include "render/heatmap.hpp"

namespace bvhlab::viewer_detail {

// ---- frames -----------------------------------------------------------------------

void Viewer::renderFrame() {
  ensureRenderers();
  const Camera& cam = camera_.camera();
  gpu_->setCamera(cam);
  const double traceMs = gpu_->drawFrame();
  if (animated() && !clipFrameRendered_) {  // the clip frame's first draw: its trace time
    clipLog_.back()["trace_ms"] = traceMs;
    clipFrameRendered_ = true;
  }
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
      statsGpu_ = std::make_unique<GpuRenderer>(*prepared_, shaderOptions(true), fo, programs_.get());
    }
    statsGpu_->setCamera(cam);
    statsGpu_->drawFrame();
    std::vector<glm::uvec4> stats = statsGpu_->readStats();
    rayStats_ = summarize(stats);
    if (animated() && !clipLog_.empty() && !clipLog_.back().contains("node_visits_per_ray")) {
      clipLog_.back()["node_visits_per_ray"] = rayStats_.visitsPerRay;
      clipLog_.back()["triangle_tests_per_ray"] = rayStats_.testsPerRay;
    }
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
  // Waited for here, so presenting (the overlay's draw, on llvmpipe its shader's compile when the
  // overlay first appears) counts in the present time and not in the next frame's trace time.
  glFinish();
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
        for (const std::string& c : choices(what, layout_, triangles_)) {
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
    combo(("[K] kernel (" + layout_ + ")").c_str(), "kernel", kernel_);
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
    ImGui::Text("layout %s, %s triangles: %.1f bytes per triangle", layout_.c_str(), triangles_.c_str(),
                prepared_->soup.size() ? double(b.bytes) / double(prepared_->soup.size()) : 0.0);
    if (rayStats_.valid)
      ImGui::Text("per ray: %.1f node visits, %.1f triangle tests%s", rayStats_.visitsPerRay, rayStats_.testsPerRay,
                  rayStats_.overflows ? "  STACK OVERFLOW" : "");
    drawClipOverlay();
    ImGui::Separator();
    const Camera& c = camera_.camera();
    ImGui::Text("eye %.3f %.3f %.3f  fov %.0f [F]  speed %.3g/s", c.eye.x, c.eye.y, c.eye.z, c.fovDeg, speed_);
    ImGui::Text("%s%s%s", recording_ ? "REC  " : "", replaying_ ? "REPLAY  " : "", status_.c_str());
    ImGui::TextDisabled("%s", glRenderer_.c_str());
    ImGui::TextDisabled("Tab mouse look, WASD/QE move, wheel speed, P shot, R rec, O replay, Ctrl+1-4 mark");
    ImGui::TextDisabled("Shift+key cycles backwards%s", animated() ? "; Space plays/pauses the clip, U strategy" : "");
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

}  // namespace bvhlab::viewer_detail

#endif  // BVHLAB_VIEWER
