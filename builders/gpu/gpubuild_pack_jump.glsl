// GPU pack, step 2, one round of pointer jumping (Wyllie's list ranking, on the paths of a tree): each
// node adds its ancestor's sum to its own and takes its ancestor's ancestor, so after k rounds a node
// holds the sum of up to 2^k steps above it, and after ceil(log2(depth)) rounds the sum of its whole
// path (gpubuild_pack_edges.glsl). Reads one half of the buffers (u_from) and writes the other (no
// node reads a value written in the same round). Dispatched indirectly: gpubuild_pack_gate.glsl stops the rounds once
// no node has an ancestor left.
layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Steps { uvec4 steps[]; };          // two halves of u_nodes
layout(std430, binding = 1) buffer Ancestors { uint ancestors[]; };  // likewise
layout(std430, binding = 2) buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };
uniform uint u_nodes;
uniform uint u_from;  // the half read: 0 or 1

const uint kNone = 0xffffffffu;
const uint kHidden = 0x80000000u;

void main() {
  uint x = gl_GlobalInvocationID.x;
  if (x >= u_nodes) return;
  uint from = u_from * u_nodes, to = (1u - u_from) * u_nodes;
  uvec4 s = steps[from + x];
  uint a = ancestors[from + x];
  if (a != kNone) {
    uvec4 above = steps[from + a];
    s = uvec4(s.xyz + above.xyz, ((s.w & ~kHidden) + (above.w & ~kHidden)) | ((s.w | above.w) & kHidden));
    a = ancestors[from + a];
    if (a != kNone) unfinished = 1u;  // every writer writes 1: no race on the value
  }
  steps[to + x] = s;
  ancestors[to + x] = a;
}
