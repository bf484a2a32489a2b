// ploc-gpu, a clustering pass, step 3: the next order of clusters, compacted. A cluster whose
// nearest neighbour is not mutual is copied; a mutual pair becomes one inner node at the lower
// position (left child the lower one, the box their union: gpubuild_ploc_pairs.glsl). Positions and
// node numbers come from the scanned counts of step 2 plus a scan within the workgroup: the pass's
// merges take the inner nodes m - 2, m - 3, .. in order, m = passClusters (the CPU's numbering; one
// cluster is made from m by m - 1 merges, so node 0, the root, comes last).
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Clusters { Cluster clusters[]; };
layout(std430, binding = 1) readonly buffer Nearest { uint nearest[]; };
layout(std430, binding = 2) readonly buffer Sums { uint sums[]; };  // scanned: kept, then merged
layout(std430, binding = 3) writeonly buffer Next { Cluster next[]; };
layout(std430, binding = 4) writeonly buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 5) writeonly buffer Children { uint children[]; };
layout(std430, binding = 6) writeonly buffer Parents { uint parents[]; };
// The pass's cluster count (gpubuild_ploc_next.glsl writes it; the pass is dispatched indirectly).
layout(std430, binding = 7) readonly buffer PassState { uvec3 dispatchGroups; uint passClusters; };

shared uvec2 s_scan[256];  // kept, merged

void main() {
  uint t = gl_LocalInvocationID.x, x = gl_GlobalInvocationID.x;
  uint block = gl_WorkGroupID.x, blocks = gl_NumWorkGroups.x;
  uint y = x;
  bool kept = false, merged = false;
  if (x < passClusters) {
    y = nearest[x];
    bool mutual = nearest[y] == x;
    kept = !mutual || x < y;
    merged = mutual && x < y;
  }
  uvec2 mine = uvec2(kept ? 1u : 0u, merged ? 1u : 0u);
  s_scan[t] = mine;
  barrier();
  for (uint step = 1u; step < 256u; step <<= 1u) {
    uvec2 add = t >= step ? s_scan[t - step] : uvec2(0u);
    barrier();
    s_scan[t] += add;
    barrier();
  }
  if (!kept) return;
  uvec2 before = s_scan[t] - mine;
  uint at = sums[block] + before.x;
  if (!merged) {
    next[at] = clusters[x];
    return;
  }
  // sums[blocks] is the total kept: the merges' scan continues from it.
  uint node = passClusters - 2u - (sums[blocks + block] - sums[blocks] + before.y);
  Cluster c = mergedCluster(clusters[x], clusters[y], node);
  next[at] = c;
  for (uint a = 0u; a < 6u; ++a) nodeBoxes[6u * node + a] = c.box[a];
  uint l = clusters[x].node, r = clusters[y].node;
  children[2u * node] = l;
  children[2u * node + 1u] = r;
  parents[l] = node;
  parents[r] = node;
}
