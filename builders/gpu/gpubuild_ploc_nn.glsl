// ploc-gpu, a clustering pass, step 1: every cluster's nearest neighbour among the clusters within
// +-u_radius in the current order, as builders/ploc.cpp defines it: the candidate with the smallest
// key (gpubuild_ploc_pairs.glsl's candidateKey, compiled ahead of this module).
// Up to radius kHalo the workgroup first copies the boxes of its 256 clusters and of the radius on
// either side into shared memory (each box is read by up to 2 * radius + 1 invocations); larger radii
// read the storage buffer. Both give the same keys.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Clusters { Cluster clusters[]; };
layout(std430, binding = 1) writeonly buffer Nearest { uint nearest[]; };
// The pass's cluster count (gpubuild_ploc_next.glsl writes it; the pass is dispatched indirectly).
layout(std430, binding = 7) readonly buffer PassState { uvec3 dispatchGroups; uint passClusters; };
uniform uint u_radius;

const uint kHalo = 128u;
shared vec3 s_lo[256u + 2u * kHalo], s_hi[256u + 2u * kHalo];  // 12 KiB

vec3 lowOf(uint i) { return vec3(clusters[i].box[0], clusters[i].box[1], clusters[i].box[2]); }
vec3 highOf(uint i) { return vec3(clusters[i].box[3], clusters[i].box[4], clusters[i].box[5]); }

void main() {
  uint x = gl_GlobalInvocationID.x, t = gl_LocalInvocationID.x;
  bool tiled = u_radius <= kHalo;  // the same for the whole dispatch: barrier() stays in uniform flow
  // Shared slot s holds cluster first + s.
  uint base = gl_WorkGroupID.x * 256u, first = base - min(base, u_radius);
  if (tiled) {
    uint span = min(passClusters, base + 256u + u_radius) - first;
    for (uint s = t; s < span; s += 256u) {
      s_lo[s] = lowOf(first + s);
      s_hi[s] = highOf(first + s);
    }
    barrier();
  }
  if (x >= passClusters) return;
  vec3 xlo = tiled ? s_lo[x - first] : lowOf(x), xhi = tiled ? s_hi[x - first] : highOf(x);
  uvec2 best = uvec2(0xffffffffu);
  uint found = x;
  uint from = x - min(x, u_radius), to = min(passClusters - 1u, x + u_radius);
  for (uint j = from; j <= to; ++j) {
    if (j == x) continue;
    vec3 jlo = tiled ? s_lo[j - first] : lowOf(j), jhi = tiled ? s_hi[j - first] : highOf(j);
    uvec2 key = candidateKey(x, j, xlo, xhi, jlo, jhi);
    if (less(key, best)) { best = key; found = j; }
  }
  nearest[x] = found;
}
