// GPU builders, phase `boxes` of a build from triangles already on the GPU (an animated clip's frame,
// builders/gpu/gpu_pack.hpp GpuPackRequest::boxesFromSoup): each triangle's box and centroid from its
// vertices in the soup's texels (7 per triangle; texels 0..2 hold v0, v1, v2 as float bits), as the CPU
// makes them (builders/refit.hpp triangleBox, builders/update_base.cpp): the box grown from +-infinity
// by glm's min/max (y < x ? y : x, x < y ? y : x; GLSL's min/max leave the sign of an equal zero
// open), the centroid 0.5 * min + 0.5 * max under `precise` (no fused multiply-add). Bit for bit the
// CPU's boxes, so the tree is the one the host-input build gives. Vertices are checked finite on the
// CPU before the build (validateBuildInput), so no NaN reaches a comparison here.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Soup { uvec4 soup[]; };
layout(std430, binding = 1) writeonly buffer Boxes { float boxes[]; };       // min xyz, max xyz per primitive
layout(std430, binding = 2) writeonly buffer Centroids { float centroids[]; };  // x, y, z per primitive
uniform uint u_count;

vec3 minOf(vec3 x, vec3 y) { return vec3(y.x < x.x ? y.x : x.x, y.y < x.y ? y.y : x.y, y.z < x.z ? y.z : x.z); }
vec3 maxOf(vec3 x, vec3 y) { return vec3(x.x < y.x ? y.x : x.x, x.y < y.y ? y.y : x.y, x.z < y.z ? y.z : x.z); }

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= u_count) return;
  vec3 lo = vec3(uintBitsToFloat(0x7f800000u)), hi = -lo;  // +infinity, -infinity (Aabb's empty box)
  for (uint v = 0u; v < 3u; ++v) {
    vec3 p = uintBitsToFloat(soup[7u * i + v].xyz);
    lo = minOf(lo, p);
    hi = maxOf(hi, p);
  }
  precise vec3 c = 0.5 * lo + 0.5 * hi;
  for (uint a = 0u; a < 3u; ++a) {
    boxes[6u * i + a] = lo[a];
    boxes[6u * i + 3u + a] = hi[a];
    centroids[3u * i + a] = c[a];
  }
}
