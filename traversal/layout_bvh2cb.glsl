// layout_bvh2cb.glsl — decodes the NODE stream of layout bvh2-cb, described once in
// layout/layout_bvh2cb.hpp. Needs a storage module (fetchNode); the TRIANGLE and ATTRIBUTE streams
// are v1's and layout.glsl decodes them. C++ mirror: layout_bvh2cb.hpp (this folder).
const uint kBvh2cbInner = 0xFFFFFFFFu;  // = bvhlab::kBvh2cbInner: a slot's count for an inner child

// Record `node` (root = 0): both children's boxes, links and counts. count == kBvh2cbInner: the
// child is inner and link is its record; otherwise a leaf of count triangles from triangle link.
void loadRecord(int node, out vec3 aMin, out vec3 aMax, out uint aLink, out uint aCount,
                out vec3 bMin, out vec3 bMax, out uint bLink, out uint bCount) {
  uvec4 t0 = fetchNode(4 * node + 0);
  uvec4 t1 = fetchNode(4 * node + 1);
  uvec4 t2 = fetchNode(4 * node + 2);
  uvec4 t3 = fetchNode(4 * node + 3);
  aMin = uintBitsToFloat(t0.xyz);
  aMax = uintBitsToFloat(t1.xyz);
  bMin = uintBitsToFloat(t2.xyz);
  bMax = uintBitsToFloat(t3.xyz);
  aLink = t0.w;
  aCount = t1.w;
  bLink = t2.w;
  bCount = t3.w;
}
