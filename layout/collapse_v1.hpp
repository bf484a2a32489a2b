// The step the wide layouts share (bvh4 / bvh8: layout/layout_wide.hpp; cwbvh: layout/layout_cwbvh.hpp):
// any builder's Bvh through v1's packer (which checks the tree, orders it depth-first and writes the
// raw TRIANGLE and ATTRIBUTE streams), v1's nodes read back as a binary tree whose every subtree covers
// one contiguous triangle range, and that tree collapsed to width W (layout/collapse_wide.hpp).
#pragma once
#include <cstdint>
#include <vector>

#include "layout/collapse_wide.hpp"
#include "layout/layout.hpp"

namespace bvhlab {

struct CollapsedV1 {
  PackedBvh v1;                  // v1's packing of the builder's tree (its triangle streams are the raw ones)
  Bvh binary;                    // v1's NODE stream as a Bvh, same order: leaf ranges index v1's TRIANGLE stream
  std::vector<uint32_t> refs;    // leaf references under each binary node (subtreeReferences)
  std::vector<uint32_t> first;   // v1 TRIANGLE-stream index of each binary subtree's first triangle
  uint32_t maxLeaf = 1;          // the largest leaf of the binary tree
  WideTree wide;                 // the SAH-optimal collapse to the width asked for
};

// Merged leaves are capped at the binary tree's largest leaf (the builder's --leaf-size, in effect) and
// at kMaxLeafSize. Throws std::runtime_error as packBvh does.
CollapsedV1 collapseThroughV1(const Bvh& bvh, const TriangleSoup& soup, uint32_t width);

}  // namespace bvhlab
