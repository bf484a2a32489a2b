// The SAH leaf collapse that the bottom-up builders (lbvh, ploc) share: they build a binary tree
// down to single primitives, then every subtree of at most maxLeafSize primitives whose SAH cost as
// one leaf (Ci * count * area) is no higher than as a subtree becomes one leaf.
//
// The input tree (`full`): root at 0, every child at a larger index than its parent, every box set,
// every leaf holding one primitive (count 1, first = the primitive's input id). The output is
// emitted depth-first (left child first, a node's children next to each other, in the order a
// sequential depth-first walk appends them), and primIndices lists the primitives in leaf order.
// The emission runs subtrees as parallel jobs, each writing its precomputed slots: the output is the
// same for any thread count.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "builders/build_util.hpp"
#include "builders/bvh.hpp"

namespace bvhlab::detail {

struct CollapseInfo {
  double cost;     // SAH cost of the subtree as it will be emitted, in unnormalised areas
  uint32_t count;  // primitives below
  uint32_t inner;  // inner nodes it will emit: 0 exactly when it becomes one leaf
  bool collapse() const { return inner == 0; }
};

// A node's entry from its children's (builders that make nodes bottom-up call this as they go).
inline CollapseInfo collapseLeafInfo(const BvhNode& leaf, const BuildOptions& options) {
  return {options.cost.intersectionCost * double(leaf.bounds.halfArea()) * leaf.count, leaf.count, 0};
}
inline CollapseInfo collapseInnerInfo(const BvhNode& node, const CollapseInfo& l, const CollapseInfo& r,
                                      const BuildOptions& options) {
  const CostModel& c = options.cost;
  const double area = node.bounds.halfArea();
  const uint32_t count = l.count + r.count;
  const double asLeaf = c.intersectionCost * area * count, asTree = c.traversalCost * area + l.cost + r.cost;
  const bool collapse = count <= options.maxLeafSize && asLeaf <= asTree;
  return {collapse ? asLeaf : asTree, count, collapse ? 0 : 1 + l.inner + r.inner};
}

// The collapsed tree from the full tree's nodes and their CollapseInfo, given by index (nodeAt(i),
// infoAt(i); a builder may keep both in one record, so that a node's one cache line serves both).
template <class NodeAt, class InfoAt>
Bvh emitCollapsed(NodeAt nodeAt, InfoAt infoAt, unsigned threads) {
  Bvh bvh;
  const size_t nodeCount = 1 + 2 * size_t(infoAt(0).inner);
  bvh.nodes.reserve(nodeCount);
  adviseHugePages(bvh.nodes.data(), nodeCount * sizeof(BvhNode));  // before the first touch (as buildTopDown)
  bvh.nodes.resize(nodeCount);
  bvh.primIndices.resize(infoAt(0).count);
  bvh.nodes[0] = {nodeAt(0).bounds};

  // A walk from `from` (written at `to`) that appends children at `next` and primitives at `prim`.
  struct Walk {
    uint32_t from, to, next, prim;
  };
  // One depth-first walk; with `split`, nodes of at most `split` primitives (not collapsed) are not
  // entered but returned, with the counters they will start from, so they can run as jobs.
  auto walk = [&](Walk w, uint32_t split, std::vector<Walk>* jobs) {
    std::vector<std::pair<uint32_t, uint32_t>> stack{{w.from, w.to}};  // (index in full, index in bvh)
    std::vector<uint32_t> leafStack;
    while (!stack.empty()) {
      auto [from, to] = stack.back();
      stack.pop_back();
      const CollapseInfo& node = infoAt(from);
      if (node.collapse()) {  // its primitives, left to right
        bvh.nodes[to].first = w.prim;
        bvh.nodes[to].count = node.count;
        leafStack.assign(1, from);
        while (!leafStack.empty()) {
          const BvhNode& sub = nodeAt(leafStack.back());
          leafStack.pop_back();
          if (sub.isLeaf()) {
            bvh.primIndices[w.prim++] = sub.first;
          } else {
            leafStack.push_back(sub.right);
            leafStack.push_back(sub.left);
          }
        }
        continue;
      }
      if (jobs && node.count <= split && from != w.from) {
        jobs->push_back({from, to, w.next, w.prim});
        w.next += 2 * node.inner;
        w.prim += node.count;
        continue;
      }
      const BvhNode& source = nodeAt(from);
      const uint32_t left = w.next;
      w.next += 2;
      bvh.nodes[to].left = left;
      bvh.nodes[to].right = left + 1;
      bvh.nodes[left] = {nodeAt(source.left).bounds};
      bvh.nodes[left + 1] = {nodeAt(source.right).bounds};
      stack.push_back({source.right, left + 1});
      stack.push_back({source.left, left});
    }
  };
  const Walk root{0, 0, 1, 0};
  const uint32_t n = infoAt(0).count;
  if (n < kParallelMinInput) {  // as buildTopDown: thresholds from the input size only
    walk(root, 0, nullptr);
    return bvh;
  }
  std::vector<Walk> jobs;
  walk(root, n / kSubtreeFraction, &jobs);
  runJobs(jobs.size(), threads, [&](size_t k) { walk(jobs[k], 0, nullptr); });
  return bvh;
}

// The whole collapse for a tree whose boxes are all set (a bottom-up pass, then the emission).
inline Bvh collapseLeavesBySah(const std::vector<BvhNode>& full, const BuildOptions& options, unsigned threads = 1) {
  std::vector<CollapseInfo> info(full.size());
  for (size_t i = full.size(); i-- > 0;) {  // children before parents
    const BvhNode& node = full[i];
    info[i] = node.isLeaf() ? collapseLeafInfo(node, options)
                            : collapseInnerInfo(node, info[node.left], info[node.right], options);
  }
  return emitCollapsed([&](uint32_t i) -> const BvhNode& { return full[i]; },
                       [&](uint32_t i) -> const CollapseInfo& { return info[i]; }, threads);
}

}  // namespace bvhlab::detail
