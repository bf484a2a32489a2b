// Layouts "bvh4" and "bvh8": WIDE BVHs of up to W = 4 / 8 children per node, made from any builder's
// binary tree by the SAH-optimal collapse of Ylitie, Karras & Laine 2017 ("Efficient Incoherent Ray
// Traversal on GPUs Through Compressed Wide BVHs", section 4.1; layout/collapse_wide.hpp). This
// comment is the one place the two layouts are described; the GLSL accessors in
// traversal/layout_wide.glsl (+ layout_wide4.glsl / layout_wide8.glsl for W) and the packer in
// layout/pack_wide.cpp implement them.
//
// Streams: uvec4 texels (RGBA32UI) as v1 (layout/layout.hpp), same storage kinds (tbo, tex2d).
// TRIANGLE and ATTRIBUTE streams: exactly v1's (raw vertices, depth-first leaf order), read with v1's
// accessors (traversal/layout.glsl). Since v1 orders triangles depth-first, the triangles of ANY
// binary subtree are one contiguous range of the TRIANGLE stream: a wide leaf made by collapsing a
// binary subtree is that range (sbvh's duplicate references included, as often as the binary tree
// has them).
//
// NODE stream: SLOTS of 2 texels. A slot describes one child (or the root):
//   texel 0 = (bmin.x, bmin.y, bmin.z, link)     bmin/bmax: float bits of the child's box
//   texel 1 = (bmax.x, bmax.y, bmax.z, count)
//   count <  kWideInner: a leaf of `count` triangles, TRIANGLE stream link .. link + count - 1
//                        (1 .. kMaxLeafSize; never 0).
//   count >= kWideInner: an inner node whose RECORD starts at NODE texel `link` and holds
//                        k = count - kWideInner child slots (2 <= k <= W), back to back.
// Texels 0-1 are the ROOT SLOT (the whole tree's box; a leaf when the binary tree is one leaf, then
// no record exists). Records follow in depth-first pre-order of the wide tree, each 2k texels, so a
// record only stores the children it has (no empty slots, no header: the parent's slot says k).
// Links are NODE texel offsets (32 bits), limits as v1's since the packer goes through v1.
//
// Why this array-of-slots form and not structure-of-arrays (min.x of 4 children in one texel):
// llvmpipe runs a shader 8 invocations wide, one invocation per SIMD lane, so a vec4 of one
// invocation is 4 scalar operations either way; what costs is the texel fetch (a gather across lanes).
// Slots let a node fetch exactly 2k texels for its k children (SoA: 6 texels of boxes + links and
// counts whatever k, per group of 4), and keep the box test each kernel already has (intersectAabb).
//
// Size: 32 bytes per wide child + 32 for the root slot, i.e. 32 (N + 1) for N nodes of the wide tree
// other than the root: fewer than v1's 32 (2L - 1) whenever the collapse merged anything.
// PackedBvh::depth is the WIDE tree's depth (root alone = 1; a leaf child of the root = 2); the
// kernels' stack bound max(1, (W - 1)(depth - 1)) is derived in traversal/kernel_wide_stack.glsl and
// returned by stackSizeFor(const PackedBvh&) (traversal/kernels.hpp).
#pragma once
#include <cstdint>

#include <glm/glm.hpp>

#include "layout/layout.hpp"

namespace bvhlab {

constexpr const char* kLayoutBvh4 = "bvh4";
constexpr const char* kLayoutBvh8 = "bvh8";
constexpr uint32_t kWideSlotTexels = 2;
constexpr uint32_t kWideInner = 0x80000000u;

// 4 for "bvh4", 8 for "bvh8", 0 for any other layout name.
uint32_t wideWidth(const std::string& layout);

// Any builder's Bvh (duplicated references and a root that is a leaf included) -> the streams above,
// collapsed to width 4 or 8. Throws std::runtime_error as packBvh does.
PackedBvh packBvh4(const Bvh& bvh, const TriangleSoup& soup);
PackedBvh packBvh8(const Bvh& bvh, const TriangleSoup& soup);
PackedBvh packWide(const Bvh& bvh, const TriangleSoup& soup, uint32_t width);

// Decoded slot, for tests and tools (the kernel mirrors decode with traversal/layout_wide.hpp).
struct WideSlot {
  glm::vec3 bmin, bmax;
  uint32_t link, count;
  bool isInner() const { return count >= kWideInner; }
  uint32_t children() const { return isInner() ? count - kWideInner : 0u; }
};
// The slot at NODE texel `texel` (0 = the root slot). Throws std::invalid_argument for a tree of
// another layout, std::out_of_range past the stream.
WideSlot unpackWideSlot(const PackedBvh& packed, uint32_t texel);

}  // namespace bvhlab
