// layout.hpp (traversal) — C++ mirror of layout.glsl: decodes layout v1's NODE stream described in
// layout/layout.hpp (kEscapeEnd and kIndexMask come from there). The triangle streams' decoders
// (loadTriangle, loadTriangleIds, loadAttributes, in the tree's triangle format) come with it.
#pragma once
#include "traversal/storage.hpp"
#include "traversal/triangles_format.hpp"

namespace bvhlab::glsl {

inline void loadNode(const Storage& s, int node, vec3& bmin, vec3& bmax, uint& a, uint& escape, uint& count) {
  uvec4 minTexel = fetchNode(s, 2 * node + 0);
  uvec4 maxTexel = fetchNode(s, 2 * node + 1);
  bmin = uintBitsToFloat(uvec3(minTexel));
  bmax = uintBitsToFloat(uvec3(maxTexel));
  a = minTexel.w & kIndexMask;
  escape = maxTexel.w & kIndexMask;
  count = (minTexel.w >> 28) | ((maxTexel.w >> 28) << 4);
}

}  // namespace bvhlab::glsl
