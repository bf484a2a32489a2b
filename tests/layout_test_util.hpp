// Helpers the layout tests share (test_layout_bvh2cb.cpp, test_layout_wide.cpp): the test meshes,
// trees built from them (a single-leaf tree included), rays aimed at them, brute force with the
// watertight test, and the GL context when one can be made.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "builders/builder.hpp"
#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layout.hpp"
#include "render/gl_context.hpp"
#include "traversal/intersectors.hpp"
#include "traversal/ray_batch.hpp"

namespace bvhlab::layouttest {

// A 3 x 3 x 3 grid of separate cubes, each face a 2 x 2 grid: axis-aligned faces and empty space.
inline Mesh cubeGrid() {
  Mesh out;
  const Mesh cube = makeCube(2);
  for (int i = 0; i < 27; ++i) {
    const glm::vec3 offset(float(i % 3) * 3.0f, float(i / 3 % 3) * 3.0f, float(i / 9) * 3.0f);
    const uint32_t base = uint32_t(out.positions.size());
    for (const glm::vec3& p : cube.positions) out.positions.push_back(0.5f * p + offset);
    for (const glm::uvec3& t : cube.triangles) out.triangles.push_back(t + glm::uvec3(base));
  }
  return out;
}

struct TestMesh {
  std::string name;
  TriangleSoup soup;
};

inline const std::vector<TestMesh>& testMeshes() {
  static const std::vector<TestMesh> meshes = [] {
    MeshSceneOptions mo;
    mo.groundPlane = false;
    std::vector<TestMesh> m;
    m.push_back({"sphere", gatherTriangles(makeMeshScene(makeUvSphere(24, 12), mo))});
    m.push_back({"soup", gatherTriangles(makeMeshScene(makeTriangleSoup(700, 9, 0.01f, 0.15f), mo))});
    m.push_back({"cube-grid", gatherTriangles(makeMeshScene(cubeGrid(), mo))});
    return m;
  }();
  return meshes;
}

inline Bvh build(const std::string& builder, const TriangleSoup& soup) {
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  return buildBvh(builder, BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, BuildOptions{});
}

// One leaf holding every triangle (at most kMaxLeafSize): the tree whose root is a leaf.
inline Bvh singleLeaf(const TriangleSoup& soup) {
  Bvh bvh;
  BvhNode leaf;
  for (const Aabb& b : triangleBoxes(soup)) leaf.bounds.grow(b);
  leaf.count = uint32_t(soup.size());
  bvh.nodes.push_back(leaf);
  for (uint32_t i = 0; i < soup.size(); ++i) bvh.primIndices.push_back(i);
  return bvh;
}

inline TriangleSoup firstTriangles(const TriangleSoup& s, size_t n) {
  TriangleSoup out = s;
  for (auto* v : {&out.v0, &out.v1, &out.v2, &out.n0, &out.n1, &out.n2}) v->resize(n);
  for (auto* v : {&out.uv0, &out.uv1, &out.uv2}) v->resize(n);
  out.material.resize(n);
  out.mesh.resize(n);
  return out;
}

// Rays at the soup's box from outside (to random points inside it), from inside, axis-parallel
// ones (direction components exactly 0: the slab test's parallel branch), and some with a finite tMax.
inline std::vector<BatchRay> testRays(const TriangleSoup& soup, size_t count, uint32_t seed) {
  Aabb box;
  for (const Aabb& b : triangleBoxes(soup)) box.grow(b);
  const glm::vec3 c = box.center(), e = box.extent();
  const float radius = glm::length(e);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const auto inside = [&] { return box.min + glm::vec3(u(rng), u(rng), u(rng)) * e; };
  // A few scattered triangles leave most of their box empty: aim the outside rays at them instead.
  const bool sparse = soup.size() < 50;
  const auto target = [&] {
    const size_t t = rng() % soup.size();
    return sparse ? (soup.v0[t] + soup.v1[t] + soup.v2[t]) / 3.0f : inside();
  };
  std::vector<BatchRay> rays;
  for (size_t i = 0; i < count; ++i) {
    BatchRay r{glm::vec3(0.0f), 0.0f, glm::vec3(0.0f, 0.0f, 1.0f), INFINITY};
    const size_t kind = i % 4;
    if (kind == 0 || kind == 3) {
      const glm::vec3 dir = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f) + 1e-3f);
      r.origin = c + dir * 1.5f * radius;
      r.dir = glm::normalize(target() - r.origin);
      if (kind == 3) r.tMax = 1.5f * radius * u(rng) + 0.5f * radius;
    } else if (kind == 1) {
      r.origin = inside();
      r.dir = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f) + 1e-3f);
    } else {
      const int axis = int(rng() % 3);
      r.origin = inside();
      r.origin[axis] = (rng() & 1u) ? box.min[axis] - radius : box.max[axis] + radius;
      r.dir = glm::vec3(0.0f);
      r.dir[axis] = r.origin[axis] < c[axis] ? 1.0f : -1.0f;
    }
    rays.push_back(r);
  }
  return rays;
}

// Brute force with the same watertight triangle test: the closest t over all triangles.
inline BatchHit bruteForce(const TriangleSoup& s, const BatchRay& r) {
  BatchHit best;
  best.t = r.tMax;
  for (uint32_t i = 0; i < s.size(); ++i) {
    float t;
    glsl::vec2 bary;
    if (glsl::watertight::intersectTriangle(glsl::Ray{r.origin, r.dir}, s.v0[i], s.v1[i], s.v2[i], r.tMin, best.t, t,
                                            bary)) {
      best = BatchHit{true, i, t};
    }
  }
  return best;
}

// GLSL's t against the mirror's: llvmpipe may contract the triangle test's products into fused
// multiply-adds (the mirror never does), which moves t by a few ulps; 2^-16 relative is far above that
// and far below any distance between the test meshes' surfaces. The triangle, the visits and the tests
// must agree exactly.
inline bool nearlyEqual(float a, float b) { return std::abs(a - b) <= 0x1.0p-16f * std::max(std::abs(a), std::abs(b)); }

inline std::unique_ptr<GlContext> contextOrNull() {
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    return createContext(backend && *backend ? parseBackend(backend) : Backend::OSMesa);
  } catch (const std::exception&) {
    return nullptr;
  }
}

}  // namespace bvhlab::layouttest
