// The viewer's clip playback (render/viewer_app.hpp): an animated scene plays frame by frame, its tree
// kept by an update strategy (builders/update.hpp) that can be switched live, with the three times of
// a dynamic frame in the overlay: the update (CPU), the upload (pack + the renderer's buffers) and the
// trace. The same steps as `bvhlab render --update` (render/render_clip.cpp), one clip frame per
// rendered frame.
#include "render/viewer_app.hpp"

#ifdef BVHLAB_VIEWER

#include <algorithm>
#include <cmath>
#include <utility>

#include <imgui.h>

#include "builders/builder.hpp"
#include "datasets/animation.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "render/clip_update.hpp"

namespace bvhlab::viewer_detail {

namespace {

void pushRolling(std::deque<double>& d, double v) {
  d.push_back(v);
  if (d.size() > kRollingWindow) d.pop_front();
}

}  // namespace

void Viewer::setupClip() {
  clipFrames_ = clipFrames(original_);
  if (!animated()) {
    if (opt_.update)
      throw std::invalid_argument("--update: " + opt_.input +
                                  " is not animated (its clip has 1 frame); --update needs a scene with a clip");
    return;
  }
  clipFps_ = clipFps(original_);
  update_ = opt_.update.value_or("rebuild");
  if (std::string e = settingError("update", update_, layout_, triangles_); !e.empty())
    throw std::invalid_argument("--update: " + e);
  clipScene_ = original_;
  programs_ = std::make_unique<ProgramCache>();
  playing_ = !opt_.paused;
}

void Viewer::togglePlay() {
  if (!animated()) {
    status_ = "static scene: nothing to play";
    return;
  }
  playing_ = !playing_;
  clipClock_ = 0.0;
  status_ = playing_ ? "playing" : "paused";
}

void Viewer::advanceClip(double dt) {
  const bool jumped = std::exchange(clipJump_, false);
  if (!animated() || !playing_ || jumped) return;
  // Scripted: one clip frame per rendered frame, so a script plays the same frames every run.
  // Interactive: the clip's own rate, but never more than one clip frame per rendered frame (a slow
  // frame slows the clip down rather than skipping frames the strategy would then update across).
  int step = 1;
  if (!script_) {
    clipClock_ += dt * clipFps_;
    step = clipClock_ >= 1.0 ? 1 : 0;
    clipClock_ = std::min(clipClock_ - step, 1.0);
  }
  if (step == 0) return;
  clipFrame_ += step;
  if (clipFrame_ >= clipFrames_) {
    // The clip starts again: a fresh strategy (a refit from the last frame's tree to frame 0 would
    // update across the whole clip at once), so every loop measures the same updates.
    clipFrame_ = 0;
    needStrategy_ = true;
  }
  needClipFrame_ = true;
}

void Viewer::updateClipFrame() {
  UpdateOptions uo;
  uo.builder = builder_;
  uo.build.maxLeafSize = uint32_t(leafSize_);
  uo.build.optimize = optimize_;
  const UpdateSpec spec = parseUpdateSpec(update_);
  const bool twoLevel = spec.name == "two-level";
  if (!twoLevel && (!strategy_ || needStrategy_ || needRebuild_)) strategy_ = makeUpdateStrategy(update_, uo);
  if (twoLevel && (!twoLevel_ || needStrategy_ || needRebuild_)) twoLevel_ = std::make_unique<TwoLevelUpdater>(spec, uo, layout_);
  if (!twoLevel) twoLevel_.reset();
  // A GPU rebuild keeps no state between frames: it is made again only for another builder or leaf size.
  const std::string& format = findTriangleFormat(triangles_).name;
  if (spec.name != "rebuild")
    gpuClip_.reset();
  else if (!gpuClip_ || needRebuild_)
    gpuClip_ = makeGpuClipBuilder(builder_, uo.build, layout_, format);
  needStrategy_ = needRebuild_ = false;

  setFrame(clipScene_, clipFrame_);
  auto frame = std::make_unique<PreparedScene>();
  frame->scene = clipScene_;
  frame->cost = uo.build.cost;
  frame->data = buildSceneData(frame->scene);
  frame->soup = gatherTriangles(frame->scene);
  const LayoutInfo& packer = findLayout(layout_);
  lastUpdateMs_ = packMs_ = 0.0;
  lastRebuilt_ = false;
  if (frame->soup.size() > 0 && twoLevel) {
    // The two-level tree (BLASes per the policy, the TLAS rebuilt), drawn by the kernel's two-level walk.
    const TwoLevelUpdater::Step step = twoLevel_->update(frame->scene, clipFrame_);
    lastRebuilt_ = step.blasBuilt;
    lastUpdateMs_ = step.blasMs + step.tlasMs;
    packMs_ = step.packMs;
    frame->packed = twoLevel_->packed().streams;
    frame->stats = twoLevelStats(*twoLevel_, builder_);
  } else if (frame->soup.size() > 0 && gpuClip_) {
    statsGpu_.reset();  // the renderers bind the last frame's streams, which this build replaces
    gpu_.reset();
    const GpuClipFrame built = gpuClip_->build(frame->soup);
    lastRebuilt_ = true;
    lastUpdateMs_ = built.buildMs;
    packMs_ = built.uploadMs;
    setClipFrameTree(*frame, built.tree, built.packed, builder_);
    frame->gpuStreams = {built.streams[0], built.streams[1], built.streams[2]};
    frame->stats.buildMs = lastUpdateMs_;
  } else if (frame->soup.size() > 0) {
    const FrameTriangles tris{frame->soup.v0, frame->soup.v1, frame->soup.v2};
    const auto start = Clock::now();
    lastRebuilt_ = strategy_->update(tris);
    lastUpdateMs_ = msSince(start);
    packMs_ = packClipFrame(*frame, strategy_->tree(), packer, format, builder_);
    frame->stats.buildMs = lastRebuilt_ ? lastUpdateMs_ : 0.0;
  } else {
    frame->packed.layout = packer.name;
    frame->packed.triangleFormat = format;
  }
  // The renderers read prepared_: they go before it is replaced.
  statsGpu_.reset();
  gpu_.reset();
  prepared_ = std::move(frame);
  // One traversal stack for the clip (the deepest tree so far), so a tree one level deeper than the
  // last does not make a new program (render --update does the same).
  clipStack_ = std::max(clipStack_, stackSizeFor(prepared_->packed));
  if (frame_ == 0) speed_ = 0.5f * prepared_->data.sceneRadius;
  // A clip with a camera path flies it while playing (pause to fly freely); a replayed path wins.
  const bool clipCamera = original_.animation && !original_.animation->camera.empty();
  if (clipCamera && playing_ && !replaying_) camera_.setCamera(prepared_->scene.camera);
  needClipFrame_ = false;
  needRenderer_ = true;
  uploadPending_ = true;
  statsStale_ = true;
  clipLog_.push_back({{"frame", frame_},
                      {"clip_frame", clipFrame_},
                      {"update", update_},
                      {"builder", builder_},
                      {"rebuilt", lastRebuilt_},
                      {"update_on", gpuClip_ ? "gpu" : "cpu"},
                      {"update_ms", lastUpdateMs_},
                      {"pack_ms", packMs_},
                      {"sah_cost", prepared_->stats.sahCost},
                      {"nodes", prepared_->stats.nodes}});
  pushRolling(recentUpdateMs_, lastUpdateMs_);
}

void Viewer::drawClipOverlay() {
  if (!animated()) return;
  ImGui::Separator();
  ImGui::Text("clip frame %d / %d at %.0f fps  %s [Space]", clipFrame_, clipFrames_, clipFps_,
              playing_ ? "playing" : "paused");
  ImGui::SetNextItemWidth(170);
  if (ImGui::BeginCombo("[U] update", update_.c_str())) {
    for (const std::string& c : choices("update", layout_, triangles_)) {
      const bool selected = c == update_;
      if (ImGui::Selectable(c.c_str(), selected) && !selected) set("update", c);
      if (selected) ImGui::SetItemDefaultFocus();
    }
    ImGui::EndCombo();
  }
  ImGui::SameLine();
  ImGui::Text("%s", lastRebuilt_ ? "rebuilt" : "updated");
  const double trace = recentMs_.empty() ? lastDrawMs_ : median({recentMs_.begin(), recentMs_.end()});
  ImGui::Text("update %.2f ms + upload %.2f ms + trace %.2f ms (last)", lastUpdateMs_, lastUploadMs_, lastDrawMs_);
  ImGui::Text("medians: update %.2f, upload %.2f, frame %.2f ms", median({recentUpdateMs_.begin(), recentUpdateMs_.end()}),
              median({recentUploadMs_.begin(), recentUploadMs_.end()}), trace);
}

nlohmann::json Viewer::clipJson() const {
  nlohmann::json j;
  j["update"] = update_;
  j["clip_frames"] = clipFrames_;
  j["clip_fps"] = clipFps_;
  j["clip_frame"] = clipFrame_;
  j["playing"] = playing_;
  j["update_ms_median"] = median({recentUpdateMs_.begin(), recentUpdateMs_.end()});
  j["upload_ms_median"] = median({recentUploadMs_.begin(), recentUploadMs_.end()});
  j["clip"] = clipLog_;
  return j;
}

}  // namespace bvhlab::viewer_detail

#endif  // BVHLAB_VIEWER
