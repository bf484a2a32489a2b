// Procedural meshes for the benchmark suite (datasets/scenes/bench/): scenes on which BVH
// builders produce genuinely different trees, unlike a compact scan seen by primary rays.
//
//   stadium   "teapot in a stadium": a dense torus-knot tube ~1e-3 of the enclosure's size at the centre
//             of a huge, sparse stadium bowl of a few thousand large triangles
//   interior  a multi-storey building: floor slabs and corridor walls spanning the building as long thin
//             slivers, rooms with doorways, many columns, stairs; almost everything axis-aligned
//   hairball  a tangle of long, thin, overlapping ribbons (random smooth strands) inside a unit sphere
//   terrain   a fractal heightfield (octaves of value noise), meant to be seen at grazing angles
//   scaling   procedural.hpp's makeLargeMesh (same content at every size): the cost-vs-size series
//
// Every generator returns EXACTLY the requested number of triangles (so a scene's count is the number
// its file asks for), is a pure function of (triangles, seed) (SplitMix64 and integer hashing, never
// std:: distributions; no two draws unsequenced in one expression, so every compiler makes the same mesh:
// tests/test_bench_scenes.cpp pins their hashes), has no normals or UVs (flat shading), and sits in a
// documented box. The request is checked in 64 bits against [kMinBenchTriangles,
// kMaxProceduralTriangles] before anything is allocated; a bad request is an InputError naming the
// generator.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/scene.hpp"

namespace bvhlab {

// The fewest triangles a bench generator accepts: below this the structures (rooms, strands, the
// stadium's enclosure plus its dense object) degenerate into a handful of pieces.
constexpr uint64_t kMinBenchTriangles = 1000;

// Stadium: bowl of radius ~1000 centred on the origin (y from 0 to ~190), the dense object within
// 1.2 of (0, 1.2, 0). min(4096, triangles / 16) enclosure triangles, the rest in the object.
Mesh makeStadium(uint64_t triangles, uint64_t seed = 1);
// Interior: a building in x,z in [0, W] x [0, D] (W, D grow with the budget; 60 x 30 m at 200k),
// 3 storeys of 3 m, y in [0, 9].
Mesh makeInterior(uint64_t triangles, uint64_t seed = 1);
// Hairball: ribbons of width 0.004 inside the unit sphere about the origin.
Mesh makeHairball(uint64_t triangles, uint64_t seed = 1);
// Terrain: x,z in [-500, 500], heights within [0, 160].
Mesh makeTerrain(uint64_t triangles, uint64_t seed = 1);

// The generators by name, for scene files (`generate = "..."`) and experiment configs.
struct BenchGenerator {
  std::string name;
  std::string summary;
  Mesh (*make)(uint64_t triangles, uint64_t seed);
};
const std::vector<BenchGenerator>& benchGenerators();  // stadium, interior, hairball, terrain, scaling
std::string benchGeneratorNames();                      // "stadium, interior, ..." for messages

// Checks a request against [kMinBenchTriangles, kMaxProceduralTriangles] (signed, so a negative
// count from a file is caught too); throws InputError "generator 'NAME': ..." otherwise.
void checkBenchRequest(const std::string& name, int64_t triangles);

// The mesh of generator `name` with `triangles` triangles (checkBenchRequest first). Unknown name:
// InputError listing the known ones. Mesh::name is "generate:NAME:TRIANGLES:SEED".
Mesh generateBenchMesh(const std::string& name, int64_t triangles, uint64_t seed);

// FNV-1a over positions and indices (bit patterns): equal meshes hash equal on every machine.
uint64_t meshContentHash(const Mesh& mesh);

}  // namespace bvhlab
