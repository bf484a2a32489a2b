// layout.glsl — decodes layout v1's NODE stream; the layout itself is described once, in
// layout/layout.hpp. Needs a storage module (fetchNode). The triangle streams are decoded by the
// triangle format's module (traversal/triangles_*.glsl, layout/triangle_formats.hpp).
// C++ mirror: layout.hpp (this folder).
const uint kEscapeEnd = 0x0FFFFFFFu;  // = bvhlab::kEscapeEnd
const uint kIndexMask = 0x0FFFFFFFu;  // = bvhlab::kIndexMask

// Node `node` (stream order, root = 0). a: second child (inner) or first triangle (leaf);
// escape: the node after this subtree in depth-first order, or kEscapeEnd; count: 0 for an inner
// node, else the leaf's triangle count. The first child of an inner node is node + 1.
void loadNode(int node, out vec3 bmin, out vec3 bmax, out uint a, out uint escape, out uint count) {
  uvec4 minTexel = fetchNode(2 * node + 0);
  uvec4 maxTexel = fetchNode(2 * node + 1);
  bmin = uintBitsToFloat(minTexel.xyz);
  bmax = uintBitsToFloat(maxTexel.xyz);
  a = minTexel.w & kIndexMask;
  escape = maxTexel.w & kIndexMask;
  count = (minTexel.w >> 28) | ((maxTexel.w >> 28) << 4);
}
