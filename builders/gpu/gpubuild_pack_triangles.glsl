// GPU pack, step 4: every leaf of the full tree writes its triangle's 3 TRIANGLE and 4 ATTRIBUTE texels
// (layout/layout.hpp, the raw format, which v1 and bvh2-cb share) at its position in the leaf order
// (the path sum .z of gpubuild_pack_jump.glsl), copied from the soup's texels, 7 per triangle in
// original order (builders/gpu/gpu_pack.cpp): the streams layout/pack.cpp writes for the same tree.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };  // sorted (hi, lo, id)
layout(std430, binding = 1) readonly buffer Steps { uvec4 steps[]; };
layout(std430, binding = 2) readonly buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };
layout(std430, binding = 3) readonly buffer Soup { uvec4 soup[]; };
layout(std430, binding = 4) writeonly buffer TriangleStream { uvec4 triangleStream[]; };
layout(std430, binding = 5) writeonly buffer AttributeStream { uvec4 attributeStream[]; };
uniform uint u_count;  // primitives n: leaves n - 1 + k, k the sorted position

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= u_count) return;
  uint nodes = 2u * u_count - 1u, leaf = u_count - 1u + k;
  uint id = keys[3u * k + 2u], at = steps[finalHalf * nodes + leaf].z;
  for (uint t = 0u; t < 3u; ++t) triangleStream[3u * at + t] = soup[7u * id + t];
  for (uint t = 0u; t < 4u; ++t) attributeStream[4u * at + t] = soup[7u * id + 3u + t];
}
