// Two-level trees (the DXR/Vulkan acceleration-structure model): a top-level tree (TLAS) over
// INSTANCES, each an object-space tree (BLAS) of one mesh placed in the world by an affine transform.
// This comment is the one place the streams are described; traversal/two_level.glsl walks them (C++
// mirror traversal/two_level.hpp); docs/layouts.md, "Two-level trees", says why they look so.
//
// Node layouts: v1 and bvh2-cb (layout/layout.hpp, layout/layout_bvh2cb.hpp); every BLAS and the TLAS
// are packed by that layout's own packer and written in its node format, so the layout's kernels walk
// both (with a root offset). Triangle format: raw (the BLAS packers' output).
//
// NODE stream, in texels (uvec4), four regions one after the other:
//   HEADER    texels 0..7: texel 0 = (TLAS root node, instance count, BLAS count, kTwoLevelVersion),
//             texels 1..7 zero.
//   BLASES    each BLAS's node stream as its packer wrote it, rebased: child and escape links
//             (v1) and record links (bvh2-cb) plus the node stream's length before it, leaf triangle
//             links plus the BLAS's first triangle in the TRIANGLE stream (kEscapeEnd stays). BLAS b's
//             root node is blasRoot[b] (node units: 2 texels for v1, 4 for bvh2-cb).
//   INSTANCES padded to a multiple of kInstanceTexels, then one RECORD of kInstanceTexels = 8 texels
//             per TLAS leaf reference, in TLAS leaf order. Record r lies at texels 8r .. 8r + 7 (the
//             header is record 0's place, so records start at r >= 1):
//               texel 8r+0..2 = world->object rows: (row i of L^-1, row i of -L^-1 T)  (float bits)
//               texel 8r+3..5 = object->world rows: (row i of L, T_i)
//               texel 8r+6    = (T.x, T.y, T.z, BLAS root node)
//               texel 8r+7    = (instance id, BLAS id, BLAS first triangle, material)
//             where object->world = [L | T]. A kernel's walk reads texels 0..2 and 6 (64 bytes): the ray
//             goes into object space as o' = L^-1 (o - T), d' = L^-1 d, translation first (its error
//             stays that of |o - T|, not of |o|: docs/layouts.md), d' not renormalised, so t is world t.
//   TLAS      the TLAS's node stream, rebased as a BLAS's, its leaf "triangle" links being record
//             indices. Root = header.x.
// The HEADER and BLASES regions do not change when instances move: repackTopLevel rewrites only
// the texels from dynamicTexelBegin on (and the header, whose TLAS root moves only when the instance
// count does).
//
// TRIANGLE / ATTRIBUTE streams: the BLASes' raw streams concatenated in BLAS order; triangle ids
// (texel .w) stay each mesh's own (the BLAS soup's triangle index), so a hit is named by (instance
// id, triangle id). A BLAS shared by instances of one mesh with different materials stores one of
// them in its triangles: shading takes the instance's (record texel 7.w; as DXR's instance data).
//
// PackedBvh::depth = the larger of the TLAS's and the deepest BLAS's depths, so stackSizeFor(streams)
// sizes the one BVH_STACK_SIZE both walks use.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"
#include "layout/layout.hpp"

namespace bvhlab {

constexpr uint32_t kTwoLevelVersion = 1;
constexpr uint32_t kInstanceTexels = 8;
constexpr uint32_t kTwoLevelHeaderTexels = kInstanceTexels;
// Texels of an instance record one instance test reads (world->object rows and texel 6).
constexpr uint32_t kInstanceTestTexels = 4;

// An instance: BLAS `blas` placed by objectToWorld, a 3x4 affine map (GLM: 4 columns of 3 rows; the
// 4th column is the translation T). Its inverse is computed by the packer, in double.
struct Instance {
  uint32_t blas = 0;
  glm::mat4x3 objectToWorld{1.0f};
  uint32_t material = 0;  // the scene material its triangles are shaded with (record texel 7.w)
};

// The inverse of a 3x4 affine map, computed in double and rounded once. Throws std::invalid_argument
// when the linear part is singular or not finite.
glm::mat4x3 inverseAffine(const glm::mat4x3& m);

// The world box of a BLAS root box under `objectToWorld`: its 8 corners transformed in double, the
// bounds rounded outwards to float, so the float box contains the exact image.
Aabb transformBox(const Aabb& objectBox, const glm::mat4x3& objectToWorld);

struct PackedTwoLevel {
  PackedBvh streams;                     // what the shader reads (layout above); streams.layout = the layout
  uint32_t tlasRoot = 0;                 // = header.x (node units)
  uint32_t tlasDepth = 0, blasDepth = 0;  // the TLAS's depth; the deepest BLAS's
  std::vector<uint32_t> blasRoot;        // per BLAS: its root node (node units)
  std::vector<uint32_t> blasFirstTriangle;  // per BLAS: its first triangle in the TRIANGLE stream
  std::vector<Aabb> blasBox;             // per BLAS: its root box (object space)
  std::vector<uint32_t> recordInstance;  // per record (from the first, in TLAS leaf order): instance id
  size_t dynamicTexelBegin = 0;          // NODE texels from here on are rewritten by repackTopLevel
  Bvh tlas;  // the TLAS as built (its primitives: the instances, by index), for its SAH
  uint32_t firstRecord() const { return uint32_t(dynamicTexelBegin / kInstanceTexels); }
};

// The TLAS's inputs, kept with the caller: which builder and options build it over the world boxes.
struct TopLevelBuild {
  std::string builder = "sah-binned";
  BuildOptions options;  // maxLeafSize: instances per TLAS leaf
};

// BLASes: each one mesh's tree in object space, packed by the layout's packer (layout/layouts.hpp),
// all in the same layout, raw triangle format. Instances name them by index. Throws
// std::invalid_argument for an unsupported layout or triangle format, mixed layouts, an instance
// naming a BLAS that does not exist, no instances, or a singular transform; std::runtime_error on a
// stream limit (as packBvh).
PackedTwoLevel packTwoLevel(const std::vector<PackedBvh>& blases, const std::vector<Instance>& instances,
                            const TopLevelBuild& top = {});
// The HEADER and BLASES regions alone (no TLAS yet: repackTopLevel adds it); the errors of
// packTwoLevel that concern BLASes. packTwoLevel = packBottomLevel, then repackTopLevel.
PackedTwoLevel packBottomLevel(const std::vector<PackedBvh>& blases);
// A new frame: the instance records and the TLAS rebuilt for `instances` (same BLASes), the
// BLASES region kept as it is. Same errors as packTwoLevel.
void repackTopLevel(PackedTwoLevel& packed, const std::vector<Instance>& instances, const TopLevelBuild& top = {});

// The layouts packTwoLevel accepts ("v1", "bvh2-cb").
bool twoLevelLayoutSupported(const std::string& layout);

}  // namespace bvhlab
