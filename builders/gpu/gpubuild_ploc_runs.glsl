// ploc-gpu, clusters phase 1: the full tree's leaves and the runs of equal Morton codes. Leaf k (sorted
// position k) is node n - 1 + k with its primitive's box. Each workgroup counts the runs that start in
// its 256 positions (sums[block]; sums[blocks + block] = 0), for the exclusive scan
// (gpubuild_scan.glsl) that numbers the runs: a run is one initial cluster (builders/ploc.cpp, step 1).
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 1) readonly buffer Boxes { float boxes[]; };  // min xyz, max xyz per primitive
layout(std430, binding = 2) writeonly buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 3) writeonly buffer Sums { uint sums[]; };
uniform uint u_count;

shared uint s_runs;

void main() {
  uint t = gl_LocalInvocationID.x, k = gl_GlobalInvocationID.x;
  uint block = gl_WorkGroupID.x, blocks = gl_NumWorkGroups.x;
  if (t == 0u) s_runs = 0u;
  barrier();
  if (k < u_count) {
    uint node = u_count - 1u + k, prim = keys[k].id;
    for (uint c = 0u; c < 6u; ++c) nodeBoxes[6u * node + c] = boxes[6u * prim + c];
    if (k == 0u || keys[k].hi != keys[k - 1u].hi || keys[k].lo != keys[k - 1u].lo) atomicAdd(s_runs, 1u);
  }
  barrier();
  if (t == 0u) {
    sums[block] = s_runs;
    sums[blocks + block] = 0u;
  }
}
