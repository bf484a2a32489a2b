// GPU pack, step 2's gate, after each jumping round (one invocation): the round just dispatched wrote
// half u_wrote of the buffers; if some node still has an ancestor the next round runs, else its
// dispatch and every later one get 0 workgroups. `finalHalf` names the half that holds the finished sums.
layout(local_size_x = 1) in;
layout(std430, binding = 2) buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };
uniform uint u_wrote;

void main() {
  if (dispatchGroups.x == 0u) return;  // the rounds are over
  finalHalf = u_wrote;
  if (unfinished == 0u) dispatchGroups.x = 0u;
  unfinished = 0u;
}
