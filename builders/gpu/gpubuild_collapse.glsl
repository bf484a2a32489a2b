// lbvh-gpu, collapse phase: builders/collapse.hpp's SAH leaf collapse, bottom-up as the fit phase
// climbs (atomic counters). Per node: the primitives below, the inner nodes it will emit (0: it
// becomes one leaf) and its cost in double, with the CPU's operations in the CPU's order: leaf
// Ci * area * count, inner Ct * area + left + right; `precise` keeps every product and sum rounded
// on its own (no fused multiply-add), as the CPU computes it. Areas are float half areas as
// Aabb::halfArea computes them ((x y + y z) + z x).
layout(local_size_x = 256) in;
// bindings 0-2 (children, parents, node boxes) and halfArea: gpubuild_tree_area.glsl
layout(std430, binding = 3) coherent buffer Info { uint info[]; };  // count, inner per node
layout(std430, binding = 4) coherent buffer Costs { double costs[]; };
layout(std430, binding = 5) coherent buffer Counters { uint counters[]; };
uniform uint u_count;
uniform uint u_maxLeaf;
uniform float u_ct, u_ci;

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= u_count) return;
  uint node = u_count - 1u + k;
  precise double leafCost = double(u_ci) * double(halfArea(node)) * 1.0LF;
  costs[node] = leafCost;
  info[2u * node] = 1u;
  info[2u * node + 1u] = 0u;
  for (;;) {
    uint parent = parents[node];
    if (parent == 0xffffffffu) break;
    memoryBarrierBuffer();
    if (atomicAdd(counters[parent], 1u) == 0u) break;
    memoryBarrierBuffer();
    uint l = children[2u * parent], r = children[2u * parent + 1u];
    uint count = info[2u * l] + info[2u * r];
    precise double area = double(halfArea(parent));
    precise double asLeaf = double(u_ci) * area * double(count);
    precise double asTree = double(u_ct) * area + costs[l] + costs[r];
    bool collapse = count <= u_maxLeaf && asLeaf <= asTree;
    costs[parent] = collapse ? asLeaf : asTree;
    info[2u * parent] = count;
    info[2u * parent + 1u] = collapse ? 0u : 1u + info[2u * l + 1u] + info[2u * r + 1u];
    node = parent;
  }
}
