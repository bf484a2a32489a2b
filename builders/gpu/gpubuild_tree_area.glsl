// Compiled ahead of the passes that climb a built tree with its boxes (gpubuild_collapse.glsl, the
// SAH leaf collapse; gpubuild_wide_costs.glsl, the wide collapse): the tree's buffers at bindings 0-2
// and a node's half area as Aabb::halfArea computes it ((x y + y z) + z x in float, each product and
// sum rounded on its own under `precise`; 0 for an empty box).
layout(std430, binding = 0) readonly buffer Children { uint children[]; };  // 2 per inner node
layout(std430, binding = 1) readonly buffer Parents { uint parents[]; };    // per node; the root's ~0u
layout(std430, binding = 2) readonly buffer NodeBoxes { float nodeBoxes[]; };  // min xyz, max xyz per node

float halfArea(uint node) {
  vec3 lo = vec3(nodeBoxes[6u * node], nodeBoxes[6u * node + 1u], nodeBoxes[6u * node + 2u]);
  vec3 hi = vec3(nodeBoxes[6u * node + 3u], nodeBoxes[6u * node + 4u], nodeBoxes[6u * node + 5u]);
  if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) return 0.0;
  precise vec3 e = hi - lo;
  precise float a = e.x * e.y + e.y * e.z + e.z * e.x;
  return a;
}
