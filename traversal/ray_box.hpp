// ray_box.hpp — C++ mirror of ray_box.glsl (the slab test; the constant's reasoning is there).
#pragma once
#include "shaders/common.hpp"

namespace bvhlab::glsl {

constexpr float kMinDirectionComponent = 1e-30f;
constexpr float kParallelInverse = 0.5f / kMinDirectionComponent;

inline vec3 rayInverseDirection(vec3 dir) {
  vec3 tiny = mix(vec3(kMinDirectionComponent), vec3(-kMinDirectionComponent), lessThan(dir, vec3(0.0f)));
  return 1.0f / mix(dir, tiny, lessThan(abs(dir), vec3(kMinDirectionComponent)));
}

inline bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, float& tEnter) {
  vec3 t0 = (bmin - origin) * invDir;
  vec3 t1 = (bmax - origin) * invDir;
  vec3 tNear = min(t0, t1);
  vec3 tFar = max(t0, t1);
  bvec3 parallel = greaterThanEqual(abs(invDir), vec3(kParallelInverse));
  bvec3 inSlab = equal(clamp(origin, bmin, bmax), origin);
  tNear = mix(tNear, mix(vec3(INF), vec3(-INF), inSlab), parallel);
  tFar = mix(tFar, mix(vec3(-INF), vec3(INF), inSlab), parallel);
  tEnter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
  float tExit = min(min(tFar.x, tFar.y), min(tFar.z, tMax));
  return tEnter <= tExit;
}

}  // namespace bvhlab::glsl
