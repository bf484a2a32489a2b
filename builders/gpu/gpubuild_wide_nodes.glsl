// GPU pack into cwbvh, step 5 (dispatched indirectly, one invocation per wide node): each node's
// index, childBase and triBase from the path sums of the pointer jumping (gpubuild_pack_jump.glsl over
// the queue's steps, half `finalHalf`), as layout/pack_cwbvh.cpp numbers them: the root 0; a node's
// inner children from childBase = 1 + the inner children counted before it (.x), at childBase + rank;
// its leaf slots' triangles from triBase = the triangles written before it (.y), in slot order. Writes
// the node's 5 texels (the level pass's, with childBase and triBase) and copies each leaf slot's
// triangles (3 TRIANGLE and 4 ATTRIBUTE texels each) from v1's streams, where they are consecutive.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer WideStateBuffer { WideState state; };  // gpubuild_wide_state.glsl
layout(std430, binding = 1) readonly buffer Queue { uvec4 queue[]; };
layout(std430, binding = 2) readonly buffer WideSteps { uvec4 wideSteps[]; };  // two halves of u_bound
layout(std430, binding = 3) readonly buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };
layout(std430, binding = 4) readonly buffer Scratch { uvec4 scratch[]; };
layout(std430, binding = 5) readonly buffer V1Triangles { uvec4 v1Triangles[]; };
layout(std430, binding = 6) readonly buffer V1Attributes { uvec4 v1Attributes[]; };
layout(std430, binding = 7) writeonly buffer NodeStream { uvec4 nodeStream[]; };
layout(std430, binding = 8) writeonly buffer TriangleStream { uvec4 triangleStream[]; };
layout(std430, binding = 9) writeonly buffer AttributeStream { uvec4 attributeStream[]; };
uniform uint u_bound;  // entries the queue has room for

const uint kNone = 0xffffffffu;
const uint kMetaInner = 0x80u;

void main() {
  uint q = gl_GlobalInvocationID.x;
  if (q >= state.queued) return;
  uvec4 entry = queue[q];
  uint halfBase = finalHalf * u_bound;
  uvec4 sums = wideSteps[halfBase + q];
  uint index = entry.y == kNone ? 0u : 1u + wideSteps[halfBase + entry.y].x + entry.z;
  uvec4 t1 = scratch[7u * q + 1u];
  uint inner = 0u;
  for (uint s = 0u; s < 8u; ++s) inner += ((s < 4u ? t1.z : t1.w) >> (8u * (s % 4u)) & 0xFFu) == kMetaInner ? 1u : 0u;
  nodeStream[5u * index] = scratch[7u * q];
  nodeStream[5u * index + 1u] = uvec4(inner > 0u ? 1u + sums.x : 0u, sums.y, t1.z, t1.w);
  for (uint t = 2u; t < 5u; ++t) nodeStream[5u * index + t] = scratch[7u * q + t];
  uint at = sums.y;
  for (uint s = 0u; s < 8u; ++s) {
    uint meta = ((s < 4u ? t1.z : t1.w) >> (8u * (s % 4u))) & 0xFFu;
    if (meta == 0u || meta == kMetaInner) continue;
    uint from = scratch[7u * q + 5u + s / 4u][s % 4u];
    for (uint i = 0u; i < meta; ++i, ++at) {
      for (uint t = 0u; t < 3u; ++t) triangleStream[3u * at + t] = v1Triangles[3u * (from + i) + t];
      for (uint t = 0u; t < 4u; ++t) attributeStream[4u * at + t] = v1Attributes[4u * (from + i) + t];
    }
  }
}
