// ploc-gpu, a clustering pass, step 1: every cluster's nearest neighbour among the clusters within
// +-u_radius in the current order, as builders/ploc.cpp defines it: the candidate with the smallest
// key (merged half area, then the pair's tie key: distance, the lower position's parity, the side).
// The merged area as the CPU computes it: extents max - min, then (x y + y z) + z x, each operation
// rounded on its own (`precise`: no fused multiply-add). A zero area counts as +0 (the CPU's "+ 0.0f":
// min and max of -0 and +0 may give either sign, and -0's bits would rank above every area).
layout(local_size_x = 256) in;
struct Cluster { float box[6]; uint node; };
layout(std430, binding = 0) readonly buffer Clusters { Cluster clusters[]; };
layout(std430, binding = 1) writeonly buffer Nearest { uint nearest[]; };
uniform uint u_count;  // clusters (>= 2)
uniform uint u_radius;

// (area bits, tie key): compared as a 64-bit number, high word first.
uvec2 candidateKey(uint x, uint j) {
  precise float ex = max(clusters[x].box[3], clusters[j].box[3]) - min(clusters[x].box[0], clusters[j].box[0]);
  precise float ey = max(clusters[x].box[4], clusters[j].box[4]) - min(clusters[x].box[1], clusters[j].box[1]);
  precise float ez = max(clusters[x].box[5], clusters[j].box[5]) - min(clusters[x].box[2], clusters[j].box[2]);
  precise float area = (ex * ey + ey * ez) + ez * ex;
  uint d = x > j ? x - j : j - x, lower = min(x, j);
  return uvec2(area == 0.0 ? 0u : floatBitsToUint(area), 4u * d + 2u * (lower & 1u) + (j > x ? 1u : 0u));
}

bool less(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

void main() {
  uint x = gl_GlobalInvocationID.x;
  if (x >= u_count) return;
  uvec2 best = uvec2(0xffffffffu);
  uint found = x;
  uint from = x - min(x, u_radius), to = min(u_count - 1u, x + u_radius);
  for (uint j = from; j <= to; ++j) {
    if (j == x) continue;
    uvec2 key = candidateKey(x, j);
    if (less(key, best)) { best = key; found = j; }
  }
  nearest[x] = found;
}
