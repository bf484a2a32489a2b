// ploc-gpu, a clustering pass, step 1: every cluster's nearest neighbour among the clusters within
// +-u_radius in the current order, as builders/ploc.cpp defines it: the candidate with the smallest
// key (merged half area, then the pair's tie key: distance, the lower position's parity, the side).
// The merged area as the CPU computes it: extents max - min, then (x y + y z) + z x, each operation
// rounded on its own (`precise`: no fused multiply-add). A zero area counts as +0 (the CPU's "+ 0.0f":
// min and max of -0 and +0 may give either sign, and -0's bits would rank above every area).
// Up to radius kHalo the workgroup first copies the boxes of its 256 clusters and of the radius on
// either side into shared memory (each box is read by up to 2 * radius + 1 invocations); larger radii
// read the storage buffer. Both give the same keys.
layout(local_size_x = 256) in;
struct Cluster { float box[6]; uint node; };
layout(std430, binding = 0) readonly buffer Clusters { Cluster clusters[]; };
layout(std430, binding = 1) writeonly buffer Nearest { uint nearest[]; };
// The pass's cluster count (gpubuild_ploc_next.glsl writes it; the pass is dispatched indirectly).
layout(std430, binding = 7) readonly buffer PassState { uvec3 dispatchGroups; uint passClusters; };
uniform uint u_radius;

const uint kHalo = 128u;
shared vec3 s_lo[256u + 2u * kHalo], s_hi[256u + 2u * kHalo];  // 12 KiB

// (area bits, tie key): compared as a 64-bit number, high word first.
uvec2 candidateKey(uint x, uint j, vec3 xlo, vec3 xhi, vec3 jlo, vec3 jhi) {
  precise float ex = max(xhi.x, jhi.x) - min(xlo.x, jlo.x);
  precise float ey = max(xhi.y, jhi.y) - min(xlo.y, jlo.y);
  precise float ez = max(xhi.z, jhi.z) - min(xlo.z, jlo.z);
  precise float area = (ex * ey + ey * ez) + ez * ex;
  uint d = x > j ? x - j : j - x, lower = min(x, j);
  return uvec2(area == 0.0 ? 0u : floatBitsToUint(area), 4u * d + 2u * (lower & 1u) + (j > x ? 1u : 0u));
}

bool less(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

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
