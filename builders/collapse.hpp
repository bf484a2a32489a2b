// The SAH leaf collapse that the bottom-up builders (lbvh, ploc) share: they build a binary tree
// down to single primitives, then every subtree of at most maxLeafSize primitives whose SAH cost as
// one leaf (Ci * count * area) is no higher than as a subtree becomes one leaf.
//
// The input tree (`full`): root at 0, every child at a larger index than its parent, every box set,
// every leaf holding one primitive (count 1, first = the primitive's input id). The output is
// emitted depth-first (left child first, a node's children next to each other, in the order a
// sequential depth-first walk appends them), and primIndices lists the primitives in leaf order.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "builders/build_util.hpp"
#include "builders/bvh.hpp"

namespace bvhlab::detail {

struct CollapseInfo {
  // Where emitCollapsed puts the node's descendants: the first output slot they take (kInside when
  // the node becomes one leaf or lies below one) and its first primitive's position in primIndices.
  struct Place {
    uint32_t base, prim;
  };
  static constexpr uint32_t kInside = ~0u;
  union {
    double cost;  // SAH cost of the subtree as it will be emitted, in unnormalised areas
    Place place;  // emitCollapsed's, over the cost once the costs are all known (no array of its own)
  };
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
// The full tree's 2n - 1 nodes (n = infoAt(0).count primitives) are indices 0 .. 2n - 2. The
// entries' costs are overwritten (CollapseInfo::place).
//
// Depth-first emission needs no depth-first walk: where a node lands follows from its parent's place
// and its left sibling's size. An emitted inner node's descendants take the 2 * inner slots from its
// `base`, its children first (base, base + 1), then the left child's descendants, then the right's;
// primitives likewise, the left child's count first. So one pass in index order (parents come before
// their children) writes every emitted node's two children and hands them their places. It reads
// the full tree in its own order, and the children it looks up do not depend on each other, so their
// cache misses overlap; a depth-first walk chases one pointer after another through a tree laid out
// in creation order (20% of a one-thread PLOC build of the bunny, perf). The places live in the
// entries' dead cost fields: a fresh array for them costs a page fault per 4 KiB on every build.
// One sequential pass for any thread count: the output does not depend on it.
template <class NodeAt, class InfoAt>
Bvh emitCollapsed(NodeAt nodeAt, InfoAt infoAt) {
  constexpr uint32_t kInside = CollapseInfo::kInside;
  Bvh bvh;
  CollapseInfo& all = infoAt(0);
  const size_t nodeCount = 1 + 2 * size_t(all.inner), fullCount = 2 * size_t(all.count) - 1;
  bvh.nodes.reserve(nodeCount);
  adviseHugePages(bvh.nodes.data(), nodeCount * sizeof(BvhNode));  // before the first touch (as buildTopDown)
  bvh.nodes.resize(nodeCount);
  bvh.primIndices.resize(all.count);

  // Writes the output node at `slot` for a full-tree node with entry `info` whose descendants start
  // at `base` and whose primitives at `prim`, and leaves it its place.
  auto emit = [&bvh](uint32_t slot, const Aabb& bounds, CollapseInfo& info, uint32_t base, uint32_t prim) {
    BvhNode& out = bvh.nodes[slot];
    out.bounds = bounds;
    if (info.collapse()) {
      out.first = prim, out.count = info.count;
      info.place = {kInside, prim};
    } else {
      out.left = base, out.right = base + 1;
      info.place = {base, prim};
    }
  };
  emit(0, nodeAt(0).bounds, all, 1, 0);
  // The children of node i + kAhead are fetched while node i is written (PLOC, one thread: 0.94-0.95x
  // with 16, 1-2% less again with 48, level with 128; lbvh, whose tree is nearly in depth-first order
  // already, 1.0-1.02x).
  constexpr size_t kAhead = 48;
  for (size_t i = 0; i < fullCount; ++i) {
    if (i + kAhead < fullCount) {
      const BvhNode& ahead = nodeAt(uint32_t(i + kAhead));
      if (!ahead.isLeaf()) {
        __builtin_prefetch(&nodeAt(ahead.left), 1), __builtin_prefetch(&infoAt(ahead.left), 1);
        __builtin_prefetch(&nodeAt(ahead.right), 1), __builtin_prefetch(&infoAt(ahead.right), 1);
      }
    }
    const BvhNode& node = nodeAt(uint32_t(i));
    const CollapseInfo::Place p = infoAt(uint32_t(i)).place;
    if (node.isLeaf()) {  // a full-tree leaf holds one primitive
      bvh.primIndices[p.prim] = node.first;
      continue;
    }
    CollapseInfo& left = infoAt(node.left);
    CollapseInfo& right = infoAt(node.right);
    const uint32_t leftCount = left.count, leftInner = left.inner;
    if (p.base == kInside) {
      left.place = {kInside, p.prim};
      right.place = {kInside, p.prim + leftCount};
      continue;
    }
    emit(p.base, nodeAt(node.left).bounds, left, p.base + 2, p.prim);
    emit(p.base + 1, nodeAt(node.right).bounds, right, p.base + 2 + 2 * leftInner, p.prim + leftCount);
  }
  return bvh;
}

// The whole collapse for a tree whose boxes are all set (a bottom-up pass, then the emission).
inline Bvh collapseLeavesBySah(const std::vector<BvhNode>& full, const BuildOptions& options) {
  ScratchVector<CollapseInfo> info(full.size());
  for (size_t i = full.size(); i-- > 0;) {  // children before parents
    const BvhNode& node = full[i];
    info[i] = node.isLeaf() ? collapseLeafInfo(node, options)
                            : collapseInnerInfo(node, info[node.left], info[node.right], options);
  }
  return emitCollapsed([&](uint32_t i) -> const BvhNode& { return full[i]; },
                       [&](uint32_t i) -> CollapseInfo& { return info[i]; });
}

}  // namespace bvhlab::detail
