// layout_wide.glsl — decodes the NODE stream of layouts bvh4 and bvh8, described once in
// layout/layout_wide.hpp (one module for both widths: a record's child count comes with the slot that
// points at it). Needs a storage module (fetchNode); the TRIANGLE and ATTRIBUTE streams are v1's and
// layout.glsl decodes them. C++ mirror: layout_wide.hpp (this folder).
const uint kWideInner = 0x80000000u;  // = bvhlab::kWideInner: count >= this marks an inner child

// The slot at NODE texel `texel` (0: the root slot; a record's child c at link + 2c). count <
// kWideInner: a leaf of count triangles from triangle link; otherwise an inner node whose record of
// count - kWideInner slots starts at texel link.
// decodeSlot: the same from the slot's two texels, already fetched (the fetch-whole kernels).
void decodeSlot(uvec4 lo, uvec4 hi, out vec3 bmin, out vec3 bmax, out uint link, out uint count) {
  bmin = uintBitsToFloat(lo.xyz);
  bmax = uintBitsToFloat(hi.xyz);
  link = lo.w;
  count = hi.w;
}

void loadSlot(uint texel, out vec3 bmin, out vec3 bmax, out uint link, out uint count) {
  decodeSlot(fetchNode(int(texel)), fetchNode(int(texel) + 1), bmin, bmax, link, count);
}
