// Helpers the layout tests share (test_layout_bvh2cb.cpp, test_layout_wide.cpp, test_layout_cwbvh.cpp):
// the test meshes, trees built from them (a single-leaf tree included), rays aimed at them, brute
// force with the watertight test, the GL context when one can be made, and the per-ray comparison of
// a GLSL kernel with its C++ mirror.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "datasets/hard_cases.hpp"
#include "datasets/procedural.hpp"
#include "datasets/random_draws.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layout.hpp"
#include "layout/layouts.hpp"
#include "render/gl_context.hpp"
#include "render/ray_tracer_gl.hpp"
#include "traversal/kernels.hpp"
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

inline Bvh build(const std::string& builder, const TriangleSoup& soup, const BuildOptions& options = {}) {
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  return buildBvh(builder, BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, options);
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
  const auto inside = [&] { return box.min + draw3<glm::vec3>(u, rng) * e; };
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
      const glm::vec3 dir = glm::normalize((draw3<glm::vec3>(u, rng) - 0.5f) + 1e-3f);
      r.origin = c + dir * 1.5f * radius;
      r.dir = glm::normalize(target() - r.origin);
      if (kind == 3) r.tMax = 1.5f * radius * u(rng) + 0.5f * radius;
    } else if (kind == 1) {
      r.origin = inside();
      r.dir = glm::normalize((draw3<glm::vec3>(u, rng) - 0.5f) + 1e-3f);
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

// Triangle tests of closest-hit walks (watertight) of `kernel` ("" = the layout's default) over all rays.
inline uint64_t closestTriangleTests(const PackedBvh& p, const std::string& kernel, const std::vector<BatchRay>& rays) {
  const glsl::Storage s(p);
  uint64_t tests = 0;
  for (const BatchRay& r : rays) {
    glsl::Counters c;
    glsl::MeshHit hit{};
    findKernel(p.layout, kernel).closest(Robustness::Watertight)(s, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, hit, c);
    tests += c.triTests;
  }
  return tests;
}

// The mirror of kernel k under `robust` over `packed` against brute force's `expected` answers to
// `rays`: the same closest t (another triangle only at the same t), the same any-hit answer, no stack
// overflow at the layout's bound. Reports the first 3 differing rays as test failures.
inline void expectBruteForceHits(const PackedBvh& packed, const KernelInfo& k, Robustness robust,
                                 const std::vector<BatchRay>& rays, const std::vector<BatchHit>& expected) {
  const glsl::Storage s(packed);
  int failures = 0;
  for (size_t i = 0; i < rays.size() && failures < 3; ++i) {
    const BatchRay& r = rays[i];
    glsl::Counters c;
    glsl::MeshHit hit{};
    const glsl::Ray ray{r.origin, r.dir};
    const bool found = k.closest(robust)(s, ray, r.tMin, r.tMax, hit, c);
    const bool any = k.any(robust)(s, ray, r.tMin, r.tMax, c);
    uint32_t prim = BatchHit::kNoPrim, material, mesh;
    if (found) glsl::loadTriangleIds(s, hit.tri, prim, material, mesh);
    const bool same = found == expected[i].hit && any == expected[i].hit && !c.stackOverflow &&
                      (!found || hit.t == expected[i].t);
    if (!same) {
      ++failures;
      ADD_FAILURE() << "ray " << i << ": kernel " << found << "/" << any << " prim " << prim << " t " << hit.t
                    << "; brute force " << expected[i].hit << " prim " << expected[i].prim << " t " << expected[i].t;
    }
  }
}

// The hard-case suite (datasets/hard_cases.hpp: shared edges and vertices, slab planes, far and scaled
// copies) in watertight mode, on a sah-binned tree packed in `layout` and walked by `kernel` (""
// = the layout's default): no ray that must hit leaks, and every ray is answered as v1's stack-ordered answers it on the
// same tree (same hit or miss; t within nearlyEqual: where a ray meets a shared edge, the two
// triangles' rounded t can differ by an ulp, and which one a walk keeps depends on its visit order,
// since a box entered beyond the first t found is culled). Returns how many rays must hit.
inline size_t expectHardCasesAnsweredAsV1(const std::string& layout, const std::string& kernel = "") {
  size_t mustHit = 0;
  for (const hard::HardCase& hc : hard::makeHardCases()) {
    SCOPED_TRACE(hc.name + " / " + layout + " / " + findKernel(layout, kernel).name);
    Mesh mesh;
    mesh.positions = hc.positions;
    mesh.triangles = hc.triangles;
    MeshSceneOptions mo;
    mo.groundPlane = false;
    const TriangleSoup soup = gatherTriangles(makeMeshScene(mesh, mo));
    const Bvh bvh = build("sah-binned", soup);
    const PackedBvh v1 = packBvh(bvh, soup), packed = findLayout(layout).pack(bvh, soup);
    const glsl::Storage reference(v1), s(packed);
    const KernelInfo& k = findKernel(layout, kernel);
    int failures = 0;
    for (size_t i = 0; i < hc.rays.size() && failures < 3; ++i) {
      const hard::HardRay& r = hc.rays[i];
      const glsl::Ray ray{r.origin, r.dir};
      glsl::Counters c, cv1;
      glsl::MeshHit hit{}, hitV1{};
      const bool found = k.closest(Robustness::Watertight)(s, ray, r.tMin, r.tMax, hit, c);
      const bool foundV1 =
          findKernel("stack-ordered").closest(Robustness::Watertight)(reference, ray, r.tMin, r.tMax, hitV1, cv1);
      mustHit += r.mustHit;
      if ((r.mustHit && !found) || found != foundV1 || (found && !nearlyEqual(hit.t, hitV1.t)) || c.stackOverflow) {
        ++failures;
        ADD_FAILURE() << "ray " << i << (r.mustHit ? " (must hit)" : "") << ": " << found << " t " << hit.t << "; v1 "
                      << foundV1 << " t " << hitV1.t;
      }
    }
  }
  return mustHit;
}

// The GLSL kernel k (in the compute shader of `bvhlab trace`, under a GL context) against its C++
// mirror on every ray of `rays` over `packed`: the same answer, node visits, triangle tests and box
// tests, no overflow, and for closest hits the same primitive with t within nearlyEqual. Reports the
// first 3 differing rays as test failures; returns how many rays hit (so a caller can require enough).
inline size_t expectGlslEqualsMirror(const PackedBvh& packed, const KernelInfo& k, const std::vector<BatchRay>& rays,
                                     bool anyHit, Robustness robust, Storage storage = Storage::Tbo) {
  RayTracerOptions o;
  o.kernel = k.name;
  o.robust = robust;
  o.anyHit = anyHit;
  o.storage = storage;
  GlRayTracer gl(packed, o);
  gl.setRays(rays);
  std::vector<BatchHit> hits;
  const std::vector<glm::uvec4> counts = gl.traceCounted(&hits);
  const glsl::Storage s(packed);
  int failures = 0;
  size_t found = 0;
  for (size_t i = 0; i < rays.size() && failures < 3; ++i) {
    const BatchRay& r = rays[i];
    glsl::Counters c;
    glsl::MeshHit mh{};
    bool hit;
    uint32_t prim = BatchHit::kNoPrim, material, mesh;
    if (anyHit) {
      hit = k.any(robust)(s, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, c);
    } else {
      hit = k.closest(robust)(s, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, mh, c);
      if (hit) glsl::loadTriangleIds(s, mh.tri, prim, material, mesh);
    }
    found += hit;
    const bool same = hits[i].hit == hit && counts[i].x == c.nodeVisits && counts[i].y == c.triTests &&
                      counts[i].z == 0u && counts[i].w == c.boxTests && !c.stackOverflow &&
                      (anyHit || !hit || (hits[i].prim == prim && nearlyEqual(hits[i].t, mh.t)));
    if (!same) {
      ++failures;
      ADD_FAILURE() << "ray " << i << ": GLSL " << hits[i].hit << " prim " << hits[i].prim << " visits " << counts[i].x
                    << " tests " << counts[i].y << " boxes " << counts[i].w << "; mirror " << hit << " prim " << prim
                    << " visits " << c.nodeVisits << " tests " << c.triTests << " boxes " << c.boxTests;
    }
  }
  return found;
}

}  // namespace bvhlab::layouttest
