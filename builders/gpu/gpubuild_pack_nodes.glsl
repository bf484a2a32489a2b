// GPU pack, step 3: the NODE stream, from each node's path sums (gpubuild_pack_jump.glsl, half
// `finalHalf`), as layout/pack.cpp (v1) and layout/pack_bvh2cb.cpp (bvh2-cb) write it for the tree the
// download emits (builders/collapse.hpp's emitCollapsed), texel for texel:
//   every emitted node (no collapsed leaf above it), LAYOUT_V1: its 2 node texels at its slot (.x)
//   every emitted inner node, LAYOUT_BVH2CB: its record at .y, its children's slots computed from it;
//     a root that is one leaf: record 0 holds it in A and an empty slot over the same box in B
// and the emitted tree's depth (root alone = 1) by atomicMax into the pack state.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Children { uint children[]; };
layout(std430, binding = 1) readonly buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 2) readonly buffer Info { uint info[]; };
layout(std430, binding = 3) buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };
layout(std430, binding = 4) readonly buffer Steps { uvec4 steps[]; };  // two halves of 2n - 1
layout(std430, binding = 5) writeonly buffer NodeStream { uvec4 nodeStream[]; };
uniform uint u_count;  // primitives n (n - 1 inner nodes, 2n - 1 nodes)

const uint kHidden = 0x80000000u;
const uint kEscapeEnd = 0x0FFFFFFFu;   // layout/layout.hpp
const uint kBvh2cbInner = 0xFFFFFFFFu;  // layout/layout_bvh2cb.hpp

uvec3 boxLow(uint node) {
  return uvec3(floatBitsToUint(nodeBoxes[6u * node]), floatBitsToUint(nodeBoxes[6u * node + 1u]),
               floatBitsToUint(nodeBoxes[6u * node + 2u]));
}
uvec3 boxHigh(uint node) {
  return uvec3(floatBitsToUint(nodeBoxes[6u * node + 3u]), floatBitsToUint(nodeBoxes[6u * node + 4u]),
               floatBitsToUint(nodeBoxes[6u * node + 5u]));
}

#ifdef LAYOUT_BVH2CB
// Child `c` of an emitted inner node as a record slot: its record when inner, else its triangles.
void writeSlot(uint at, uint c, uint record, uint firstPrimitive) {
  bool inner = info[2u * c + 1u] != 0u;
  nodeStream[at] = uvec4(boxLow(c), inner ? record : firstPrimitive);
  nodeStream[at + 1u] = uvec4(boxHigh(c), inner ? kBvh2cbInner : info[2u * c]);
}
#endif

void main() {
  uint x = gl_GlobalInvocationID.x, nodes = 2u * u_count - 1u;
  if (x >= nodes) return;
  uvec4 s = steps[finalHalf * nodes + x];
  if ((s.w & kHidden) != 0u) return;  // inside a collapsed leaf
  atomicMax(depth, s.w + 1u);
  uint count = info[2u * x], below = info[2u * x + 1u];
#ifdef LAYOUT_V1
  uint a, escape;
  if (below == 0u) {
    a = s.z;
    escape = s.x + 1u;
  } else {
    count = 0u;
    a = s.x + 2u + 2u * info[2u * children[2u * x] + 1u];
    escape = s.x + 1u + 2u * below;
  }
  if (escape == 1u + 2u * info[1u]) escape = kEscapeEnd;  // the root's subtree ends the stream
  nodeStream[2u * s.x] = uvec4(boxLow(x), a | ((count & 0xFu) << 28));
  nodeStream[2u * s.x + 1u] = uvec4(boxHigh(x), escape | ((count >> 4) << 28));
#endif
#ifdef LAYOUT_BVH2CB
  if (below == 0u) {
    if (x == 0u) {  // the root is one leaf
      nodeStream[0] = uvec4(boxLow(x), s.z);
      nodeStream[1] = uvec4(boxHigh(x), count);
      nodeStream[2] = uvec4(boxLow(x), s.z);
      nodeStream[3] = uvec4(boxHigh(x), 0u);
    }
    return;
  }
  uint l = children[2u * x], r = children[2u * x + 1u];
  writeSlot(4u * s.y, l, s.y + 1u, s.z);
  writeSlot(4u * s.y + 2u, r, s.y + 1u + info[2u * l + 1u], s.z + info[2u * l]);
#endif
}
