// Tree statistics recomputed from a built Bvh: nothing here trusts what a builder says about itself.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "builders/bvh.hpp"
#include "builders/refit.hpp"

namespace bvhlab {

namespace {

// Visits every node reachable from the root with an explicit stack (a degenerate tree may be as
// deep as it has primitives), calling visit(node, depth) with the root at depth 1.
template <class Visit>
void walkNodes(const Bvh& bvh, Visit&& visit) {
  if (bvh.nodes.empty()) return;
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};
  size_t visited = 0;
  while (!stack.empty()) {
    auto [index, depth] = stack.back();
    stack.pop_back();
    // A well-formed tree visits each node once; more visits than nodes means a cycle or a DAG.
    if (index >= bvh.nodes.size() || ++visited > bvh.nodes.size())
      throw std::runtime_error("malformed BVH: child index out of range or node reached twice");
    const BvhNode& node = bvh.nodes[index];
    visit(node, depth);
    if (!node.isLeaf()) {
      stack.push_back({node.right, depth + 1});
      stack.push_back({node.left, depth + 1});
    }
  }
}

}  // namespace

double sahCost(const SahSums& sums, double rootHalfArea, const CostModel& cost) {
  if (!std::isfinite(rootHalfArea))  // builders reject such input; a hand-made tree must not turn NaN into a cost
    throw std::runtime_error("sahCost: the root box is not finite");
  // A root of zero area (all primitives are one point) has no meaningful ratio: every node has the
  // root's box then, so each area ratio is 1 and the cost is the plain node/reference count.
  if (rootHalfArea <= 0.0) return cost.traversalCost * sums.innerNodes + cost.intersectionCost * sums.references;
  return (cost.traversalCost * sums.innerArea + cost.intersectionCost * sums.leafArea) / rootHalfArea;
}

double sahCost(const Bvh& bvh, const CostModel& cost) {
  if (bvh.nodes.empty()) return 0.0;
  std::vector<uint32_t> order;
  try {
    order = refitOrder(bvh);
  } catch (const std::invalid_argument&) {
    throw std::runtime_error("malformed BVH: child index out of range or node reached twice");
  }
  SahSums sums;
  for (const uint32_t index : order) sums.add(bvh.nodes[index]);
  return sahCost(sums, bvh.nodes[0].bounds.halfArea(), cost);
}

BuildStats computeStats(const Bvh& bvh, const CostModel& cost) {
  BuildStats stats;
  walkNodes(bvh, [&](const BvhNode& node, uint32_t depth) {
    ++stats.nodes;
    stats.depth = std::max(stats.depth, depth);
    if (node.isLeaf()) {
      ++stats.leaves;
      stats.references += node.count;
      stats.primsPerLeafMax = std::max(stats.primsPerLeafMax, node.count);
    }
  });
  stats.primitives = stats.references;  // buildBvh sets the input's count (they differ for sbvh)
  stats.primsPerLeafMean = stats.leaves ? double(stats.references) / double(stats.leaves) : 0.0;
  stats.sahCost = sahCost(bvh, cost);
  return stats;
}

}  // namespace bvhlab
