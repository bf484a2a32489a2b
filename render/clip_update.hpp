// What `trace --update` and `render --update` share (render/trace_clip.hpp, render/render_clip.hpp):
// the clip's frames to visit, and the update strategy's copies that keep the tree over them, each
// update timed: a flat tree's (ClipUpdater) or a two-level tree's (ClipTwoLevel).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "builders/update.hpp"
#include "datasets/scene.hpp"
#include "layout/layout.hpp"
#include "layout/two_level_update.hpp"
#include "layout/layouts.hpp"
#include "render/gpu_clip_build.hpp"
#include "render/prepared_scene.hpp"
#include "render/render_command.hpp"
#include "shaders/assemble.hpp"  // Storage

namespace bvhlab {

// The frames of the scene's clip a run visits: sceneFrame(i) = i * step for i in [0, count).
struct ClipPlan {
  int sceneFrames = 1, count = 1, step = 1;
  int sceneFrame(int i) const { return i * step; }
};
// Checks cmd.update (parseUpdateSpec; std::invalid_argument naming --update), --update-repeats,
// --clip-frames and --clip-step, and refuses a scene whose clip has one frame (naming --update).
ClipPlan planClip(const RenderCommand& cmd, const Scene& scene);

// cmd.updateRepeats copies of the strategy cmd.update, building with cmd.builder and `build`.
class ClipUpdater {
 public:
  ClipUpdater(const RenderCommand& cmd, const BuildOptions& build);
  struct Step {
    bool rebuilt = false;
    bool agree = true;  // every copy rebuilt alike and reached the same SAH
    double sah = 0.0;   // copy 0's tree, with the build's cost model
    std::vector<double> ms;  // each copy's update, wall-clock (steady_clock)
  };
  // Every copy updated to the frame's triangles, each timed; copy 0's tree is the one to use.
  Step update(const TriangleSoup& soup);
  const Bvh& tree() const { return copies_.front()->tree(); }
  uint32_t rotations() const { return copies_.front()->rotations(); }
  const CostModel& cost() const { return options_.build.cost; }

 private:
  UpdateOptions options_;
  std::vector<std::unique_ptr<UpdateStrategy>> copies_;
};

// `--update rebuild` with a GPU builder that builds and packs the run's layout on the GPU, traced from
// the streams it leaves there (render/gpu_clip_build.hpp): each frame built cmd.updateRepeats times, each
// build uploading the frame's triangles and building from them; the last build's streams are traced.
class ClipGpuRebuild {
 public:
  // The GPU path for this run, or nullptr where it does not apply: another strategy, a CPU builder, a
  // layout the GPU does not pack, another triangle format, or `storage` tex2d (which would copy).
  static std::unique_ptr<ClipGpuRebuild> make(const RenderCommand& cmd, const BuildOptions& build,
                                              const std::string& layout, const std::string& triangleFormat,
                                              Storage storage);
  struct Step {
    bool agree = true;  // every build gave the same streams (tree_hash)
    double sah = 0.0;   // the tree's, with the build's cost model
    std::vector<double> ms, uploadMs, gpuMs;  // per build: GpuClipFrame's buildMs, uploadMs, gpuMs
    std::vector<std::pair<std::string, double>> phases;  // per phase, its median over the builds
  };
  // Needs the GL context every frame of the clip is built in.
  Step update(const TriangleSoup& soup);
  const GpuClipFrame& frame() const { return last_; }  // the last build's: the tree to trace
  const CostModel& cost() const { return cost_; }

 private:
  ClipGpuRebuild(std::unique_ptr<GpuClipBuilder> builder, int repeats, const CostModel& cost)
      : builder_(std::move(builder)), repeats_(repeats), cost_(cost) {}
  std::unique_ptr<GpuClipBuilder> builder_;
  int repeats_ = 1;
  CostModel cost_;
  GpuClipFrame last_;
};

// cmd.updateRepeats copies of a two-level strategy (cmd.update is `two-level[:...]`; layout/
// two_level_update.hpp) over `layout` with the kernel `kernel` (std::invalid_argument naming --update
// for a layout or kernel without a two-level walk, or a triangle format other than raw).
class ClipTwoLevel {
 public:
  ClipTwoLevel(const RenderCommand& cmd, const BuildOptions& build, const std::string& layout,
               const std::string& kernel, const std::string& triangleFormat);
  struct Step {
    bool built = false;          // copy 0 built some BLAS from scratch
    bool agree = true;           // every copy built alike and reached the same SAH
    double sah = 0.0;            // copy 0's sahCost()
    uint32_t blasUpdated = 0;    // copy 0's
    double packMs = 0.0;         // copy 0's BLAS pack
    std::vector<double> blasMs, tlasMs, ms;  // each copy's parts and their sums (update_ms)
  };
  // Every copy brought to `scene` at `frame` (setFrame done by the caller), each timed.
  Step update(const Scene& scene, int frame);
  const TwoLevelUpdater& first() const { return *copies_.front(); }
  const CostModel& cost() const { return cost_; }

 private:
  CostModel cost_;
  std::vector<std::unique_ptr<TwoLevelUpdater>> copies_;
};

// A two-level frame's tree statistics for a PreparedScene (render/prepared_scene.hpp): its nodes (the
// TLAS's and each BLAS's once), the two-level SAH estimate (TwoLevelUpdater::sahCost), depth and bytes.
BuildStats twoLevelStats(const TwoLevelUpdater& tree, const std::string& builder);

// A flat frame made ready to draw from the strategy's tree: frame.bvh = tree, packed by `packer` into
// `triangleFormat` (returns the pack's ms: steady_clock), frame.stats computed (with frame.cost) and
// named after `builder`. frame.scene and frame.soup are the frame's already.
double packClipFrame(PreparedScene& frame, const Bvh& tree, const LayoutInfo& packer, const std::string& triangleFormat,
                     const std::string& builder);

// The same for a tree packed already (on the GPU: ClipGpuRebuild's frame, whose streams the caller also
// sets in frame.gpuStreams): frame.bvh, frame.packed and frame.stats.
void setClipFrameTree(PreparedScene& frame, const Bvh& tree, PackedBvh packed, const std::string& builder);

// A part's samples as the JSON keys KEY, KEY_ci_low, KEY_ci_high (null below 6 samples) and KEY_all.
void putClipTimes(nlohmann::json& j, const std::string& key, const std::vector<double>& ms);
// A two-level frame's own keys of `trace --json` and `render --json`: blas_updated, blas_update_ms,
// tlas_update_ms (putClipTimes), tlas_sah_cost, instances, blases.
void putTwoLevelFrame(nlohmann::json& j, const ClipTwoLevel::Step& step, const TwoLevelUpdater& tree);

}  // namespace bvhlab
