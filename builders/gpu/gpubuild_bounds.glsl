// lbvh-gpu, morton phase 1: the bounds of the centroids, reduced through atomicMin/atomicMax on an
// order-preserving uint image of each float (min and max are exact: no rounding, any order).
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Centroids { float centroids[]; };  // x, y, z per primitive
layout(std430, binding = 1) buffer Bounds { uint boundKeys[6]; };             // min xyz, max xyz
uniform uint u_count;

// Monotonic: a < b (as floats, -0 below +0) exactly when key(a) < key(b).
uint orderedKey(float f) {
  uint u = floatBitsToUint(f);
  return (u & 0x80000000u) != 0u ? ~u : u | 0x80000000u;
}

shared uint s_keys[6];

void main() {
  uint t = gl_LocalInvocationID.x, i = gl_GlobalInvocationID.x;
  if (t < 3u) s_keys[t] = 0xffffffffu;
  else if (t < 6u) s_keys[t] = 0u;
  barrier();
  if (i < u_count) {
    for (uint a = 0u; a < 3u; ++a) {
      uint k = orderedKey(centroids[3u * i + a]);
      atomicMin(s_keys[a], k);
      atomicMax(s_keys[3u + a], k);
    }
  }
  barrier();
  if (t < 3u) atomicMin(boundKeys[t], s_keys[t]);
  else if (t < 6u) atomicMax(boundKeys[t], s_keys[t]);
}
