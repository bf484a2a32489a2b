// lbvh-gpu, fit phase: boxes bottom-up. One invocation per leaf writes the leaf's box (its primitive's)
// and climbs: at each parent the first child to arrive stops (atomic counter), the second unites the
// two children's boxes as Aabb::grow does (min/max as glm's: y < x ? y : x, x < y ? y : x) and goes on.
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Boxes { float boxes[]; };  // min xyz, max xyz per primitive
layout(std430, binding = 1) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 2) readonly buffer Children { uint children[]; };
layout(std430, binding = 3) readonly buffer Parents { uint parents[]; };
layout(std430, binding = 4) coherent buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 5) coherent buffer Counters { uint counters[]; };
uniform uint u_count;

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= u_count) return;
  uint node = u_count - 1u + k, prim = keys[k].id;
  for (uint c = 0u; c < 6u; ++c) nodeBoxes[6u * node + c] = boxes[6u * prim + c];
  for (;;) {
    uint parent = parents[node];
    if (parent == 0xffffffffu) break;
    memoryBarrierBuffer();
    if (atomicAdd(counters[parent], 1u) == 0u) break;  // the sibling is not done yet: it goes on
    memoryBarrierBuffer();
    uint l = children[2u * parent], r = children[2u * parent + 1u];
    for (uint c = 0u; c < 3u; ++c) {
      float a = nodeBoxes[6u * l + c], b = nodeBoxes[6u * r + c];
      nodeBoxes[6u * parent + c] = b < a ? b : a;
      a = nodeBoxes[6u * l + 3u + c], b = nodeBoxes[6u * r + 3u + c];
      nodeBoxes[6u * parent + 3u + c] = a < b ? b : a;
    }
    node = parent;
  }
}
