// Builder inputs for the builder tests and benchmarks (tests/test_builders.cpp,
// experiments/bench/bench_builders.cpp): generated triangle soups and the bunny, as boxes + centroids
// (and their vertices, for builders that clip triangles).
// Header-only and not used by the library itself: the mesh loader needs datasets/OpenMesh, which the
// test and benchmark executables link.
#pragma once
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"
#include "datasets/random_draws.hpp"

#if __has_include("datasets/mesh_io.hpp")
#include "datasets/mesh_io.hpp"
#define BVHLAB_TEST_INPUTS_MESH_IO 1
#else
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#endif

namespace bvhlab::testing {

// Builders that split primitives into several references (sbvh): a primitive may be referenced by
// more than one leaf, and a leaf's box need only hold the clipped part of each primitive it
// references. The tests keep the strict invariants (each primitive exactly once, leaf box = union of
// its primitives' boxes) for every other builder.
inline bool splitsPrimitives(const std::string& builder) { return builder == "sbvh"; }

// Triangles reduced to what a builder sees: boxes and centroids, and the vertices of the sets made
// of triangles (inputWithTriangles() passes them, so a splitting builder clips the triangles rather
// than their boxes).
struct PrimitiveSet {
  std::string name;
  std::vector<Aabb> boxes;
  std::vector<glm::vec3> centroids;
  std::vector<glm::vec3> v0, v1, v2;  // empty as soon as one primitive was added as a box

  void addTriangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    Aabb box;
    box.grow(a);
    box.grow(b);
    box.grow(c);
    if (v0.size() == boxes.size()) v0.push_back(a), v1.push_back(b), v2.push_back(c);
    boxes.push_back(box);
    centroids.push_back((a + b + c) / 3.0f);
  }
  void addBox(const Aabb& box, const glm::vec3& centroid) {
    boxes.push_back(box);
    centroids.push_back(centroid);
    v0.clear(), v1.clear(), v2.clear();
  }
  size_t size() const { return boxes.size(); }
  bool hasTriangles() const { return !boxes.empty() && v0.size() == boxes.size(); }
  BuildInput input() const { return {boxes, centroids}; }
  BuildInput inputWithTriangles() const {
    if (!hasTriangles()) return input();
    return {boxes, centroids, v0, v1, v2};
  }
};

// `count` triangles of random orientation, centres uniform in the unit cube, edge lengths spread over
// two orders of magnitude (0.002..0.2), so boxes overlap and vary in size.
inline PrimitiveSet randomSoup(size_t count, uint32_t seed = 1) {
  PrimitiveSet set;
  set.name = "random" + std::to_string(count);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
  for (size_t i = 0; i < count; ++i) {
    // draw3 makes the draws in a fixed order (datasets/random_draws.hpp): the same seed must give the
    // same soup, so the same tree hashes, under every compiler (the sanitizer build is Clang's).
    const glm::vec3 c = draw3<glm::vec3>(unit, rng);
    const float size = 0.002f * std::pow(100.0f, unit(rng));
    auto corner = [&] { return c + size * draw3<glm::vec3>(signedUnit, rng); };
    const glm::vec3 a = corner(), b = corner(), d = corner();
    set.addTriangle(a, b, d);
  }
  return set;
}

// A height field of nx * nz quads (2 triangles each) over [0,1]^2 with smooth bumps: the
// well-behaved case, every triangle about the same size.
inline PrimitiveSet gridSoup(uint32_t nx, uint32_t nz) {
  PrimitiveSet set;
  set.name = "grid" + std::to_string(2 * nx * nz);
  auto p = [&](uint32_t i, uint32_t k) {
    const float x = float(i) / float(nx), z = float(k) / float(nz);
    return glm::vec3(x, 0.1f * std::sin(12.0f * x) * std::cos(9.0f * z), z);
  };
  for (uint32_t k = 0; k < nz; ++k)
    for (uint32_t i = 0; i < nx; ++i) {
      set.addTriangle(p(i, k), p(i + 1, k), p(i + 1, k + 1));
      set.addTriangle(p(i, k), p(i + 1, k + 1), p(i, k + 1));
    }
  return set;
}

