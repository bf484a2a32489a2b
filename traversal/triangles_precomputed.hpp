// triangles_precomputed.hpp — C++ mirror of triangles_precomputed.glsl (v0, edges, normal stored;
// Moller-Trumbore only: the arithmetic is explained there).
#pragma once
#include "traversal/ray_triangle.hpp"
#include "traversal/storage.hpp"
#include "traversal/triangles_raw.hpp"

namespace bvhlab::glsl::precomputed {

inline bool testTriangle(const Storage& s, Ray ray, int tri, float tMin, float tMax, float& t, vec2& bary) {
  t = tMax;
  bary = vec2(0.0f);
  vec3 v0 = uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 0)));
  vec3 e1 = uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 1)));
  vec3 e2 = uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 2)));
  vec3 n = uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 3)));
  float det = -dot(ray.dir, n);
  if (!(abs(det) >= kTriangleMinDet)) return false;
  float invDet = 1.0f / det;
  vec3 sv = ray.origin - v0;  // GLSL's s (here s is the storage)
  vec3 q = cross(sv, ray.dir);
  float u = dot(e2, q) * invDet;
  float v = -dot(e1, q) * invDet;
  t = dot(sv, n) * invDet;
  bary = vec2(u, v);
  return u >= 0.0f && v >= 0.0f && u + v <= 1.0f && t > tMin && t < tMax;
}

inline void loadTriangle(const Storage& s, int tri, vec3& v0, vec3& v1, vec3& v2) {
  v0 = uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 0)));
  v1 = v0 + uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 1)));
  v2 = v0 + uintBitsToFloat(uvec3(fetchTriangle(s, 4 * tri + 2)));
}

inline void loadTriangleIds(const Storage& s, int tri, uint& primitive, uint& material, uint& mesh) {
  primitive = fetchTriangle(s, 4 * tri + 0).w;
  material = fetchTriangle(s, 4 * tri + 1).w;
  mesh = fetchTriangle(s, 4 * tri + 2).w;
}

// The ATTRIBUTE stream is raw's.
inline void loadAttributes(const Storage& s, int tri, vec2 bary, vec3& normal, vec2& uv) {
  raw::loadAttributes(s, tri, bary, normal, uv);
}

}  // namespace bvhlab::glsl::precomputed
