// The cwbvh pack's state (builders/gpu/gpu_pack_wide.cpp WideState, the same std430 layout), compiled
// ahead of each of its passes, which bind it as `buffer ... { WideState state; }`:
//   levelGroups   the next level's indirect dispatch (0 workgroups once the levels are over)
//   levelBegin, levelEnd   the level's queue entries; queued: every entry so far (atomicAdd)
//   leafCap       the collapsed tree's largest leaf (atomicMax; the host starts it at 1)
//   largestLeaf   the largest leaf slot past cwbvh's 127 triangles (0: none)
//   levels        the levels done
//   rootInfinite  1 where the root's half area overflows a float (the CPU's collapse refuses the tree)
//   nodeGroups    the node pass's indirect dispatch, set when the levels end
struct WideState {
  uvec3 levelGroups;
  uint levelBegin, levelEnd, queued, leafCap, largestLeaf, levels, rootInfinite, pad1, pad2;
  uvec3 nodeGroups;
  uint pad3;
};
