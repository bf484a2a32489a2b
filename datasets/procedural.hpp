// Procedural data: the project's logo and a checker texture, and meshes for tests and benchmarks.
// Everything is a pure function of its arguments (our own SplitMix64 generator and integer hashing,
// never std:: distributions, whose output differs between standard libraries), so the same call gives
// bit-identical data on every machine.
#pragma once
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "datasets/scene.hpp"

namespace bvhlab {

// Resource limit for every mesh generator below: the most triangles one generated mesh may have.
// A generated mesh costs up to ~110 bytes per triangle (soup: 3 own positions 36 B + indices 12 B;
// spheres, cubes and planes: about one vertex per triangle with position, normal and UV, 32 B, plus
// 12 B of indices, twice over while vectors grow), and building, packing and uploading its BVH some
// 150-250 bytes more per triangle (build references, nodes, texel streams). 2^26 (67M) triangles is
// thus ~16-24 GB, the whole memory of the 24 GiB machines this project runs on (the largest shipped
// experiment, large.toml, asks for 10M). A request above it (10^9 triangles from a config or a
// resolution whose product overflows) is an InputError naming the generator and the request, thrown
// before anything is allocated, instead of std::bad_alloc or the OOM killer.
constexpr size_t kMaxProceduralTriangles = size_t(1) << 26;

// The bvhlab emblem: a BVH drawn as a binary tree of boxes (root, two inner nodes, four leaves each
// holding a triangle) on a dark rounded tile. size x size, linear RGBA, opaque, 4x4 supersampled.
Image makeLogoTexture(int size = 512);

// squares x squares checkerboard, (0,0) corner in colour `a`. Linear RGBA, opaque.
Image makeCheckerTexture(int size = 512, int squares = 8, glm::vec3 a = glm::vec3(0.8f),
                         glm::vec3 b = glm::vec3(0.1f));

// Unit-radius UV sphere about the origin: `segments` around +Y (>= 3), `rings` pole to pole (>= 2).
// Per-vertex normals and UVs (u around, v = 0 at the south pole); a seam column of duplicated vertices.
// 2 * segments * (rings - 1) triangles (one per segment at each pole), at most kMaxProceduralTriangles.
Mesh makeUvSphere(int segments, int rings);

// The closed cube [-1,1]^3, each face an n x n grid of quads (n >= 1): 12 n^2 triangles, outward
// winding, flat per-face normals, per-face UVs. Edge vertices are repeated per face with identical
// coordinates, so the surface is geometrically watertight. 12 n^2 <= kMaxProceduralTriangles.
Mesh makeCube(int n);

// The square y = 0, |x|,|z| <= 1 as an nx x nz grid of quads: 2 nx nz triangles, normals +Y, UVs.
// 2 nx nz <= kMaxProceduralTriangles.
Mesh makeGridPlane(int nx, int nz);

// `count` random triangles: centres uniform in [0,1]^3, random orientation, sizes log-uniform over
// [minSize, maxSize] (the corner offsets' half-extent). No normals or UVs. count <= kMaxProceduralTriangles.
Mesh makeTriangleSoup(size_t count, uint64_t seed = 1, float minSize = 0.002f, float maxSize = 0.2f);

// Exactly `triangles` triangles (>= 100) of something a BVH finds hard: a bumpy, noise-displaced
// sphere (radius ~1, 3/4 of the budget, fine and uniform) inside a clustered cloud of small
// tetrahedra of log-uniform sizes (the rest, shell 1.4..3.5, 48 Gaussian clusters): dense and sparse
// regions, long thin gaps and many overlapping boxes. No normals (flat shading), no UVs.
// Deterministic in (triangles, seed). triangles <= kMaxProceduralTriangles.
Mesh makeLargeMesh(size_t triangles, uint64_t seed = 1);

// SplitMix64 (Steele, Lea, Flood 2014): the generator behind every random choice above.
struct SplitMix64 {
  uint64_t state;
  explicit SplitMix64(uint64_t seed) : state(seed) {}
  uint64_t next();
  float uniform();                       // [0, 1), 24 random bits
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  float normal();                        // standard normal (Box-Muller)
  glm::vec3 unitVector();                // uniform on the unit sphere
  // Vectors of three draws, made in draw3's fixed order (datasets/random_draws.hpp), so a seed gives the
  // same vector with every compiler. Every random choice here is sequenced the same way: one draw per
  // statement where two would meet in an expression.
  glm::vec3 uniform3(float lo, float hi);  // each coordinate uniform(lo, hi)
  glm::vec3 normal3();                     // each coordinate normal()
};

}  // namespace bvhlab
