// Exclusive prefix sum of u_count uints in place, in one workgroup: each invocation sums its
// contiguous segment, the 256 sums are scanned in shared memory (Hillis-Steele), then each invocation
// writes its segment's running sums. Used for the radix sort's digit counts (256 x blocks entries).
// COUNT_FROM_PASS_STATE (ploc-gpu's clustering passes): the count is the 2 x workgroups of the pass
// that wrote the values (gpubuild_ploc_next.glsl's state), not a uniform: no CPU round trip.
layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Values { uint values[]; };
#ifdef COUNT_FROM_PASS_STATE
layout(std430, binding = 7) readonly buffer PassState { uvec3 dispatchGroups; uint passClusters; };
uint valueCount() { return 2u * dispatchGroups.x; }
#else
uniform uint u_count;
uint valueCount() { return u_count; }
#endif

shared uint s_sum[256];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint count = valueCount();
  uint per = (count + 255u) / 256u, begin = min(t * per, count), end = min(begin + per, count);
  uint sum = 0u;
  for (uint i = begin; i < end; ++i) sum += values[i];
  s_sum[t] = sum;
  barrier();
  for (uint step = 1u; step < 256u; step <<= 1u) {
    uint add = t >= step ? s_sum[t - step] : 0u;
    barrier();
    s_sum[t] += add;
    barrier();
  }
  uint running = s_sum[t] - sum;  // exclusive
  for (uint i = begin; i < end; ++i) {
    uint v = values[i];
    values[i] = running;
    running += v;
  }
}
