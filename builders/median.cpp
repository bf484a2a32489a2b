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
// h = floor(log2 leaves), the level-h nodes of which the leftmost (leaves - 2^h) are split once more:
// half of the 2^h level-h positions are on the left, and the split ones fill from the left.
uint64_t leftLeaves(uint64_t leaves) {
  const uint64_t full = std::bit_floor(leaves);  // 2^h
  const uint64_t half = full / 2;                // level-h positions in the left subtree
  const uint64_t extra = leaves - full;          // level-h positions split into two leaves
  return half + std::min(extra, half);
}

struct Task {
  uint32_t node, begin, end;
  uint64_t leaves;
};

}  // namespace

Bvh buildMedianBvh(const BuildInput& input, const BuildOptions& options) {
  std::vector<PrimRef> refs = detail::makePrimRefs(input);
  const uint32_t n = uint32_t(refs.size());
  const uint64_t leafSize = options.maxLeafSize;

  Bvh bvh;
  bvh.nodes.reserve(2 * size_t(n) - 1);
  bvh.nodes.push_back({});
  std::vector<Task> stack{{0, 0, n, (n + leafSize - 1) / leafSize}};
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    std::span<PrimRef> range(refs.data() + task.begin, task.end - task.begin);
    const detail::RangeBounds bounds = detail::rangeBounds(range);
    BvhNode& node = bvh.nodes[task.node];
    node.bounds = bounds.box;
    if (task.leaves == 1) {
      node.first = task.begin;
      node.count = task.end - task.begin;
      continue;
    }
    const uint64_t leftLeafCount = leftLeaves(task.leaves);
    const uint32_t mid = uint32_t(leftLeafCount * leafSize);  // < range.size(): the right side has >= 1 leaf
    detail::objectMedianSplit(range, mid, detail::longestAxis(bounds.centroids.extent()));
    const uint32_t left = uint32_t(bvh.nodes.size());
    node.left = left;
    node.right = left + 1;
    node.count = 0;
    bvh.nodes.push_back({});
    bvh.nodes.push_back({});
    stack.push_back({left + 1, task.begin + mid, task.end, task.leaves - leftLeafCount});
    stack.push_back({left, task.begin, task.begin + mid, leftLeafCount});
  }

  bvh.primIndices.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.primIndices[i] = refs[i].id;
  return bvh;
}

}  // namespace bvhlab
