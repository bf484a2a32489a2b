// `--optimize reinsert` with the primitives at hand: the leaves are re-formed too.
//
// The inner-structure pass (reinsert.cpp) keeps every leaf; a tree whose leaves are full (median:
// 4 primitives each) keeps a leaf cost no reinsertion touches (14.4 of the bunny's 46.0). Given the
// builder's input, this pass
//  1. expands every leaf of c > 1 primitives into a binary subtree of c single-primitive leaves
//     (split at the median of the longest centroid axis, recursively),
//  2. runs the inner-structure pass on that tree, so single primitives move (Bittner et al. 2013
//     optimise trees of single-primitive leaves too),
//  3. collapses the result into SAH-optimal leaves of at most maxLeafSize primitives
//     (builders/collapse.hpp, as lbvh and ploc do: a subtree becomes one leaf where that costs less).
// Step 3 on the tree of step 1 gives the input's leaves back or better ones, but step 2 optimises the
// inner areas of the expanded tree, a proxy for the collapsed SAH: the result is kept only if its SAH
// is no higher than the input's, otherwise the inner-structure pass runs on the input tree instead.
//
// A leaf can be expanded only when its box is exactly the union of its primitives' input boxes:
// SBVH's leaves hold clipped references whose boxes are smaller, and a tree with such a leaf (or
// primitive indices outside the input) gets the inner-structure pass alone, leaves kept.
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/build_util.hpp"
#include "builders/collapse.hpp"
#include "builders/reinsert.hpp"

namespace bvhlab {

namespace {

bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

uint32_t depthOf(const Bvh& bvh) {
  uint32_t depth = 0;
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};
  while (!stack.empty()) {
    const auto [i, d] = stack.back();
    stack.pop_back();
    depth = std::max(depth, d);
    const BvhNode& n = bvh.nodes[i];
    if (!n.isLeaf()) stack.push_back({n.left, d + 1}), stack.push_back({n.right, d + 1});
  }
  return depth;
}

// The tree with single-reference leaves (leaf k of the result: first = k, an index into the same
// primIndices), or an empty Bvh when some leaf cannot be expanded (see the header comment) or the
// nodes do not form a tree (the inner-structure pass then reports that).
Bvh expandLeaves(const Bvh& bvh, const BuildInput& input) {
  const size_t count = bvh.nodes.size(), prims = input.boxes.size();
  Bvh out;
  out.primIndices = bvh.primIndices;
  out.nodes.reserve(2 * bvh.primIndices.size());
  std::vector<char> reached(count, 0);
  std::vector<uint32_t> refs;
  // (node in bvh, slot in out); a slot is written when its node is taken off the stack.
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
  out.nodes.emplace_back();
  while (!stack.empty()) {
    const auto [i, slot] = stack.back();
    stack.pop_back();
    if (i >= count || reached[i]) return {};
    reached[i] = 1;
    const BvhNode& n = bvh.nodes[i];
    if (!n.isLeaf()) {
      const uint32_t left = uint32_t(out.nodes.size());
      out.nodes[slot] = {n.bounds, left, left + 1, 0, 0};
      out.nodes.emplace_back();
      out.nodes.emplace_back();
      stack.push_back({n.right, left + 1});
      stack.push_back({n.left, left});
      continue;
    }
    if (uint64_t(n.first) + n.count > bvh.primIndices.size()) return {};
    Aabb box;
    refs.clear();
    for (uint32_t k = n.first; k < n.first + n.count; ++k) {
      if (bvh.primIndices[k] >= prims) return {};
      box.grow(input.boxes[bvh.primIndices[k]]);
      refs.push_back(k);
    }
    if (!sameBox(box, n.bounds)) return {};
    // A subtree over refs[lo, hi) at `at`: halves at the median of the longest centroid axis
    // (ties by reference index, so the split is a function of the leaf alone).
    struct Range {
      uint32_t lo, hi, at;
    };
    std::vector<Range> ranges{{0, uint32_t(refs.size()), slot}};
    while (!ranges.empty()) {
      const Range r = ranges.back();
      ranges.pop_back();
      if (r.hi - r.lo == 1) {
        const uint32_t k = refs[r.lo];
        out.nodes[r.at] = {input.boxes[bvh.primIndices[k]], 0, 0, k, 1};
        continue;
      }
      Aabb bounds, centres;
      for (uint32_t j = r.lo; j < r.hi; ++j) {
        bounds.grow(input.boxes[bvh.primIndices[refs[j]]]);
        centres.grow(input.centroids[bvh.primIndices[refs[j]]]);
      }
      const glm::vec3 e = centres.max - centres.min;
      const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
      const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
      std::nth_element(refs.begin() + r.lo, refs.begin() + mid, refs.begin() + r.hi, [&](uint32_t a, uint32_t b) {
        const float ca = input.centroids[bvh.primIndices[a]][axis], cb = input.centroids[bvh.primIndices[b]][axis];
        return ca < cb || (ca == cb && a < b);
      });
      const uint32_t left = uint32_t(out.nodes.size());
      out.nodes[r.at] = {bounds, left, left + 1, 0, 0};
      out.nodes.emplace_back();
      out.nodes.emplace_back();
      ranges.push_back({mid, r.hi, left + 1});
      ranges.push_back({r.lo, mid, left});
    }
  }
  return out;
}

// The SAH collapse of a tree of single-reference leaves (leaf first = index into primIndices): the
// nodes renumbered depth-first (every child after its parent, as collapse.hpp wants), each leaf
// holding its primitive id.
Bvh collapse(const Bvh& single, const BuildOptions& options) {
  std::vector<BvhNode> full;
  full.reserve(single.nodes.size());
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};  // (node in single, its slot in full)
  full.emplace_back();
  while (!stack.empty()) {
    const auto [i, slot] = stack.back();
    stack.pop_back();
    const BvhNode& n = single.nodes[i];
    if (n.isLeaf()) {
      full[slot] = {n.bounds, 0, 0, single.primIndices[n.first], 1};
      continue;
    }
    const uint32_t left = uint32_t(full.size());
    full[slot] = {n.bounds, left, left + 1, 0, 0};
    full.emplace_back();
    full.emplace_back();
    stack.push_back({n.right, left + 1});
    stack.push_back({n.left, left});
  }
  return detail::collapseLeavesBySah(full, options);
}

}  // namespace

void optimizeReinsert(Bvh& bvh, const BuildInput& input, const BuildOptions& options) {
  Bvh single = expandLeaves(bvh, input);
  if (single.nodes.empty() || !(options.cost.traversalCost > 0.0f)) return optimizeReinsert(bvh, options);
  const double sahBefore = sahCost(bvh, options.cost);
  const uint32_t depthBound = std::max(depthOf(bvh), detail::kReinsertMinDepthLimit);
  detail::optimizeInnerStructure(single, options, std::max(depthOf(single), detail::kReinsertMinDepthLimit));
  Bvh result = collapse(single, options);
  // The collapse only merges subtrees, so its depth is at most the expanded tree's; the bound checked
  // here is the inner-structure pass's promise for the input tree.
  if (sahCost(result, options.cost) <= sahBefore && depthOf(result) <= depthBound) {
    bvh = std::move(result);
    return;
  }
  optimizeReinsert(bvh, options);
}

}  // namespace bvhlab
