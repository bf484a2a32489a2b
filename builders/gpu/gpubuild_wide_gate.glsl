// GPU pack into cwbvh, step 3's gate, after each level (one invocation): the entries the level
// appended become the next level, dispatched with one invocation each; once a level appends none, the
// level dispatches that remain get 0 workgroups, the wide tree's depth is known (levels, plus 1 for the
// leaf children: PackedBvh::depth), and the pointer jumping and the node pass get their workgroups.
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer WideStateBuffer { WideState state; };  // gpubuild_wide_state.glsl
layout(std430, binding = 1) buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };

void main() {
  if (state.levelGroups.x == 0u) return;  // the levels are over
  ++state.levels;
  state.levelBegin = state.levelEnd;
  state.levelEnd = state.queued;
  uint groups = (state.levelEnd - state.levelBegin + 255u) / 256u;
  state.levelGroups.x = groups;
  if (groups == 0u) {
    uint all = (state.queued + 255u) / 256u;
    state.nodeGroups = uvec3(all, 1u, 1u);
    dispatchGroups = uvec3(all, 1u, 1u);
    depth = state.levels + 1u;
  }
}
