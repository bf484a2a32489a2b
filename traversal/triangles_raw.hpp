// triangles_raw.hpp — C++ mirror of triangles_raw.glsl (the `raw` triangle format).
#pragma once
#include "traversal/storage.hpp"

namespace bvhlab::glsl::raw {

inline void loadTriangle(const Storage& s, int tri, vec3& v0, vec3& v1, vec3& v2) {
  v0 = uintBitsToFloat(uvec3(fetchTriangle(s, 3 * tri + 0)));
  v1 = uintBitsToFloat(uvec3(fetchTriangle(s, 3 * tri + 1)));
  v2 = uintBitsToFloat(uvec3(fetchTriangle(s, 3 * tri + 2)));
}

// Tests: the intersector pair of traversal/intersectors.hpp (its intersectTriangle is the module the
// assembler picks).
template <class Tests>
inline bool testTriangle(const Storage& s, Ray ray, int tri, float tMin, float tMax, float& t, vec2& bary) {
  vec3 v0, v1, v2;
  loadTriangle(s, tri, v0, v1, v2);
  return Tests::intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
}

inline void loadTriangleIds(const Storage& s, int tri, uint& primitive, uint& material, uint& mesh) {
  primitive = fetchTriangle(s, 3 * tri + 0).w;
  material = fetchTriangle(s, 3 * tri + 1).w;
  mesh = fetchTriangle(s, 3 * tri + 2).w;
}

// The normal is interpolated, NOT normalised (see triangles_raw.glsl).
inline void loadAttributes(const Storage& s, int tri, vec2 bary, vec3& normal, vec2& uv) {
  uvec4 t0 = fetchAttribute(s, 4 * tri + 0);
  uvec4 t1 = fetchAttribute(s, 4 * tri + 1);
  uvec4 t2 = fetchAttribute(s, 4 * tri + 2);
  uvec4 t3 = fetchAttribute(s, 4 * tri + 3);
  vec3 n0 = uintBitsToFloat(uvec3(t0));
  vec3 n1 = uintBitsToFloat(uvec3(t1));
  vec3 n2 = uintBitsToFloat(uvec3(t2));
  vec2 uv0 = uintBitsToFloat(uvec2(t0.w, t1.w));
  vec2 uv1 = uintBitsToFloat(uvec2(t2.w, t3.x));
  vec2 uv2 = uintBitsToFloat(uvec2(t3.y, t3.z));
  float w = 1.0f - bary.x - bary.y;
  normal = w * n0 + bary.x * n1 + bary.y * n2;
  uv = w * uv0 + bary.x * uv1 + bary.y * uv2;
}

}  // namespace bvhlab::glsl::raw
