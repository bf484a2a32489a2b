// The SAH leaf collapse that the bottom-up builders (lbvh, ploc) share: they build a binary tree
// down to single primitives, then every subtree of at most maxLeafSize primitives whose SAH cost as
// one leaf (Ci * count * area) is no higher than as a subtree becomes one leaf.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "builders/bvh.hpp"

namespace bvhlab::detail {

// `full`: a binary tree with its root at 0 and every child at a larger index than its parent, every
// box set, and every leaf holding one primitive (count 1, first = the primitive's input id). Returns
// the collapsed tree, emitted depth-first (left child first); primIndices lists the primitives in
// the order the leaves are emitted, so a leaf's range is contiguous.
inline Bvh collapseLeavesBySah(const std::vector<BvhNode>& full, const BuildOptions& options) {
  struct Info {
    uint32_t count;
    double cost;  // SAH cost of the subtree as it will be emitted, in unnormalised areas
    bool collapse;
  };
  std::vector<Info> info(full.size());
  const CostModel& c = options.cost;
  for (size_t i = full.size(); i-- > 0;) {  // children before parents
    const BvhNode& node = full[i];
    if (node.isLeaf()) {
      info[i] = {node.count, c.intersectionCost * double(node.bounds.halfArea()) * node.count, true};
      continue;
    }
    const Info &l = info[node.left], &r = info[node.right];
    const double area = node.bounds.halfArea();
    const uint32_t count = l.count + r.count;
    const double asLeaf = c.intersectionCost * area * count, asTree = c.traversalCost * area + l.cost + r.cost;
    const bool collapse = count <= options.maxLeafSize && asLeaf <= asTree;
    info[i] = {count, collapse ? asLeaf : asTree, collapse};
  }

  Bvh bvh;
  bvh.nodes.reserve(full.size());
  bvh.primIndices.reserve(info[0].count);
  bvh.nodes.push_back({full[0].bounds});
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};  // (index in full, index in bvh)
  std::vector<uint32_t> leafStack;
  while (!stack.empty()) {
    auto [from, to] = stack.back();
    stack.pop_back();
    const BvhNode& node = full[from];
    if (info[from].collapse) {  // its primitives, left to right
      bvh.nodes[to].first = uint32_t(bvh.primIndices.size());
      bvh.nodes[to].count = info[from].count;
      leafStack.assign(1, from);
      while (!leafStack.empty()) {
        const BvhNode& sub = full[leafStack.back()];
        leafStack.pop_back();
        if (sub.isLeaf()) {
          bvh.primIndices.push_back(sub.first);
        } else {
          leafStack.push_back(sub.right);
          leafStack.push_back(sub.left);
        }
      }
      continue;
    }
    const uint32_t left = uint32_t(bvh.nodes.size());
    bvh.nodes[to].left = left;
    bvh.nodes[to].right = left + 1;
    bvh.nodes.push_back({full[node.left].bounds});
    bvh.nodes.push_back({full[node.right].bounds});
    stack.push_back({node.right, left + 1});
    stack.push_back({node.left, left});
  }
  return bvh;
}

}  // namespace bvhlab::detail
