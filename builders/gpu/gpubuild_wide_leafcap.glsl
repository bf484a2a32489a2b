// GPU pack into cwbvh, step 1: the leaf cap of the wide collapse (layout/collapse_v1.cpp): the largest
// leaf of the collapsed binary tree, by atomicMax into the wide state's leafCap (the host starts it at
// 1, as the CPU does). A leaf of the collapsed tree is a node that emits no inner node (info's second
// word 0) under a parent that does (or the root).
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Parents { uint parents[]; };
layout(std430, binding = 1) readonly buffer Info { uint info[]; };  // count, inner per node
layout(std430, binding = 2) buffer WideStateBuffer { WideState state; };  // gpubuild_wide_state.glsl
uniform uint u_nodes;  // 2n - 1

void main() {
  uint x = gl_GlobalInvocationID.x;
  if (x >= u_nodes || info[2u * x + 1u] != 0u) return;
  uint p = parents[x];
  if (p == 0xffffffffu || info[2u * p + 1u] != 0u) atomicMax(state.leafCap, info[2u * x]);
}
