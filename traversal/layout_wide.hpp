// layout_wide.hpp (traversal) — C++ mirror of layout_wide.glsl: decodes a bvh4 / bvh8 slot
// (layout/layout_wide.hpp, where kWideInner comes from).
#pragma once
#include "layout/layout_wide.hpp"
#include "traversal/layout.hpp"

namespace bvhlab::glsl {

inline void decodeSlot(uvec4 lo, uvec4 hi, vec3& bmin, vec3& bmax, uint& link, uint& count) {
  bmin = uintBitsToFloat(uvec3(lo));
  bmax = uintBitsToFloat(uvec3(hi));
  link = lo.w;
  count = hi.w;
}

inline void loadSlot(const Storage& s, uint texel, vec3& bmin, vec3& bmax, uint& link, uint& count) {
  decodeSlot(fetchNode(s, int(texel)), fetchNode(s, int(texel) + 1), bmin, bmax, link, count);
}

}  // namespace bvhlab::glsl
