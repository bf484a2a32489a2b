// layout_cwbvh.glsl — decodes the NODE stream of layout cwbvh, described once in layout/layout_cwbvh.hpp
// (Ylitie, Karras & Laine 2017's compressed 8-wide node). Needs a storage module (fetchNode); the
// triangle streams come with the triangle format's module. C++ mirror: layout_cwbvh.hpp (this folder).
const uint kCwbvhMetaInner = 0x80u;  // = bvhlab::kCwbvhMetaInner: a child's meta byte for an inner node

// One node's 5 texels, its grid decoded: p the origin, scale = 2^(e - 127) per axis; meta and the 48
// quantised bytes stay packed (cwbvhMeta and cwbvhChildBox take them out per child).
struct CwNode {
  vec3 p;
  vec3 scale;
  uint k;          // children, in slots 0 .. k - 1
  uint childBase;  // node index of the first inner child
  uint triBase;    // first triangle of the leaf children
  uvec2 meta;      // 8 meta bytes
  uvec4 q0, q1, q2;  // qlo.x, qlo.y | qlo.z, qhi.x | qhi.y, qhi.z: one uvec2 (8 bytes) per array
};

CwNode loadCwNode(uint node) {
  int texel = 5 * int(node);
  uvec4 t0 = fetchNode(texel);
  uvec4 t1 = fetchNode(texel + 1);
  CwNode n;
  n.p = uintBitsToFloat(t0.xyz);
  n.scale = uintBitsToFloat(((uvec3(t0.w, t0.w >> 8, t0.w >> 16) & 0xFFu) << 23));  // e in the float's exponent field
  n.k = t0.w >> 24;
  n.childBase = t1.x;
  n.triBase = t1.y;
  n.meta = t1.zw;
  n.q0 = fetchNode(texel + 2);
  n.q1 = fetchNode(texel + 3);
  n.q2 = fetchNode(texel + 4);
  return n;
}

// Node `node`'s whole grid, p .. p + 255 scale (only texel 0 fetched): it contains every child box the
// node decodes (the packer chose e so that it reaches the node's max; decoding is monotone in q).
void cwbvhGridBox(uint node, out vec3 bmin, out vec3 bmax) {
  uvec4 t0 = fetchNode(5 * int(node));
  bmin = uintBitsToFloat(t0.xyz);
  bmax = bmin + vec3(255.0) * uintBitsToFloat(((uvec3(t0.w, t0.w >> 8, t0.w >> 16) & 0xFFu) << 23));
}

// Byte c (0..7) of an array of 8 bytes held in two uints, little-endian.
uint cwbvhByte(uvec2 bytes, uint c) {
  return ((c < 4u ? bytes.x : bytes.y) >> (8u * (c & 3u))) & 0xFFu;
}

// Child c's meta: kCwbvhMetaInner, or its leaf's triangle count.
uint cwbvhMeta(CwNode n, uint c) {
  return cwbvhByte(n.meta, c);
}

// Child c's box: p + q * scale per axis. q * scale is exact (8 bits times a power of two), so the sum
// is rounded once, fused or not: the packer's conservative rounding holds for the decoded box.
void cwbvhChildBox(CwNode n, uint c, out vec3 bmin, out vec3 bmax) {
  uvec3 lo = uvec3(cwbvhByte(n.q0.xy, c), cwbvhByte(n.q0.zw, c), cwbvhByte(n.q1.xy, c));
  uvec3 hi = uvec3(cwbvhByte(n.q1.zw, c), cwbvhByte(n.q2.xy, c), cwbvhByte(n.q2.zw, c));
  bmin = n.p + vec3(lo) * n.scale;
  bmax = n.p + vec3(hi) * n.scale;
}
