// Object-median builder: a COMPLETE binary tree with full leaves. With L = maxLeafSize and
// K = ceil(N / L) leaves, every leaf holds exactly L primitives except the last (rightmost) one, and
// every level is full except the deepest, which fills from the left. Each node splits its references
// at the object median on its longest centroid axis, the split position chosen so that the left
// subtree receives whole leaves in the shape of a complete tree.
#include <bit>
#include <span>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab {

namespace {

using detail::PrimRef;

// Leaves of the left subtree of a complete binary tree with `leaves` >= 2 leaves. With
// h = floor(log2 leaves), the leftmost (leaves - 2^h) of the 2^h level-h positions are split once
// more; half of the level-h positions are in the left subtree, and the split ones fill from the left.
uint64_t leftLeaves(uint64_t leaves) {
  const uint64_t full = std::bit_floor(leaves);  // 2^h
  const uint64_t half = full / 2;                // level-h positions in the left subtree
  const uint64_t extra = leaves - full;          // level-h positions split into two leaves
  return half + std::min(extra, half);
}

struct Task {
  uint32_t node, begin, end;
  uint64_t leaves;  // leaves of this subtree
  Aabb centroids;
};

class MedianStepper {
 public:
  MedianStepper(detail::ScratchVector<PrimRef>& refs, uint32_t leafSize) : refs_(refs), leafSize_(leafSize) {}

  detail::NodeStep<Task> step(const Task& task, const Aabb&) {
    detail::NodeStep<Task> step;
    if (task.leaves == 1) return step;
    const uint64_t leftLeafCount = leftLeaves(task.leaves);
    const uint32_t mid = uint32_t(leftLeafCount * leafSize_);  // < range size: the right side has >= 1 leaf
    std::span<PrimRef> range(refs_.data() + task.begin, task.end - task.begin);
    detail::objectMedianSplit(range, mid, detail::longestAxis(task.centroids.extent()));
    const detail::RangeBounds left = detail::rangeBounds(range.first(mid));
    const detail::RangeBounds right = detail::rangeBounds(range.subspan(mid));
    step.leaf = false;
    step.childBox[0] = left.box;
    step.childBox[1] = right.box;
    step.child[0] = {0, task.begin, task.begin + mid, leftLeafCount, left.centroids};
    step.child[1] = {0, task.begin + mid, task.end, task.leaves - leftLeafCount, right.centroids};
    return step;
  }

 private:
  detail::ScratchVector<PrimRef>& refs_;
  uint32_t leafSize_;
};

}  // namespace

Bvh buildMedianBvh(const BuildInput& input, const BuildOptions& options) {
  detail::ScratchVector<PrimRef> refs = detail::makePrimRefs(input);
  const uint32_t n = uint32_t(refs.size());
  const uint32_t leafSize = options.maxLeafSize;
  const detail::RangeBounds all = detail::rangeBounds(refs);

  Bvh bvh;
  bvh.nodes = detail::buildTopDown(all.box, Task{0, 0, n, (uint64_t(n) + leafSize - 1) / leafSize, all.centroids},
                                   detail::resolveThreads(options.threads),
                                   [&] { return MedianStepper(refs, leafSize); });
  bvh.primIndices.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.primIndices[i] = refs[i].id;
  return bvh;
}

}  // namespace bvhlab
