// collapseThroughV1 (layout/collapse_v1.hpp): v1's packing read back as a binary tree, then collapsed.
#include "layout/collapse_v1.hpp"

#include <algorithm>
#include <stdexcept>

namespace bvhlab {

namespace {

// v1's NODE stream as a Bvh in the same (depth-first) order: node i's children are i + 1 and a, a
// leaf's range indexes the TRIANGLE stream.
Bvh binaryFromV1(const PackedBvh& v1) {
  Bvh b;
  const uint32_t count = uint32_t(v1.nodes.size() / kNodeTexels);
  b.nodes.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    const NodeRecord r = unpackNode(v1, i);
    BvhNode& n = b.nodes[i];
    n.bounds = Aabb{r.bmin, r.bmax};
    if (r.isLeaf()) n.first = r.a, n.count = r.count;
    else n.left = i + 1, n.right = r.a;
  }
  return b;
}

}  // namespace

CollapsedV1 collapseThroughV1(const Bvh& bvh, const TriangleSoup& soup, uint32_t width) {
  CollapsedV1 out;
  out.v1 = packBvh(bvh, soup);
  out.binary = binaryFromV1(out.v1);
  out.refs = subtreeReferences(out.binary);
  // First triangle of every subtree; v1's depth-first order makes a subtree's triangles contiguous.
  out.first.resize(out.binary.nodes.size());
  for (uint32_t i = uint32_t(out.binary.nodes.size()); i-- > 0;) {
    const BvhNode& n = out.binary.nodes[i];
    if (n.isLeaf()) {
      out.first[i] = n.first;
      out.maxLeaf = std::max(out.maxLeaf, n.count);
      continue;
    }
    out.first[i] = out.first[n.left];
    if (out.first[n.right] != out.first[n.left] + out.refs[n.left])
      throw std::runtime_error("collapseThroughV1: v1's triangle stream is not in depth-first leaf order");
  }
  // The collapse trades nodes for references only within the leaf size the tree was asked for.
  out.wide = collapseWide(out.binary, width, CostModel{}, std::min(out.maxLeaf, kMaxLeafSize));
  return out;
}

}  // namespace bvhlab
