// lbvh-gpu, morton phase 3: the 63-bit codes of builders/morton.hpp (no size bits), as (hi, lo)
// halves beside the primitive's index. q = min((c - min) * scale, 2^21 - 1) in float, each operation
// correctly rounded (GLSL's + - *; `precise` forbids fused multiply-adds), then truncated as the CPU
// truncates: the same cells.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Centroids { float centroids[]; };
layout(std430, binding = 1) readonly buffer Grid { float grid[6]; };
struct Key { uint hi, lo, id; };
layout(std430, binding = 2) writeonly buffer Keys { Key keys[]; };
uniform uint u_count;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= u_count) return;
  const float top = 2097151.0;  // 2^21 - 1
  precise vec3 c = vec3(centroids[3u * i], centroids[3u * i + 1u], centroids[3u * i + 2u]);
  precise vec3 q = (c - vec3(grid[0], grid[1], grid[2])) * vec3(grid[3], grid[4], grid[5]);
  q = min(q, vec3(top));
  uvec3 cell = uvec3(q);
  uint hi = 0u, lo = 0u;
  for (uint k = 0u; k < 21u; ++k) {  // bit k of x, y, z to code bits 3k + 2, 3k + 1, 3k
    for (uint a = 0u; a < 3u; ++a) {
      uint bit = (cell[a] >> k) & 1u, at = 3u * k + 2u - a;
      if (at < 32u) lo |= bit << at;
      else hi |= bit << (at - 32u);
    }
  }
  keys[i] = Key(hi, lo, i);
}
