// ploc-gpu, a clustering pass, step 2: mutual nearest neighbours merge (builders/ploc.cpp). Per
// workgroup of 256 clusters: how many clusters the pass keeps (each unpaired one, and each pair once,
// at its lower position) into sums[block], and how many pairs merge into sums[blocks + block], for
// one exclusive scan (gpubuild_scan.glsl) of both.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Nearest { uint nearest[]; };
layout(std430, binding = 1) writeonly buffer Sums { uint sums[]; };
// The pass's cluster count (gpubuild_ploc_next.glsl writes it; the pass is dispatched indirectly).
layout(std430, binding = 7) readonly buffer PassState { uvec3 dispatchGroups; uint passClusters; };

shared uint s_kept, s_merged;

void main() {
  uint t = gl_LocalInvocationID.x, x = gl_GlobalInvocationID.x;
  uint block = gl_WorkGroupID.x, blocks = gl_NumWorkGroups.x;
  if (t == 0u) s_kept = 0u, s_merged = 0u;
  barrier();
  if (x < passClusters) {
    uint y = nearest[x];
    bool mutual = nearest[y] == x;
    if (!mutual || x < y) atomicAdd(s_kept, 1u);
    if (mutual && x < y) atomicAdd(s_merged, 1u);
  }
  barrier();
  if (t == 0u) {
    sums[block] = s_kept;
    sums[blocks + block] = s_merged;
  }
}
