// ray_box_robust.hpp — C++ mirror of ray_box_robust.glsl (Ize 2013; the constants' and the bound's
// reasoning is there). Same names and signatures as ray_box.hpp, in its own namespace: a kernel mirror
// selects it with `using robust::rayInverseDirection; using robust::intersectAabb;` (or a template
// parameter). GLSL's `precise`: this project builds with -std=c++20 (not gnu++20), where GCC defaults
// to -ffp-contract=off, so nothing is fused or reassociated here either.
#pragma once
#include "shaders/common.hpp"

namespace bvhlab::glsl::robust {

constexpr float kRobustMinDirection = 1e-30f;
constexpr float kRobustParallelInverse = 0.5f / kRobustMinDirection;
constexpr float kRobustExitScale = 1.0000004768371582f;
static_assert(kRobustExitScale == 1.0f + 8.0f / 16777216.0f, "1 + 8u, u = 2^-24");

inline vec3 rayInverseDirection(vec3 dir) {
  vec3 tiny = mix(vec3(kRobustMinDirection), vec3(-kRobustMinDirection), lessThan(dir, vec3(0.0f)));
  return 1.0f / mix(dir, tiny, lessThan(abs(dir), vec3(kRobustMinDirection)));
}

inline bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, float& tEnter) {
  vec3 t0 = (bmin - origin) * invDir;
  vec3 t1 = (bmax - origin) * invDir;
  vec3 tNear = min(t0, t1);
  vec3 tFar = max(t0, t1) * kRobustExitScale;
  bvec3 parallel = greaterThanEqual(abs(invDir), vec3(kRobustParallelInverse));
  bvec3 inSlab = equal(clamp(origin, bmin, bmax), origin);
  tNear = mix(tNear, mix(vec3(INF), vec3(-INF), inSlab), parallel);
  tFar = mix(tFar, mix(vec3(-INF), vec3(INF), inSlab), parallel);
  tEnter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
  float tExit = min(min(tFar.x, tFar.y), min(tFar.z, tMax));
  return tEnter <= tExit;
}

}  // namespace bvhlab::glsl::robust
