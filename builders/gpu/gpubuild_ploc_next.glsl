// ploc-gpu, a clustering pass, step 4: the next pass's cluster count and workgroups, computed on the
// GPU so that the passes follow one another by indirect dispatch (glDispatchComputeIndirect) without
// the CPU reading anything back. The host issues passes in batches and reads this state once per batch
// (builders/gpu/gpu_ploc.cpp); a pass issued after the last one finds 0 workgroups and does nothing.
//   dispatchGroups  the indirect dispatch of nn, count and merge: (workgroups of 256 clusters, 1, 1),
//                   0 workgroups once one cluster is left or a pass merged none
//   passClusters    the clusters the next pass starts from
//   passes          the passes that ran (that merged)
//   stuck           1 when a pass merged no pair: impossible for correct passes (the smallest key in a
//                   window is mutual, builders/ploc.cpp); the host reports it as an error
layout(local_size_x = 1) in;
layout(std430, binding = 0) readonly buffer Sums { uint sums[]; };  // scanned: kept, then merged
layout(std430, binding = 7) buffer PassState { uvec3 dispatchGroups; uint passClusters; uint passes; uint stuck; };
// Nonzero for the first state, after the runs: the clusters are sums[u_first] (u_first = the runs'
// workgroups). Zero after a clustering pass: the clusters it kept are sums[its workgroups].
uniform uint u_first;

void main() {
  uint kept;
  if (u_first != 0u) {
    kept = sums[u_first];
  } else {
    if (dispatchGroups.x == 0u) return;  // past the last pass
    kept = sums[dispatchGroups.x];
    passes += 1u;
    if (kept >= passClusters) {
      stuck = 1u;
      dispatchGroups = uvec3(0u, 1u, 1u);
      return;
    }
  }
  passClusters = kept;
  dispatchGroups = uvec3(kept > 1u ? (kept + 255u) / 256u : 0u, 1u, 1u);
}
