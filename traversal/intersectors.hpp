// The ray-box / ray-triangle pair a kernel mirror is instantiated with: the C++ counterpart of the
// shader assembler choosing ray_box.glsl + ray_triangle.glsl (fast) or ray_box_robust.glsl +
// ray_triangle_watertight.glsl (--robust watertight). Kernel mirrors call Tests::intersectAabb(...)
// where their GLSL twin calls intersectAabb(...).
#pragma once
#include "traversal/ray_box.hpp"
#include "traversal/ray_box_robust.hpp"
#include "traversal/ray_triangle.hpp"
#include "traversal/ray_triangle_watertight.hpp"

namespace bvhlab::glsl {

struct FastTests {
  static vec3 rayInverseDirection(vec3 dir) { return glsl::rayInverseDirection(dir); }
  static bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, float& tEnter) {
    return glsl::intersectAabb(origin, invDir, bmin, bmax, tMin, tMax, tEnter);
  }
  static bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, float& t, vec2& bary) {
    return glsl::intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
  }
};

struct RobustTests {
  static vec3 rayInverseDirection(vec3 dir) { return robust::rayInverseDirection(dir); }
  static bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, float& tEnter) {
    return robust::intersectAabb(origin, invDir, bmin, bmax, tMin, tMax, tEnter);
  }
  static bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, float& t, vec2& bary) {
    return watertight::intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
  }
};

}  // namespace bvhlab::glsl
