// GPU pack, step 1: every node's step from its parent, for the pointer jumping that follows
// (gpubuild_pack_jump.glsl). A node's place in the packed streams is the sum of the steps on its path
// from the root (the depth-first pre-order of the collapsed tree, left child first, as layout/pack.cpp
// orders it):
//   x = the step's uvec4:
//     .x v1 node slot      left child: +1; right child: +1 + (1 + 2 inner(left)), past the left subtree
//     .y bvh2-cb record    left child: +1; right child: +1 + inner(left) (records count inner nodes only)
//     .z first primitive   left child: +0; right child: + count(left)
//     .w depth | hidden    +1 per step; bit 31 set where the parent is a collapsed leaf (the child is not
//                          emitted; its primitive position .z still is its place in the leaf's order)
// Nodes as the GPU builders number them: inner nodes 0 .. n - 2 (root 0), leaves n - 1 + sorted position.
// info = (primitives below, inner nodes emitted below; 0: the node is one leaf) from the collapse pass.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Children { uint children[]; };
layout(std430, binding = 1) readonly buffer Parents { uint parents[]; };
layout(std430, binding = 2) readonly buffer Info { uint info[]; };
layout(std430, binding = 3) writeonly buffer Steps { uvec4 steps[]; };       // its first half
layout(std430, binding = 4) writeonly buffer Ancestors { uint ancestors[]; };  // likewise
uniform uint u_nodes;  // 2n - 1

const uint kNone = 0xffffffffu;
const uint kHidden = 0x80000000u;

void main() {
  uint x = gl_GlobalInvocationID.x;
  if (x >= u_nodes) return;
  uint p = parents[x];
  if (p == kNone) {
    steps[x] = uvec4(0u);
    ancestors[x] = kNone;
    return;
  }
  uint l = children[2u * p];
  uint hidden = info[2u * p + 1u] == 0u ? kHidden : 0u;
  if (x == l)
    steps[x] = uvec4(1u, 1u, 0u, 1u | hidden);
  else
    steps[x] = uvec4(2u + 2u * info[2u * l + 1u], 1u + info[2u * l + 1u], info[2u * l], 1u | hidden);
  ancestors[x] = p;
}
