// The download the GPU builders share (builders/gpu/gpu_build_steps.hpp).
#include "builders/gpu/gpu_build_steps.hpp"

namespace bvhlab::gpubuild {

Bvh downloadClusteredTree(const std::string& builder, const GpuTreeBuffers& tree, uint32_t n) {
  const uint32_t inner = n - 1, nodes = 2 * n - 1;
  const std::vector<GpuKey> keys = download<GpuKey>(tree.keys, n);
  const std::vector<uint32_t> children = download<uint32_t>(tree.children, 2 * size_t(inner));
  const std::vector<Aabb> boxes = download<Aabb>(tree.nodeBoxes, nodes);
  const std::vector<uint32_t> info = download<uint32_t>(tree.info, 2 * size_t(nodes));  // count, inner
  checkGl((builder + ": download").c_str());
  Bvh bvh;
  bvh.nodes.resize(1 + 2 * size_t(info[1]));
  bvh.primIndices.resize(n);
  struct Item {
    uint32_t node, slot, base, prim;
  };
  std::vector<Item> stack{{0, 0, 1, 0}};
  std::vector<uint32_t> below;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    BvhNode& out = bvh.nodes[it.slot];
    out.bounds = boxes[it.node];
    if (info[2 * it.node + 1] == 0) {  // one leaf (a full-tree leaf, or a collapsed subtree)
      out.first = it.prim;
      out.count = info[2 * it.node];
      uint32_t prim = it.prim;
      below.assign(1, it.node);
      while (!below.empty()) {
        const uint32_t node = below.back();
        below.pop_back();
        if (node >= inner) {
          bvh.primIndices[prim++] = keys[node - inner].id;
        } else {
          below.push_back(children[2 * node + 1]);
          below.push_back(children[2 * node]);
        }
      }
      continue;
    }
    const uint32_t l = children[2 * it.node], r = children[2 * it.node + 1];
    out.left = it.base;
    out.right = it.base + 1;
    stack.push_back({r, it.base + 1, it.base + 2 + 2 * info[2 * l + 1], it.prim + info[2 * l]});
    stack.push_back({l, it.base, it.base + 2, it.prim});
  }
  return bvh;
}

}  // namespace bvhlab::gpubuild
