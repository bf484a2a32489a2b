// The ray cost of a tree (bench_builders' accuracy curves): node visits + triangle tests per
// closest-hit ray, traversed front to back on the CPU over the Bvh itself, so that a tree's quality
// can be given beside its build time without a renderer. Only bench_builders.cpp includes this.
#pragma once
#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/random_draws.hpp"

namespace bvhlab::bench {

using bvhlab::testing::PrimitiveSet;

// Closest-hit rays traversed front to back over the Bvh itself: a node counts as visited when it is
// entered (its box was hit closer than the closest hit so far when it is popped); every triangle of
// a visited leaf counts as tested. Rays: from random points on the sphere around the scene (radius
// its diagonal) to random points in its box, so most rays hit. The same rays for every tree.
struct Ray {
  glm::vec3 origin, dir, invDir;
};

inline std::vector<Ray> curveRays(const PrimitiveSet& set, size_t count) {
  Aabb bounds;
  for (const Aabb& b : set.boxes) bounds.grow(b);
  const glm::vec3 centre = 0.5f * (bounds.min + bounds.max), extent = bounds.max - bounds.min;
  const float radius = glm::length(extent);
  std::mt19937 rng(15);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), n(-1.0f, 1.0f);
  std::vector<Ray> rays;
  while (rays.size() < count) {
    const glm::vec3 p = draw3<glm::vec3>(n, rng);  // fixed order: datasets/random_draws.hpp
    if (!(glm::dot(p, p) > 1e-6f && glm::dot(p, p) <= 1.0f)) continue;  // uniform direction by rejection
    const glm::vec3 origin = centre + radius * glm::normalize(p);
    const glm::vec3 target = bounds.min + draw3<glm::vec3>(u, rng) * extent;
    glm::vec3 dir = glm::normalize(target - origin);
    // No zero components: 1 / 0 and then 0 * inf would make the slab test NaN for origins on a slab.
    // 1e-20 is far below any direction component that changes a float slab distance in these scenes.
    for (int k = 0; k < 3; ++k)
      if (std::fabs(dir[k]) < 1e-20f) dir[k] = 1e-20f;
    rays.push_back({origin, dir, 1.0f / dir});
  }
  return rays;
}

// Entry distance of the ray into the box, or +inf when it misses it or enters it beyond tMax.
inline float entry(const Ray& r, const Aabb& b, float tMax) {
  const glm::vec3 t0 = (b.min - r.origin) * r.invDir, t1 = (b.max - r.origin) * r.invDir;
  const glm::vec3 lo = glm::min(t0, t1), hi = glm::max(t0, t1);
  const float tNear = std::max({lo.x, lo.y, lo.z, 0.0f}), tFar = std::min({hi.x, hi.y, hi.z, tMax});
  return tNear <= tFar ? tNear : INFINITY;
}

// Möller & Trumbore (1997): the hit distance, or tMax when there is none closer.
inline float hitTriangle(const Ray& r, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, float tMax) {
  const glm::vec3 e1 = b - a, e2 = c - a, p = glm::cross(r.dir, e2);
  const float det = glm::dot(e1, p);
  if (!(std::fabs(det) > 0.0f)) return tMax;  // parallel or degenerate
  const float inv = 1.0f / det;
  const glm::vec3 s = r.origin - a;
  const float u = glm::dot(s, p) * inv;
  if (!(u >= 0.0f && u <= 1.0f)) return tMax;
  const glm::vec3 q = glm::cross(s, e1);
  const float v = glm::dot(r.dir, q) * inv;
  if (!(v >= 0.0f && u + v <= 1.0f)) return tMax;
  const float t = glm::dot(e2, q) * inv;
  return t > 0.0f && t < tMax ? t : tMax;
}

inline double rayCost(const Bvh& bvh, const PrimitiveSet& set, const std::vector<Ray>& rays) {
  double cost = 0.0;
  std::vector<std::pair<uint32_t, float>> stack;
  for (const Ray& ray : rays) {
    float tBest = INFINITY;
    stack.clear();
    if (const float t = entry(ray, bvh.nodes[0].bounds, tBest); t < INFINITY) stack.push_back({0u, t});
    while (!stack.empty()) {
      const auto [index, t] = stack.back();
      stack.pop_back();
      if (!(t < tBest)) continue;
      cost += 1.0;  // a node visit
      const BvhNode& node = bvh.nodes[index];
      if (node.isLeaf()) {
        cost += node.count;  // triangle tests
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
          const uint32_t id = bvh.primIndices[k];
          tBest = hitTriangle(ray, set.v0[id], set.v1[id], set.v2[id], tBest);
        }
        continue;
      }
      const float tl = entry(ray, bvh.nodes[node.left].bounds, tBest), tr = entry(ray, bvh.nodes[node.right].bounds, tBest);
      const bool leftFirst = tl <= tr;  // both finite or +inf: never NaN
      const std::pair<uint32_t, float> near{leftFirst ? node.left : node.right, leftFirst ? tl : tr};
      const std::pair<uint32_t, float> far{leftFirst ? node.right : node.left, leftFirst ? tr : tl};
      if (far.second < INFINITY) stack.push_back(far);
      if (near.second < INFINITY) stack.push_back(near);
    }
  }
  return cost / double(rays.size());
}

}  // namespace bvhlab::bench
