#include "render/clip_update.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "datasets/animation.hpp"
#include "layout/tree_hash.hpp"
#include "layout/triangle_formats.hpp"
#include "render/frame_stats.hpp"
#include "shaders/assemble.hpp"

namespace bvhlab {

ClipPlan planClip(const RenderCommand& cmd, const Scene& scene) {
  try {
    parseUpdateSpec(cmd.update);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--update: ") + e.what());
  }
  if (cmd.updateRepeats < 1) throw std::invalid_argument("--update-repeats must be >= 1");
  if (cmd.clipFrames < 0 || cmd.clipStep < 1) throw std::invalid_argument("--clip-frames must be >= 0 and --clip-step >= 1");
  ClipPlan p;
  p.sceneFrames = clipFrames(scene);
  if (p.sceneFrames <= 1)
    throw std::invalid_argument("--update: " + cmd.input +
                                " is not animated (its clip has 1 frame); --update needs a scene with a clip");
  p.step = cmd.clipStep;
  p.count = (p.sceneFrames + p.step - 1) / p.step;
  if (cmd.clipFrames > 0) p.count = std::min(p.count, cmd.clipFrames);
  return p;
}

ClipUpdater::ClipUpdater(const RenderCommand& cmd, const BuildOptions& build) {
  options_.builder = cmd.builder;
  options_.build = build;
  for (int k = 0; k < cmd.updateRepeats; ++k) {
    try {
      copies_.push_back(makeUpdateStrategy(cmd.update, options_));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--update: ") + e.what());
    }
  }
}

ClipUpdater::Step ClipUpdater::update(const TriangleSoup& soup) {
  Step s;
  const FrameTriangles frame{soup.v0, soup.v1, soup.v2};
  for (size_t k = 0; k < copies_.size(); ++k) {
    const auto start = std::chrono::steady_clock::now();
    const bool rebuilt = copies_[k]->update(frame);
    s.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    const double sah = sahCost(copies_[k]->tree(), options_.build.cost);
    if (k == 0) {
      s.rebuilt = rebuilt;
      s.sah = sah;
    } else if (rebuilt != s.rebuilt || sah != s.sah) {
      s.agree = false;
    }
  }
  return s;
}

std::unique_ptr<ClipGpuRebuild> ClipGpuRebuild::make(const RenderCommand& cmd, const BuildOptions& build,
                                                     const std::string& layout, const std::string& triangleFormat,
                                                     Storage storage) {
  if (parseUpdateSpec(cmd.update).name != "rebuild" || storage == Storage::Tex2D) return nullptr;
  std::unique_ptr<GpuClipBuilder> builder = makeGpuClipBuilder(cmd.builder, build, layout, triangleFormat);
  if (!builder) return nullptr;
  return std::unique_ptr<ClipGpuRebuild>(new ClipGpuRebuild(std::move(builder), cmd.updateRepeats, build.cost));
}

ClipGpuRebuild::Step ClipGpuRebuild::update(const TriangleSoup& soup) {
  Step s;
  std::string firstHash;
  std::vector<std::vector<double>> phases;
  for (int k = 0; k < repeats_; ++k) {
    last_ = builder_->build(soup);
    s.ms.push_back(last_.buildMs);
    s.uploadMs.push_back(last_.uploadMs);
    s.gpuMs.push_back(last_.gpuMs);
    phases.resize(last_.phases.size());
    for (size_t p = 0; p < last_.phases.size(); ++p) phases[p].push_back(last_.phases[p].second);
    const std::string hash = packedTreeHash(last_.packed);
    if (k == 0)
      firstHash = hash;
    else if (hash != firstHash)
      s.agree = false;
  }
  for (size_t p = 0; p < last_.phases.size(); ++p) s.phases.emplace_back(last_.phases[p].first, medianOf(phases[p]));
  s.sah = sahCost(last_.tree, cost_);
  return s;
}

ClipTwoLevel::ClipTwoLevel(const RenderCommand& cmd, const BuildOptions& build, const std::string& layout,
                           const std::string& kernel, const std::string& triangleFormat)
    : cost_(build.cost) {
  const UpdateSpec spec = parseUpdateSpec(cmd.update);
  try {
    if (triangleFormat != "raw")
      throw std::invalid_argument("a two-level tree takes raw triangles, not --triangles " + triangleFormat);
    checkTwoLevel(layout, kernel);
    for (int k = 0; k < cmd.updateRepeats; ++k)
      copies_.push_back(std::make_unique<TwoLevelUpdater>(spec, UpdateOptions{cmd.builder, build}, layout));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--update " + cmd.update + ": " + e.what());
  }
}

ClipTwoLevel::Step ClipTwoLevel::update(const Scene& scene, int frame) {
  Step s;
  for (size_t k = 0; k < copies_.size(); ++k) {
    const TwoLevelUpdater::Step step = copies_[k]->update(scene, frame);
    s.blasMs.push_back(step.blasMs);
    s.tlasMs.push_back(step.tlasMs);
    s.ms.push_back(step.blasMs + step.tlasMs);
    const double sah = copies_[k]->sahCost();
    if (k == 0) {
      s.built = step.blasBuilt;
      s.sah = sah;
      s.packMs = step.packMs;
      s.blasUpdated = step.blasUpdated;
    } else if (step.blasBuilt != s.built || sah != s.sah) {
      s.agree = false;
    }
  }
  return s;
}

BuildStats twoLevelStats(const TwoLevelUpdater& tree, const std::string& builder) {
  BuildStats b;
  b.builder = builder;
  b.nodes = tree.nodeCount();
  b.sahCost = tree.sahCost();
  b.sahBeforeOptimize = b.sahCost;
  const PackedTwoLevel& p = tree.packed();
  b.depth = p.streams.depth;
  b.bytes = p.streams.bytes();
  return b;
}

double packClipFrame(PreparedScene& frame, const Bvh& tree, const LayoutInfo& packer, const std::string& triangleFormat,
                     const std::string& builder) {
  const auto start = std::chrono::steady_clock::now();
  PackedBvh packed = packer.pack(tree, frame.soup);
  packTriangles(packed, frame.soup, triangleFormat);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  setClipFrameTree(frame, tree, std::move(packed), builder);
  return ms;
}

void setClipFrameTree(PreparedScene& frame, const Bvh& tree, PackedBvh packed, const std::string& builder) {
  frame.bvh = tree;
  frame.packed = std::move(packed);
  frame.stats = computeStats(frame.bvh, frame.cost);
  frame.stats.builder = builder;
  frame.stats.bytes = frame.packed.bytes();
}

void putClipTimes(nlohmann::json& j, const std::string& key, const std::vector<double>& ms) {
  const auto ci = medianInterval(ms);
  j[key] = medianOf(ms);
  j[key + "_ci_low"] = ci ? nlohmann::json(ci->low) : nlohmann::json();
  j[key + "_ci_high"] = ci ? nlohmann::json(ci->high) : nlohmann::json();
  j[key + "_all"] = ms;
}

void putTwoLevelFrame(nlohmann::json& j, const ClipTwoLevel::Step& step, const TwoLevelUpdater& tree) {
  j["blas_updated"] = step.blasUpdated;
  putClipTimes(j, "blas_update_ms", step.blasMs);
  putClipTimes(j, "tlas_update_ms", step.tlasMs);
  j["tlas_sah_cost"] = tree.tlasSahCost();
  j["instances"] = tree.instanceCount();
  j["blases"] = tree.blasCount();
}

}  // namespace bvhlab
