// Layout "bvh2-cb": binary BVH, both CHILD BOXES stored in the parent (the node of Aila & Laine 2009,
// "Understanding the Efficiency of Ray Traversal on GPUs"). This comment is the one place it is
// described; the GLSL accessors in traversal/layout_bvh2cb.glsl and the packer in
// layout/pack_bvh2cb.cpp implement it. One node fetch gives a kernel both children's boxes, so it
// can test and order them before touching either child; leaves have no record of their own.
//
// Streams: uvec4 texels (RGBA32UI) as v1 (layout/layout.hpp), same storage kinds (tbo, tex2d).
// TRIANGLE and ATTRIBUTE streams: exactly v1's (raw vertices, leaf order), so the triangle tests,
// the ids and the shading read them with v1's accessors (traversal/layout.glsl).
//
// NODE stream: one RECORD of 4 texels (64 bytes) per INNER node of the binary tree, depth-first
// pre-order of the inner nodes, root record = 0. A record holds its two children A (left) and B
// (right), each as a SLOT:
//   texel 4i+0 = (A.bmin.x, A.bmin.y, A.bmin.z, A.link)    bmin/bmax: float bits of the child's box
//   texel 4i+1 = (A.bmax.x, A.bmax.y, A.bmax.z, A.count)
//   texel 4i+2 = (B.bmin.x, B.bmin.y, B.bmin.z, B.link)
//   texel 4i+3 = (B.bmax.x, B.bmax.y, B.bmax.z, B.count)
//   count == kBvh2cbInner (0xFFFFFFFF): the child is an inner node; link = its record index.
//   count  < kBvh2cbInner: the child is a leaf of `count` triangles (at most kMaxLeafSize), TRIANGLE
//                          stream triangles link .. link + count - 1.
//   count == 0 (a leaf of no triangles, an EMPTY slot) occurs only when the whole tree is one leaf:
//   then the root record holds that leaf in A and an empty slot in B (B's box = A's box, link = A's).
//   When child A is inner its record is i + 1 (pre-order); B's record is stored in its link.
// The root's own box is not stored: a ray that misses the scene tests the root's two child boxes.
// No escape links (no stackless kernel for this layout). Record indices and triangle links use all
// 32 bits; v1's limits (2^28 - 1 nodes and triangles) apply anyway, since the packer starts from v1.
// Size: 64 bytes per inner node, i.e. 64 (L - 1) for L leaves, where v1 stores 32 (2L - 1): the same
// node bytes, less 32.
// PackedBvh::depth is the binary tree's depth (root alone = 1), as v1's: kernels size stacks from it.
#pragma once
#include <cstdint>

#include <glm/glm.hpp>

#include "layout/layout.hpp"

namespace bvhlab {

constexpr const char* kLayoutBvh2cb = "bvh2-cb";
constexpr uint32_t kBvh2cbRecordTexels = 4;
constexpr uint32_t kBvh2cbInner = 0xFFFFFFFFu;

// Any builder's Bvh (including trees whose leaves reference a primitive more than once, and a root
// that is a leaf) -> the streams above. Throws std::runtime_error as packBvh does.
PackedBvh packBvh2cb(const Bvh& bvh, const TriangleSoup& soup);

// Decoded record, for tests and tools (the kernel mirrors decode with traversal/layout_bvh2cb.hpp).
struct Bvh2cbSlot {
  glm::vec3 bmin, bmax;
  uint32_t link, count;
  bool isInner() const { return count == kBvh2cbInner; }
};
struct Bvh2cbRecord {
  Bvh2cbSlot child[2];  // A, B
};
// Throws std::out_of_range past the last record, std::invalid_argument for a tree of another layout.
Bvh2cbRecord unpackBvh2cbRecord(const PackedBvh& packed, uint32_t index);
uint32_t bvh2cbRecordCount(const PackedBvh& packed);

}  // namespace bvhlab
