// layout_wide.hpp (traversal) — C++ mirror of layout_wide.glsl: decodes a bvh4 / bvh8 slot
// (layout/layout_wide.hpp, where kWideInner comes from).
#pragma once
#include "layout/layout_wide.hpp"
#include "traversal/layout.hpp"

namespace bvhlab::glsl {

inline void loadSlot(const Storage& s, uint texel, vec3& bmin, vec3& bmax, uint& link, uint& count) {
  uvec4 lo = fetchNode(s, int(texel));
  uvec4 hi = fetchNode(s, int(texel) + 1);
  bmin = uintBitsToFloat(uvec3(lo));
  bmax = uintBitsToFloat(uvec3(hi));
  link = lo.w;
  count = hi.w;
}

}  // namespace bvhlab::glsl
