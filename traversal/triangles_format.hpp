// triangles_format.hpp — the mirrors' triangle accessors in the tree's triangle format
// (layout/triangle_formats.hpp): where the shader assembler links one triangles_<format>.glsl, the
// mirror switches on Storage::triangles. testTriangle, which also needs the triangle test, is
// Tests::testTriangle (traversal/intersectors.hpp).
#pragma once
#include "traversal/storage.hpp"
#include "traversal/triangles_indexed.hpp"
#include "traversal/triangles_precomputed.hpp"
#include "traversal/triangles_raw.hpp"

namespace bvhlab::glsl {

// Bytes one Tests::testTriangle fetches in the tree's triangle format, texel by texel as its module
// reads them: raw 3 vertex texels; precomputed v0, two edges and the normal (4 texels); indexed the
// index texel, then its 3 VERTEX texels (4 texels; shared vertices are fetched again per triangle,
// as the GLSL does). Hit attributes (loadAttributes) are fetched after traversal, not counted here.
inline uint triangleTestBytes(const Storage& s) {
  switch (s.triangles) {
    case TriangleFormat::Precomputed: return bvhlab::kPrecomputedTriangleTexels * kTexelBytes;
    case TriangleFormat::Indexed: return (bvhlab::kIndexedTriangleTexels + 3u * bvhlab::kVertexTexels) * kTexelBytes;
    default: return bvhlab::kTriangleTexels * kTexelBytes;
  }
}

inline void loadTriangle(const Storage& s, int tri, vec3& v0, vec3& v1, vec3& v2) {
  switch (s.triangles) {
    case TriangleFormat::Precomputed: return precomputed::loadTriangle(s, tri, v0, v1, v2);
    case TriangleFormat::Indexed: return indexed::loadTriangle(s, tri, v0, v1, v2);
    default: return raw::loadTriangle(s, tri, v0, v1, v2);
  }
}

inline void loadTriangleIds(const Storage& s, int tri, uint& primitive, uint& material, uint& mesh) {
  switch (s.triangles) {
    case TriangleFormat::Precomputed: return precomputed::loadTriangleIds(s, tri, primitive, material, mesh);
    case TriangleFormat::Indexed: return indexed::loadTriangleIds(s, tri, primitive, material, mesh);
    default: return raw::loadTriangleIds(s, tri, primitive, material, mesh);
  }
}

inline void loadAttributes(const Storage& s, int tri, vec2 bary, vec3& normal, vec2& uv) {
  switch (s.triangles) {
    case TriangleFormat::Precomputed: return precomputed::loadAttributes(s, tri, bary, normal, uv);
    case TriangleFormat::Indexed: return indexed::loadAttributes(s, tri, bary, normal, uv);
    default: return raw::loadAttributes(s, tri, bary, normal, uv);
  }
}

}  // namespace bvhlab::glsl
