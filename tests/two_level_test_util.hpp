// Shared by tests/test_two_level.cpp's mirror and GLSL checks: two-level test scenes (a closed welded
// sphere, random instances), brute force over the flattened scene in double with its "clear ray"
// classification, the rays, and the per-ray comparison.
#pragma once
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "datasets/random_draws.hpp"
#include "layout/layouts.hpp"
#include "layout/pack_two_level.hpp"
#include "traversal/two_level.hpp"
#include "traversal_test_util.hpp"

namespace bvhlab::twoleveltest {

using namespace traversaltest;
using glsl::two_level::TwoLevelCounters;
using glsl::two_level::TwoLevelHit;

// ---- scenes -------------------------------------------------------------------------------------

// A closed UV sphere whose seam and poles are welded (one vertex each), so every edge is shared by
// exactly two triangles with the same vertex bits: the mesh the watertightness checks aim at.
inline Mesh closedSphere(int stacks, int slices) {
  Mesh m;
  m.name = "closed-sphere";
  m.positions.push_back({0.0f, 1.0f, 0.0f});
  for (int i = 1; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const double theta = M_PI * i / stacks, phi = 2.0 * M_PI * j / slices;
      m.positions.push_back(glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
    }
  m.positions.push_back({0.0f, -1.0f, 0.0f});
  const uint32_t south = uint32_t(m.positions.size() - 1);
  auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * slices + (j % slices)); };
  for (int j = 0; j < slices; ++j) {
    m.triangles.push_back({0u, ring(1, j + 1), ring(1, j)});
    m.triangles.push_back({south, ring(stacks - 1, j), ring(stacks - 1, j + 1)});
  }
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      m.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j)});
      m.triangles.push_back({ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)});
    }
  return m;
}

struct TwoLevelScene {
  std::vector<TriangleSoup> soups;  // per BLAS, object space
  std::vector<Instance> instances;
};

inline std::vector<PackedBvh> packBlases(const TwoLevelScene& scene, const std::string& layout) {
  std::vector<PackedBvh> blases;
  for (const TriangleSoup& soup : scene.soups) {
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(soup);
    blases.push_back(findLayout(layout).pack(buildBvh("sah-binned", BuildInput{boxes, centroids}, BuildOptions{}), soup));
  }
  return blases;
}

inline glm::mat4x3 affine(glm::vec3 translation, glm::vec3 axis, float angle, glm::vec3 scale) {
  const glm::mat4 m = glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), translation), angle, axis), scale);
  return glm::mat4x3(m);
}

// Three meshes, `count` instances at random rotations and scales around `offset`.
inline TwoLevelScene randomScene(glm::vec3 offset, glm::vec3 scale, size_t count, uint32_t seed) {
  TwoLevelScene s;
  s.soups = {soupOf({closedSphere(8, 16)}), soupOf({gridMesh(6)}), soupOf({randomSoupMesh(60, seed)})};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 axis = glm::normalize(draw3<glm::vec3>(u, rng) + glm::vec3(0.0f, 0.0f, 1e-3f));
    const float k = 1.0f + 0.5f * u(rng);
    const float angle = 3.0f * u(rng);  // drawn before the offset (see random_draws.hpp)
    const glm::vec3 at = offset + 4.0f * draw3<glm::vec3>(u, rng);
    s.instances.push_back({uint32_t(i % 3), affine(at, axis, angle, k * scale)});
  }
  return s;
}

// ---- brute force over the flattened scene, in double ---------------------------------------------

// Every instance's triangles in world space, transformed in double (a float world copy of a mesh at
// 1e5 would round its vertices to 2^-7, the very error two-level traversal avoids).
struct FlatTriangle {
  glm::dvec3 v0, v1, v2;
  uint32_t instance, triangle;
};

inline std::vector<FlatTriangle> flatten(const TwoLevelScene& scene) {
  std::vector<FlatTriangle> out;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    const glm::dmat3 l{glm::dvec3(inst.objectToWorld[0]), glm::dvec3(inst.objectToWorld[1]), glm::dvec3(inst.objectToWorld[2])};
    const glm::dvec3 t(inst.objectToWorld[3]);
    const TriangleSoup& soup = scene.soups[inst.blas];
    for (uint32_t k = 0; k < soup.size(); ++k)
      out.push_back({l * glm::dvec3(soup.v0[k]) + t, l * glm::dvec3(soup.v1[k]) + t, l * glm::dvec3(soup.v2[k]) + t, i, k});
  }
  return out;
}

// The barycentric margin and the relative t tolerance of the comparison. The two-level walk tests the
// object-space ray, rounded by the transform: measured below at <= 2e-6 of the coordinates near the
// origin and at 1e5 (translation first), relative to triangles >= 0.05 across, so a hit 1e-3 (in
// barycentrics) inside its triangle cannot change triangles and its t moves by far less than 1e-4.
inline constexpr double kBaryMargin = 1e-3;
inline constexpr double kRelativeT = 1e-4;

struct Reference {
  bool found = false;
  double t = 0.0;
  uint32_t instance = 0, triangle = 0;
  bool clear = true;  // no triangle within the margins: the float walks must agree exactly on it
};

