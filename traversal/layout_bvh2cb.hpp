// layout_bvh2cb.hpp (traversal) — C++ mirror of layout_bvh2cb.glsl: decodes a bvh2-cb record
// (layout/layout_bvh2cb.hpp, where kBvh2cbInner comes from).
#pragma once
#include "layout/layout_bvh2cb.hpp"
#include "traversal/layout.hpp"

namespace bvhlab::glsl {

inline void loadRecord(const Storage& s, int node, vec3& aMin, vec3& aMax, uint& aLink, uint& aCount, vec3& bMin,
                       vec3& bMax, uint& bLink, uint& bCount) {
  uvec4 t0 = fetchNode(s, 4 * node + 0);
  uvec4 t1 = fetchNode(s, 4 * node + 1);
  uvec4 t2 = fetchNode(s, 4 * node + 2);
  uvec4 t3 = fetchNode(s, 4 * node + 3);
  aMin = uintBitsToFloat(uvec3(t0));
  aMax = uintBitsToFloat(uvec3(t1));
  bMin = uintBitsToFloat(uvec3(t2));
  bMax = uintBitsToFloat(uvec3(t3));
  aLink = t0.w;
  aCount = t1.w;
  bLink = t2.w;
  bCount = t3.w;
}

}  // namespace bvhlab::glsl
