// layout_cwbvh.hpp (traversal) — C++ mirror of layout_cwbvh.glsl: decodes a cwbvh node
// (layout/layout_cwbvh.hpp, where kCwbvhMetaInner comes from).
#pragma once
#include "layout/layout_cwbvh.hpp"
#include "traversal/layout.hpp"

namespace bvhlab::glsl {

struct CwNode {
  vec3 p;
  vec3 scale;
  uint k;
  uint childBase;
  uint triBase;
  uvec2 meta;
  uvec4 q0, q1, q2;
};

inline CwNode loadCwNode(const Storage& s, uint node) {
  int texel = 5 * int(node);
  uvec4 t0 = fetchNode(s, texel);
  uvec4 t1 = fetchNode(s, texel + 1);
  CwNode n;
  n.p = uintBitsToFloat(uvec3(t0));
  n.scale = uintBitsToFloat(((uvec3(t0.w, t0.w >> 8, t0.w >> 16) & 0xFFu) << 23u));
  n.k = t0.w >> 24;
  n.childBase = t1.x;
  n.triBase = t1.y;
  n.meta = uvec2(t1.z, t1.w);
  n.q0 = fetchNode(s, texel + 2);
  n.q1 = fetchNode(s, texel + 3);
  n.q2 = fetchNode(s, texel + 4);
  return n;
}

inline void cwbvhGridBox(const Storage& s, uint node, vec3& bmin, vec3& bmax) {
  uvec4 t0 = fetchNode(s, 5 * int(node));
  bmin = uintBitsToFloat(uvec3(t0));
  bmax = bmin + vec3(255.0f) * uintBitsToFloat(((uvec3(t0.w, t0.w >> 8, t0.w >> 16) & 0xFFu) << 23u));
}

inline uint cwbvhByte(uvec2 bytes, uint c) { return ((c < 4u ? bytes.x : bytes.y) >> (8u * (c & 3u))) & 0xFFu; }

inline uint cwbvhMeta(const CwNode& n, uint c) { return cwbvhByte(n.meta, c); }

inline void cwbvhChildBox(const CwNode& n, uint c, vec3& bmin, vec3& bmax) {
  uvec3 lo = uvec3(cwbvhByte(uvec2(n.q0.x, n.q0.y), c), cwbvhByte(uvec2(n.q0.z, n.q0.w), c),
                   cwbvhByte(uvec2(n.q1.x, n.q1.y), c));
  uvec3 hi = uvec3(cwbvhByte(uvec2(n.q1.z, n.q1.w), c), cwbvhByte(uvec2(n.q2.x, n.q2.y), c),
                   cwbvhByte(uvec2(n.q2.z, n.q2.w), c));
  bmin = n.p + vec3(lo) * n.scale;
  bmax = n.p + vec3(hi) * n.scale;
}

}  // namespace bvhlab::glsl
