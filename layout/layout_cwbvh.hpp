// Layout "cwbvh": the COMPRESSED 8-wide node of Ylitie, Karras & Laine 2017 ("Efficient Incoherent Ray
// Traversal on GPUs Through Compressed Wide BVHs", section 3), 80 bytes per node, made from any
// builder's binary tree by the same SAH-optimal collapse as bvh8 (section 4.1; layout/collapse_wide.hpp,
// layout/collapse_v1.hpp). This comment is the one place the layout is described; the packer
// layout/pack_cwbvh.cpp and the GLSL decoder traversal/layout_cwbvh.glsl (C++ mirror
// traversal/layout_cwbvh.hpp) implement it.
//
// Streams: uvec4 texels (RGBA32UI) as v1 (layout/layout.hpp), same storage kinds (tbo, tex2d).
//
// NODE stream: 5 texels (80 bytes) per node of the wide tree, node i at texels 5i .. 5i + 4, node 0 =
// the root. A node holds its k children (1 <= k <= 8) in 8 slots, placed by OCTANT (the paper's section
// 3.2): slot s holds the child that rays of octant s (bit a of s set: the direction's component a is
// negative, a = x, y, z) should meet first, chosen by cwbvhAssignSlots below; a kernel that visits the
// slots in the order s XOR octant (kernel_cwbvh_groups.glsl) walks the children roughly near to far.
// The 8 - k other slots are EMPTY: meta 0, q bytes 0 (kernels skip them by their meta).
//   texel 5i+0 = (p.x, p.y, p.z, ex | ey << 8 | ez << 16 | k << 24)
//       p: float bits of the node's box min, the origin of the quantisation grid. e: biased exponent
//       per axis, 1..254: the grid step is scale = 2^(e - 127) = uintBitsToFloat(e << 23), a normal
//       power of two.
//   texel 5i+1 = (childBase, triBase, meta[0..3], meta[4..7])   meta byte c in bits 8 (c % 4) of its uint
//       meta[c] = kCwbvhMetaInner (0x80): child c is an inner node. Its node index is childBase + r,
//                 r = its rank among the node's inner children (the inner children of a node are
//                 consecutive nodes; childBase is 0, unused, when the node has none).
//       meta[c] = 1..127: child c is a leaf of that many triangles. The leaf children's triangles are
//                 consecutive in slot order from TRIANGLE-stream index triBase: leaf child c starts at
//                 triBase + the counts of the leaf children in slots below c. (0 is never stored for a
//                 child; an empty slot holds 0.) A leaf of more than kCwbvhMaxLeaf triangles is refused by
//                 the packer (build with a smaller --leaf-size).
//   texels 5i+2 .. 5i+4 = 48 quantised bytes, six arrays of 8 (one byte a slot): qlo.x, qlo.y, qlo.z,
//       qhi.x, qhi.y, qhi.z, in that order; byte j of the 48 in uint j / 4 of the three texels, bits
//       8 (j % 4) (little-endian), so array a of child c is byte 8a + c. Unused slots hold 0.
//   Child c's box: bmin = p + vec3(qlo) * scale, bmax = p + vec3(qhi) * scale, per axis. An 8-bit
//   integer times a power of two is exact (no subnormal: scale >= 2^-126), so the one rounding is the
//   addition, with or without a fused multiply-add: GLSL and C++ decode the same bits.
//   CONSERVATIVE: the packer makes every decoded child box contain the child's exact (float) box:
//   e is the smallest exponent with fl(p + 255 scale) >= the node box max, qlo the largest q with
//   fl(p + q scale) <= the child min, qhi the smallest q with fl(p + q scale) >= the child max (all
//   evaluated as the decoder does), checked before it is written. A ray can only test a looser box,
//   never miss a triangle because of the quantisation.
// Node order: a node's inner children get consecutive indices when the node is written, then the
// packer walks depth-first (first child first), so a subtree's nodes lie close together.
// The ROOT NODE's own box is not stored: the kernel tests the root's grid, p .. p + 255 scale, which
// contains every child box (traversal/kernel_cwbvh_stack.glsl says why and what it measured). A binary tree that is one leaf packs as one node with one leaf child.
//
// TRIANGLE and ATTRIBUTE streams: the raw format (layout/layout.hpp), v1's triangles RE-ORDERED so each
// node's leaf triangles are consecutive (node by node, in the packer's depth-first node order); sbvh's
// duplicate references are copied as often as the binary tree has them. The triangle formats
// (layout/triangle_formats.hpp) rewrite the raw streams afterwards keeping the order, so every format
// works with cwbvh.
//
// Size: 80 bytes per node of the wide tree (paper: 80 bytes for 8 children, 10 per child, where bvh8's
// slots take 32 per child). Node indices and triBase use 32 bits; v1's limits apply anyway (the packer
// starts from v1). PackedBvh::depth is the wide tree's depth counting leaf children (root node = 1, its
// children 2), so the kernel's stack bound is (W - 1)(D - 1) with W = 8 (traversal/kernel_cwbvh_stack.glsl
// derives it; stackSizeFor(const PackedBvh&) returns it).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "layout/layout.hpp"

