// THE triangle formats: the second layout axis, orthogonal to the node layout (layout/layouts.hpp).
// This comment is the one place they are described; the packers are layout/pack_triangles*.cpp, the
// GLSL accessors traversal/triangles_<format>.glsl (C++ mirrors traversal/triangles_<format>.hpp).
//
// A node packer (v1, bvh2-cb, ...) writes the `raw` streams in leaf order; packTriangles then rewrites
// them in the chosen format, keeping the order. So the TRIANGLE-stream position j of a triangle is
// the same in every format, and it is the triangle id the kernels use (leaf ranges, MeshHit::tri):
// node layouts need no change. Every accessor module defines
//   bool testTriangle(Ray, int tri, float tMin, float tMax, out float t, out vec2 bary)  fetch + test
//   void loadTriangle(int tri, out vec3 v0, out vec3 v1, out vec3 v2)                    vertices
//   void loadTriangleIds(int tri, out uint primitive, out uint material, out uint mesh)
//   void loadAttributes(int tri, vec2 bary, out vec3 normal, out vec2 uv)  (normal not normalised)
// bary = (u, v) weighs v1 and v2, v0 weighs 1 - u - v, in every format.
//
// raw (default; layout/layout.hpp describes its streams): TRIANGLE 3 texels (v0, v1, v2 as float bits
//   + the three ids), ATTRIBUTE 4 texels (three normals, three uvs as floats). 112 bytes a triangle.
//   testTriangle = loadTriangle + the selected intersectTriangle (Moller-Trumbore or watertight).
//
// precomputed: what a Moller-Trumbore test can do without, stored (the arrangement with a stored
//   geometric normal Embree's Moller-Trumbore intersector uses; Moller & Trumbore 1997 solve the same
//   3x3 system by Cramer's rule: with s = origin - v0, q = cross(s, dir), det = -dot(dir, n):
//   u = dot(e2, q) / det, v = -dot(e1, q) / det, t = dot(s, n) / det).
//   TRIANGLE 4 texels:  4j+0 = (v0, primitive)   4j+1 = (e1 = v1 - v0, material)
//                       4j+2 = (e2 = v2 - v0, mesh)   4j+3 = (n = cross(e1, e2), 0)   (float bits)
//   ATTRIBUTE as raw. 128 bytes a triangle: 16 more than raw, for one cross product and two edge
//   subtractions less per test. loadTriangle gives v0, v0 + e1, v0 + e2 (rounded: not the input
//   vertices), so the watertight test, which needs a vertex shared by two triangles to be the same bits
//   in both, is refused with it (checkTriangleFormat).
//
// indexed: shared vertices, the memory-lean format.
//   VERTEX stream, 1 texel per vertex: (x, y, z as float bits, normal). The positions are the input's,
//     exact. normal = packSnorm2x16 of the octahedral encoding (Cigolle, Donow, Evangelakos, Mara,
//     McGuire & Meyer 2014, "A Survey of Efficient Representations for Independent Unit Vectors",
//     JCGT 3(2), "oct32"), rounded to nearest; decoded angle error <= kOctNormalMaxError. The value
//     kFlatNormal (0x80008000: -32768 twice, which packSnorm2x16 never produces) marks a corner whose
//     normal is the triangle's geometric normal (what gatherTriangles gives a mesh without normals):
//     the decoder computes normalize(cross(v1 - v0, v2 - v0)) there, so such vertices weld.
//   TRIANGLE stream, 1 texel per triangle: (i0, i1, i2, primitive), vertex indices into VERTEX.
//   ATTRIBUTE stream, 2 uints per vertex, 2 vertices per texel: vertex k in texel k / 2, lanes
//     2 (k % 2) and 2 (k % 2) + 1 = (packHalf2x16(uv), material | mesh << 16). uv as half floats: 11
//     significant bits, so an error <= 2^-12 for |uv| < 1 (a quarter texel of a 1024-texel texture);
//     tiled uvs far from 0 lose more (2^-12 |uv|). The ids of a triangle are its vertex i0's.
//   Welding: per mesh, two corners of the soup become one vertex when their position, normal (or
//   both flat) and uv are the same bits (exact equality, no tolerance: nothing that was apart in the
//   input is merged). Vertices are numbered in first-use order along the TRIANGLE stream, so the
//   vertices of a leaf lie close together. 16 + 24 V / T bytes a triangle (V / T ~ 0.5 on a closed
//   smooth mesh: 28).
//   Limits: 2^28 - 1 vertices, 65,535 meshes and materials (refused beyond, naming the count).
//
// Which triangle tests a format works with: raw and indexed with both (the vertices are exact);
// precomputed with Moller-Trumbore only (`--robust fast|box|ulp|box+ulp`).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "layout/layout.hpp"
#include "traversal/robustness.hpp"

namespace bvhlab {

enum class TriangleFormat : uint8_t { Raw, Precomputed, Indexed };

struct TriangleFormatInfo {
  TriangleFormat format;
  std::string name;         // "raw", "precomputed", "indexed"
  std::string description;  // one line for `bvhlab layouts`
  std::string glslModule;   // "triangles_raw.glsl", ...
  bool watertight;          // works with the watertight triangle test
};

constexpr const char* kDefaultTriangleFormat = "raw";
constexpr uint32_t kPrecomputedTriangleTexels = 4;
constexpr uint32_t kIndexedTriangleTexels = 1, kVertexTexels = 1;
constexpr uint32_t kFlatNormal = 0x80008000u;
constexpr uint32_t kMaxIndexedIds = 0xFFFFu;  // meshes and materials an indexed vertex can name
// Bound on the angle (radians) between a unit normal and its oct32 decoding: a coordinate rounded to
// the nearest of 32767 steps moves by <= 0.5 / 32767; through the octahedron's fold and the
// normalisation (the octahedron point has length >= 1 / sqrt(3)) that is <= sqrt(3) * sqrt(6) * 0.5 /
// 32767 = 6.5e-5, plus float rounding of the decode, well below 1e-6: 7e-5 rad (0.004 degrees).
constexpr float kOctNormalMaxError = 7e-5f;

const std::vector<TriangleFormatInfo>& triangleFormats();
// Throws std::invalid_argument naming the valid formats when `name` is unknown.
const TriangleFormatInfo& findTriangleFormat(const std::string& name);
// Throws std::invalid_argument, before anything is built, when the format cannot run the robustness
// variant's triangle test (precomputed with a watertight test), naming the variants it works with.
void checkTriangleFormat(const std::string& format, Robustness robust);

// Rewrites packed's raw TRIANGLE and ATTRIBUTE streams (as a node packer leaves them) in `format`,
// keeping the triangle order; sets packed.triangleFormat. Throws std::runtime_error on a limit.
void packTriangles(PackedBvh& packed, const TriangleSoup& soup, const std::string& format);

// The octahedral unit-vector code of the indexed format (exposed for tests).
uint32_t encodeOctNormal(glm::vec3 n);
glm::vec3 decodeOctNormal(uint32_t code);  // = the GLSL decoder's arithmetic

// The indexed packer (layout/pack_triangles_indexed.cpp); `order` = the soup triangle of each
// TRIANGLE-stream position.
void packIndexedTriangles(PackedBvh& packed, const TriangleSoup& soup, const std::vector<uint32_t>& order);

}  // namespace bvhlab