inline Reference reference(const std::vector<FlatTriangle>& tris, const RayQuery& q) {
  const glm::dvec3 o(q.ray.origin), d(q.ray.dir);
  Reference r;
  struct Near {
    double t;
    double margin;
  };
  std::vector<Near> near;
  for (const FlatTriangle& f : tris) {
    const glm::dvec3 e1 = f.v1 - f.v0, e2 = f.v2 - f.v0, p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (det == 0.0) continue;
    const glm::dvec3 s = o - f.v0, qv = glm::cross(s, e1);
    const double u = glm::dot(s, p) / det, v = glm::dot(d, qv) / det, t = glm::dot(e2, qv) / det;
    const double margin = std::min({u, v, 1.0 - u - v});
    if (margin < -kBaryMargin) continue;
    near.push_back({t, margin});
    if (margin >= 0.0 && t > q.tMin && t < q.tMax && (!r.found || t < r.t)) {
      r.found = true;
      r.t = t;
      r.instance = f.instance;
      r.triangle = f.triangle;
    }
  }
  // Not clear: a triangle whose edge the ray passes within the margin, in front of (or near) the
  // closest hit, or a hit near tMin/tMax, or two hits at nearly the same t.
  const double tol = kRelativeT * (r.found ? std::max(1.0, r.t) : 1.0);
  for (const Near& n : near) {
    const bool relevant = n.t > double(q.tMin) - tol && n.t < double(q.tMax) + tol && (!r.found || n.t < r.t + tol);
    if (!relevant) continue;
    if (std::abs(n.margin) < kBaryMargin) r.clear = false;
    if (r.found && n.margin >= 0.0 && n.t != r.t && std::abs(n.t - r.t) < tol) r.clear = false;
    if (std::abs(n.t - double(q.tMin)) < tol || std::abs(n.t - double(q.tMax)) < tol) r.clear = false;
  }
  return r;
}

// Random rays over the scene's bounds (randomRays), and as many aimed at the instances' origins
// (with a jitter), so that a sparse scene is hit too.
inline std::vector<RayQuery> sceneRays(const TwoLevelScene& scene, const Aabb& bounds, size_t count, uint32_t seed) {
  std::vector<RayQuery> rays = randomRays(bounds, count / 2, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const glm::vec3 c = bounds.center(), e = bounds.extent();
  for (size_t i = rays.size(); i < count; ++i) {
    const Instance& inst = scene.instances[i % scene.instances.size()];
    const glm::vec3 from = c + draw3<glm::vec3>(u, rng) * e;
    const glm::vec3 to = inst.objectToWorld * glm::vec4(0.5f * draw3<glm::vec3>(u, rng), 1.0f);
    rays.push_back({{from, to - from}, 0.0f, glsl::INF});
  }
  return rays;
}

// ---- the check ----------------------------------------------------------------------------------

struct MirrorRun {
  bool closest, any;
  TwoLevelHit hit;
  TwoLevelCounters cc, ac;
};

inline MirrorRun runMirror(const TwoLevelMirror& m, const glsl::Storage& s, const RayQuery& q) {
  MirrorRun r{};
  r.closest = m.closest(s, q.ray, q.tMin, q.tMax, r.hit, r.cc);
  r.any = m.any(s, q.ray, q.tMin, q.tMax, r.ac);
  return r;
}

// Ids of a two-level hit: (instance id, the mesh's own triangle id).
inline std::pair<uint32_t, uint32_t> hitIds(const PackedTwoLevel& p, const TwoLevelHit& h) {
  const glsl::Storage s(p.streams);
  uint primitive, material, mesh;
  glsl::loadTriangleIds(s, h.hit.tri, primitive, material, mesh);
  return {glsl::two_level::instanceId(s, h.record), primitive};
}

struct Tally {
  size_t rays = 0, clear = 0, hits = 0, failures = 0;
  double maxRelativeT = 0.0;
};

// Compares one ray's two-level result with the reference; returns false (and reports) on a mismatch.
inline bool agrees(const PackedTwoLevel& p, bool closest, bool any, const TwoLevelHit& h, const Reference& ref,
            const RayQuery& q, const std::string& who, Tally& tally) {
  ++tally.rays;
  if (!ref.clear) return true;
  ++tally.clear;
  tally.hits += ref.found;
  std::string what;
  if (closest != ref.found || any != ref.found) {
    what = "found " + std::to_string(closest) + "/" + std::to_string(any) + ", reference " + std::to_string(ref.found);
  } else if (ref.found) {
    const auto [instance, triangle] = hitIds(p, h);
    const double rel = std::abs(double(h.hit.t) - ref.t) / std::max(1.0, ref.t);
    tally.maxRelativeT = std::max(tally.maxRelativeT, rel);
    if (instance != ref.instance || triangle != ref.triangle || !(rel <= kRelativeT))
      what = "hit instance " + std::to_string(instance) + " triangle " + std::to_string(triangle) + " t " +
             std::to_string(h.hit.t) + ", reference " + std::to_string(ref.instance) + "/" +
             std::to_string(ref.triangle) + " t " + std::to_string(ref.t);
  } else if (h.hit.tri != -1 || h.record != -1 || h.hit.t != q.tMax) {
    what = "a miss must leave (tMax, -1) and no instance";
  }
  if (what.empty()) return true;
  if (++tally.failures <= 5) ADD_FAILURE() << who << ": " << what << "; " << describe(q);
  return false;
}

inline const std::vector<std::pair<std::string, std::string>>& layoutKernels() {
  static const std::vector<std::pair<std::string, std::string>> v = {
      {"v1", "stack-ordered"}, {"v1", "stack-unordered"}, {"v1", "stackless"}, {"bvh2-cb", "bvh2cb-stack-ordered"}};
  return v;
}


}  // namespace bvhlab::twoleveltest