namespace bvhlab {

constexpr const char* kLayoutCwbvh = "cwbvh";
constexpr uint32_t kCwbvhNodeTexels = 5;
constexpr uint32_t kCwbvhWidth = 8;
constexpr uint32_t kCwbvhMetaInner = 0x80u;
constexpr uint32_t kCwbvhMaxLeaf = 127;  // the largest leaf count a meta byte holds below kCwbvhMetaInner

// Any builder's Bvh (duplicated references and a root that is a leaf included) -> the streams above.
// Throws std::runtime_error as packBvh does, and for a leaf of more than kCwbvhMaxLeaf triangles.
PackedBvh packCwbvh(const Bvh& bvh, const TriangleSoup& soup);

// The slot assignment (Ylitie, Karras & Laine 2017, section 3.2): the cost of child c in slot s is
// dot(centroid_c - parentCentroid, d_s), d_s octant s's diagonal direction (component a = -1 where bit
// a of s is set, else +1), low when rays of octant s meet c early; pairs are taken greedily, cheapest
// first (ties: lower child, then lower slot). Returns, per slot, the child's index in `centroids` or -1
// for an empty slot. Throws std::invalid_argument for 0 or more than 8 centroids.
std::array<int, 8> cwbvhAssignSlots(const std::vector<glm::vec3>& centroids, glm::vec3 parentCentroid);

// The decoding of one coordinate: p + q * scale in float (the decoder's arithmetic, also the packer's).
inline float cwbvhDecode(float p, uint32_t q, float scale) { return p + float(q) * scale; }

// A decoded node, for tests and tools (the kernel mirror decodes with traversal/layout_cwbvh.hpp).
struct CwbvhNode {
  glm::vec3 origin, scale;           // p and 2^(e - 127) per axis
  glm::uvec3 exponent;               // e per axis
  uint32_t children = 0;             // k (the occupied slots: meta != 0)
  uint32_t childBase = 0, triBase = 0;
  std::array<uint32_t, 8> meta{};    // kCwbvhMetaInner or a leaf's triangle count; 0 for an empty slot
  std::array<glm::vec3, 8> bmin{}, bmax{};  // decoded child boxes (empty slots: p)
  std::array<glm::uvec3, 8> qlo{}, qhi{};
  bool isInner(uint32_t c) const { return meta[c] == kCwbvhMetaInner; }
  // An inner child's node index, or a leaf child's first triangle (TRIANGLE-stream index).
  uint32_t link(uint32_t c) const;
};
// Node `index` (0 = the root). Throws std::invalid_argument for a tree of another layout,
// std::out_of_range past the stream.
CwbvhNode unpackCwbvhNode(const PackedBvh& packed, uint32_t index);
inline uint32_t cwbvhNodeCount(const PackedBvh& packed) { return uint32_t(packed.nodes.size() / kCwbvhNodeTexels); }

}  // namespace bvhlab
