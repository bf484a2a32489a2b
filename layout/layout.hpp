// THE texture layout (version 1, registered as layout "v1", the default). This comment is the one
// place it is described; the GLSL accessors in traversal/layout.glsl and the packer in
// layout/pack.cpp implement it. Other layouts have one header each beside it (layout/layout_*.hpp),
// listed in the registry layout/layouts.hpp.
//
// Every stream is an array of uvec4 texels (RGBA32UI: integer texels keep float bits exact;
// floats are stored with floatBitsToUint). Any builder's Bvh packs into the same streams, so any
// traversal kernel runs over any builder's tree.
//
// NODE stream: 2 texels per node, depth-first order, first child adjacent (child A of node i is
// node i + 1), root = node 0.
//   texel 2i+0 = (bmin.x, bmin.y, bmin.z, A)      bmin/bmax: float bits of the node's box
//   texel 2i+1 = (bmax.x, bmax.y, bmax.z, B)
//   A bits 0..27 : inner -> index of the second child; leaf -> first triangle (TRIANGLE stream index)
//   B bits 0..27 : escape index: the node a depth-first walk visits after this node's subtree
//                  (kEscapeEnd = 0x0FFFFFFF: the walk is over). Stackless kernels follow it on a miss.
//   count = (A >> 28) | ((B >> 28) << 4)   8 bits; 0 marks an inner node, 1..255 a leaf.
//   So at most 2^28 - 1 nodes and triangles, and leaves of at most 255 triangles.
//
// TRIANGLE and ATTRIBUTE streams below are the `raw` triangle format, what every node packer writes;
// the other triangle formats (precomputed, indexed: a second axis, any node layout with any format)
// are described in layout/triangle_formats.hpp.
//
// TRIANGLE stream: 3 texels per triangle, in leaf order (a leaf's triangles are contiguous).
//   texel 3j+0 = (v0.x, v0.y, v0.z, original triangle id)   vertices as float bits, unmodified,
//   texel 3j+1 = (v1.x, v1.y, v1.z, material index)         so a watertight intersector can use them
//   texel 3j+2 = (v2.x, v2.y, v2.z, mesh index)
//
// ATTRIBUTE stream: 4 texels per triangle, same order as TRIANGLE (no indirection at shading time).
//   texel 4j+0 = (n0.x, n0.y, n0.z, uv0.x)   per-vertex shading normals (float bits); a mesh
//   texel 4j+1 = (n1.x, n1.y, n1.z, uv0.y)   without normals gets its geometric normal in all three,
//   texel 4j+2 = (n2.x, n2.y, n2.z, uv1.x)   a mesh without UVs gets (0,0)
//   texel 4j+3 = (uv1.y, uv2.x, uv2.y, 0)
//
// STORAGE kinds (same texel streams, chosen at shader-assembly time):
//   tbo   : one usamplerBuffer per stream (default; 1.8x faster than 2D on llvmpipe, NOTES.md)
//   tex2d : one usampler2D per stream, width kTex2DWidth, texel i at (i % W, i / W)
// A stream longer than the storage limit (GL_MAX_TEXTURE_BUFFER_SIZE, or W * MAX_TEXTURE_SIZE) is a
// clear error naming the stream and its size.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"
#include "datasets/scene.hpp"

namespace bvhlab {

constexpr uint32_t kLayoutVersion = 1;
constexpr uint32_t kEscapeEnd = 0x0FFFFFFFu;
constexpr uint32_t kIndexMask = 0x0FFFFFFFu;
constexpr uint32_t kTex2DWidth = 4096;
constexpr uint32_t kNodeTexels = 2, kTriangleTexels = 3, kAttributeTexels = 4;

struct PackedBvh {
  // The registered layout (layout/layouts.hpp) the NODE stream is written in: "v1" as described here,
  // or another layout's name. Kernels and accessors check it; the streams alone do not say.
  std::string layout = "v1";
  // The triangle format (layout/triangle_formats.hpp) the TRIANGLE/ATTRIBUTE/VERTEX streams are in.
  std::string triangleFormat = "raw";
  std::vector<glm::uvec4> nodes;
  std::vector<glm::uvec4> triangles;
  std::vector<glm::uvec4> attributes;
  std::vector<glm::uvec4> vertices;  // VERTEX stream: indexed format only, empty otherwise
  uint32_t depth = 0;  // tree depth (root alone = 1): kernels size their stacks from it
  size_t bytes() const { return 16 * (nodes.size() + triangles.size() + attributes.size() + vertices.size()); }
};

// The triangles of all of a scene's meshes, in one array, with the per-triangle data the packer needs.
struct TriangleSoup {
  std::vector<glm::vec3> v0, v1, v2;
  std::vector<glm::vec3> n0, n1, n2;
  std::vector<glm::vec2> uv0, uv1, uv2;
  std::vector<uint32_t> material, mesh;
  size_t size() const { return v0.size(); }
};
TriangleSoup gatherTriangles(const Scene& scene);
// Boxes and centroids for the builders.
std::vector<Aabb> triangleBoxes(const TriangleSoup& soup);
std::vector<glm::vec3> triangleCentroids(const TriangleSoup& soup);
// Unit normal of the triangle's plane, counter-clockwise front (+Z for a zero-area triangle): the
// normal gatherTriangles gives every corner of a mesh without normals.
glm::vec3 geometricNormal(const glm::vec3& v0, const glm::vec3& v1, const glm::vec3& v2);

// Depth-first re-order + escape links + triangle/attribute streams. Throws std::runtime_error if the
// tree exceeds the layout's limits.
PackedBvh packBvh(const Bvh& bvh, const TriangleSoup& soup);

// Decoded node, for tests and the C++ kernel mirrors.
struct NodeRecord {
  glm::vec3 bmin, bmax;
  uint32_t a, escape, count;  // a: second child (inner) or first triangle (leaf)
  bool isLeaf() const { return count > 0; }
};
NodeRecord unpackNode(const PackedBvh& packed, uint32_t index);

// Throws std::runtime_error naming the first stream longer than maxTexels, the storage kind's limit
// (tbo: GL_MAX_TEXTURE_BUFFER_SIZE; tex2d: kTex2DWidth * GL_MAX_TEXTURE_SIZE).
void checkStreamLimits(const PackedBvh& packed, const std::string& storage, uint64_t maxTexels);

}  // namespace bvhlab
