// triangles_indexed.hpp — C++ mirror of triangles_indexed.glsl (welded vertices, oct normals, half uvs).
#pragma once
#include <glm/gtc/packing.hpp>

#include "traversal/storage.hpp"

namespace bvhlab::glsl::indexed {

inline void loadTriangle(const Storage& s, int tri, vec3& v0, vec3& v1, vec3& v2) {
  uvec4 index = fetchTriangle(s, tri);
  v0 = uintBitsToFloat(uvec3(fetchVertex(s, int(index.x))));
  v1 = uintBitsToFloat(uvec3(fetchVertex(s, int(index.y))));
  v2 = uintBitsToFloat(uvec3(fetchVertex(s, int(index.z))));
}

template <class Tests>
inline bool testTriangle(const Storage& s, Ray ray, int tri, float tMin, float tMax, float& t, vec2& bary) {
  vec3 v0, v1, v2;
  loadTriangle(s, tri, v0, v1, v2);
  return Tests::intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
}

inline uvec2 vertexWords(const Storage& s, uint k) {
  uvec4 texel = fetchAttribute(s, int(k >> 1));
  return (k & 1u) == 0u ? uvec2(texel.x, texel.y) : uvec2(texel.z, texel.w);
}

inline void loadTriangleIds(const Storage& s, int tri, uint& primitive, uint& material, uint& mesh) {
  uvec4 index = fetchTriangle(s, tri);
  uint ids = vertexWords(s, index.x).y;
  primitive = index.w;
  material = ids & 0xFFFFu;
  mesh = ids >> 16;
}

// GLSL's unpackSnorm2x16 as its specification writes it: clamp(f / 32767.0, -1, +1).
inline vec2 unpackSnorm2x16(uint code) {
  const float x = float(int16_t(uint16_t(code & 0xFFFFu))), y = float(int16_t(uint16_t(code >> 16)));
  return clamp(vec2(x, y) / 32767.0f, -1.0f, 1.0f);
}

inline vec3 decodeOctNormal(uint code) {
  vec2 e = unpackSnorm2x16(code);
  vec3 v = vec3(e.x, e.y, 1.0f - abs(e.x) - abs(e.y));
  if (v.z < 0.0f) {
    vec2 folded = vec2((1.0f - abs(v.y)) * (v.x >= 0.0f ? 1.0f : -1.0f), (1.0f - abs(v.x)) * (v.y >= 0.0f ? 1.0f : -1.0f));
    v.x = folded.x;
    v.y = folded.y;
  }
  return normalize(v);
}

inline vec3 flatNormal(vec3 v0, vec3 v1, vec3 v2) {
  vec3 n = cross(v1 - v0, v2 - v0);
  float len = length(n);
  return len > 0.0f && !std::isinf(len) ? n / len : vec3(0.0f, 0.0f, 1.0f);
}

inline void loadAttributes(const Storage& s, int tri, vec2 bary, vec3& normal, vec2& uv) {
  uvec4 index = fetchTriangle(s, tri);
  uvec4 p0 = fetchVertex(s, int(index.x));
  uvec4 p1 = fetchVertex(s, int(index.y));
  uvec4 p2 = fetchVertex(s, int(index.z));
  vec3 geometric = vec3(0.0f);
  if (p0.w == kFlatNormal || p1.w == kFlatNormal || p2.w == kFlatNormal)
    geometric = flatNormal(uintBitsToFloat(uvec3(p0)), uintBitsToFloat(uvec3(p1)), uintBitsToFloat(uvec3(p2)));
  vec3 n0 = p0.w == kFlatNormal ? geometric : decodeOctNormal(p0.w);
  vec3 n1 = p1.w == kFlatNormal ? geometric : decodeOctNormal(p1.w);
  vec3 n2 = p2.w == kFlatNormal ? geometric : decodeOctNormal(p2.w);
  vec2 uv0 = glm::unpackHalf2x16(vertexWords(s, index.x).x);
  vec2 uv1 = glm::unpackHalf2x16(vertexWords(s, index.y).x);
  vec2 uv2 = glm::unpackHalf2x16(vertexWords(s, index.z).x);
  float w = 1.0f - bary.x - bary.y;
  normal = w * n0 + bary.x * n1 + bary.y * n2;
  uv = w * uv0 + bary.x * uv1 + bary.y * uv2;
}

}  // namespace bvhlab::glsl::indexed
