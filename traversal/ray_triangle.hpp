// ray_triangle.hpp — C++ mirror of ray_triangle.glsl (Möller–Trumbore; the constant's reasoning
// is there).
#pragma once
#include "shaders/common.hpp"

namespace bvhlab::glsl {

constexpr float kTriangleMinDet = 1.17549435e-38f;

inline bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, float& t, vec2& bary) {
  t = tMax;
  bary = vec2(0.0f);
  vec3 e1 = v1 - v0;
  vec3 e2 = v2 - v0;
  vec3 p = cross(ray.dir, e2);
  float det = dot(e1, p);
  if (abs(det) < kTriangleMinDet) return false;
  float invDet = 1.0f / det;
  vec3 s = ray.origin - v0;
  float u = dot(s, p) * invDet;
  vec3 q = cross(s, e1);
  float v = dot(ray.dir, q) * invDet;
  t = dot(e2, q) * invDet;
  bary = vec2(u, v);
  return u >= 0.0f && v >= 0.0f && u + v <= 1.0f && t > tMin && t < tMax;
}

}  // namespace bvhlab::glsl