// A UV sphere of radius 1 with nu * nv quads (2 triangles each), its radius modulated by `bumps` so
// it is "sphere-like" rather than a sphere. The pole rows have degenerate (zero-area) triangles.
inline PrimitiveSet sphereSoup(uint32_t nu, uint32_t nv, float bumps = 0.0f) {
  PrimitiveSet set;
  set.name = "sphere" + std::to_string(2 * nu * nv);
  const float pi = 3.14159265358979f;
  auto p = [&](uint32_t i, uint32_t k) {
    const float phi = 2.0f * pi * float(i % nu) / float(nu), theta = pi * float(k) / float(nv);
    const float r = 1.0f + bumps * std::sin(7.0f * phi) * std::sin(5.0f * theta);
    return r * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  for (uint32_t k = 0; k < nv; ++k)
    for (uint32_t i = 0; i < nu; ++i) {
      set.addTriangle(p(i, k), p(i + 1, k), p(i + 1, k + 1));
      set.addTriangle(p(i, k), p(i + 1, k + 1), p(i, k + 1));
    }
  return set;
}

// `count` long thin triangles of random orientation crossing one another in the unit cube (grass,
// hair, wires, a jumble of sticks): lengths 0.1..0.6 (log-uniform), widths 1% of the length. Their
// boxes are large and overlap everywhere while their area is small: the case spatial splits are for.
inline PrimitiveSet thinTriangles(size_t count, uint32_t seed = 3) {
  PrimitiveSet set;
  set.name = "thin" + std::to_string(count);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
  auto direction = [&] {
    while (true) {
      const glm::vec3 d = draw3<glm::vec3>(signedUnit, rng);
      const float len = glm::length(d);
      if (len > 0.1f && len <= 1.0f) return d / len;
    }
  };
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c = draw3<glm::vec3>(unit, rng);
    const float length = 0.1f * std::pow(6.0f, unit(rng));
    const glm::vec3 d = direction();
    glm::vec3 side = glm::cross(d, direction());
    side = glm::length(side) > 1e-3f ? glm::normalize(side) : glm::vec3(0.0f, 1.0f, 0.0f);
    const glm::vec3 a = c - 0.5f * length * d, b = c + 0.5f * length * d;
    set.addTriangle(a, b, a + 0.01f * length * side);
  }
  return set;
}

// `count` small triangles scattered on the plane y = 0 (the boxes have zero extent in y).
inline PrimitiveSet planeSoup(size_t count, uint32_t seed = 2) {
  PrimitiveSet set;
  set.name = "plane" + std::to_string(count);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), small(-0.001f, 0.001f);
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c = drawXZ<glm::vec3>(unit, rng);  // fixed order (datasets/random_draws.hpp): last first
    const glm::vec3 v2 = c + drawXZ<glm::vec3>(small, rng), v1 = c + drawXZ<glm::vec3>(small, rng);
    set.addTriangle(c + drawXZ<glm::vec3>(small, rng), v1, v2);
  }
  return set;
}

// The report's mesh. Returns an empty set when the file is missing (run `bash datasets/fetch.sh`).
inline std::filesystem::path bunnyPath() {
  return std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
}

inline PrimitiveSet loadTriangles(const std::filesystem::path& path) {
  PrimitiveSet set;
  set.name = path.stem().string();
  if (!std::filesystem::exists(path)) return set;
#ifdef BVHLAB_TEST_INPUTS_MESH_IO
  const Mesh mesh = loadMesh(path);
  for (const glm::uvec3& t : mesh.triangles)
    set.addTriangle(mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
#else
  OpenMesh::TriMesh_ArrayKernelT<> mesh;
  if (!OpenMesh::IO::read_mesh(mesh, path.string())) throw std::runtime_error("cannot read " + path.string());
  for (const auto& face : mesh.faces()) {
    glm::vec3 v[3];
    int k = 0;
    for (const auto& vh : face.vertices()) {
      const auto& q = mesh.point(vh);
      v[k++] = glm::vec3(q[0], q[1], q[2]);
    }
    set.addTriangle(v[0], v[1], v[2]);
  }
#endif
  return set;
}

}  // namespace bvhlab::testing
