// A batch of rays as every tracer of `bvhlab trace` reads it: the GLSL kernels (two vec4 per ray in
// a shader storage buffer), Embree (traversal/embree_tracer.hpp) and the C++ mirrors.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab {

// std430 layout of GLSL's `vec4 rays[2 * i + k]`: (origin, tMin), (dir, tMax).
struct BatchRay {
  glm::vec3 origin;
  float tMin;
  glm::vec3 dir;
  float tMax;
};
static_assert(sizeof(BatchRay) == 32, "two vec4 texels per ray");

// One ray's answer. Closest-hit: hit, the triangle (soup index) and t. Any-hit: hit only (prim and t
// are left at kNoPrim / tMax).
struct BatchHit {
  static constexpr uint32_t kNoPrim = 0xFFFFFFFFu;
  bool hit = false;
  uint32_t prim = kNoPrim;
  float t = 0.0f;
};

}  // namespace bvhlab
