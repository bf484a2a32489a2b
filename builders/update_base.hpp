// What the update strategies share (builders/update_*.cpp): the tree, the first frame's triangle
// count, and the two ways to bring the tree to a frame, a build from scratch and a refit.
#pragma once
#include <string>
#include <vector>

#include "builders/update.hpp"

namespace bvhlab::detail {

class UpdateStrategyBase : public UpdateStrategy {
 public:
  UpdateStrategyBase(UpdateSpec spec, UpdateOptions options) : spec_(std::move(spec)), options_(std::move(options)) {}
  const Bvh& tree() const override { return tree_; }
  const UpdateSpec& spec() const override { return spec_; }
  const UpdateOptions& options() const override { return options_; }

 protected:
  bool first() const { return tree_.nodes.empty(); }
  // Throws std::invalid_argument unless `frame` has the first frame's triangle count (any count on
  // the first frame).
  void checkCount(const FrameTriangles& frame) const;
  // A new tree over the frame with options_.builder and options_.build (the boxes and centroids the
  // app gives a builder: layout/layout.hpp triangleBoxes and triangleCentroids; the triangles too, so
  // a builder that splits primitives clips them). Keeps the refit order of the new tree.
  void rebuild(const FrameTriangles& frame);
  // Refit with the schedule kept since the last rebuild (the topology has not changed since), on
  // options_.build.threads threads; with `sums`, the refit tree's SahSums (builders/refit.hpp).
  void refit(const FrameTriangles& frame, SahSums* sums = nullptr);

  Bvh tree_;
  size_t count_ = 0;  // triangles per frame (the first frame's)

 private:
  UpdateSpec spec_;
  UpdateOptions options_;
  RefitSchedule schedule_;  // the refit's order and its tasks for the build's threads (since the last rebuild)
  std::vector<Aabb> boxes_;  // scratch kept between rebuilds (no reallocation per frame)
  std::vector<glm::vec3> centroids_;
};

}  // namespace bvhlab::detail
