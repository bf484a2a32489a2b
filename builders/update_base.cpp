// UpdateStrategyBase (builders/update_base.hpp).
#include "builders/update_base.hpp"

#include <cmath>
#include <stdexcept>

#include "builders/build_util.hpp"  // resolveThreads
#include "builders/builder.hpp"
#include "datasets/scene.hpp"  // InputError

namespace bvhlab::detail {

void UpdateStrategyBase::checkCount(const FrameTriangles& frame) const {
  if (!first() && frame.size() != count_)
    throw std::invalid_argument("update '" + spec_.text + "': a frame of " + std::to_string(frame.size()) +
                                " triangles after frames of " + std::to_string(count_) +
                                " (every frame of a clip has the same triangles)");
}

void UpdateStrategyBase::rebuild(const FrameTriangles& frame) {
  const size_t n = frame.size();
  if (frame.v1.size() != n || frame.v2.size() != n)
    throw std::invalid_argument("update: " + std::to_string(n) + "/" + std::to_string(frame.v1.size()) + "/" +
                                std::to_string(frame.v2.size()) + " triangle vertices (v0/v1/v2 differ in length)");
  checkFiniteVertices(frame);
  boxes_.resize(n);
  centroids_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    boxes_[i] = triangleBox(frame, i);
    centroids_[i] = 0.5f * boxes_[i].min + 0.5f * boxes_[i].max;  // as triangleCentroids: halves first (no overflow)
  }
  BuildInput input{boxes_, centroids_, frame.v0, frame.v1, frame.v2};
  tree_ = buildBvh(options_.builder, input, options_.build);
  schedule_ = refitSchedule(tree_, resolveThreads(options_.build.threads));
  count_ = n;
}

void UpdateStrategyBase::refit(const FrameTriangles& frame, SahSums* sums) {
  refitBvh(tree_, schedule_, frame, resolveThreads(options_.build.threads), sums);
}

}  // namespace bvhlab::detail
