// The buffers, collapse, option checks and download the GPU builders share
// (builders/gpu/gpu_build_steps.hpp).
#include "builders/gpu/gpu_build_steps.hpp"

#include <stdexcept>

namespace bvhlab::gpubuild {

void makeSharedBuffers(GLuint* ids, const BuildInput& input, bool soupBoxes) {
  const uint64_t n = input.boxes.size(), inner = n - 1, nodes = 2 * n - 1;
  ids[kBoxes] = makeStorageBuffer(n * 24, soupBoxes ? nullptr : input.boxes.data());
  ids[kCentroids] = makeStorageBuffer(n * 12, soupBoxes ? nullptr : input.centroids.data());
  const uint32_t initialKeys[6] = {~0u, ~0u, ~0u, 0u, 0u, 0u};  // min keys from the top, max from the bottom
  ids[kBoundKeys] = makeStorageBuffer(sizeof initialKeys, initialKeys);
  ids[kGrid] = makeStorageBuffer(6 * 4);
  ids[kKeys] = makeStorageBuffer(n * 12);
  ids[kScratch] = makeStorageBuffer(n * 12);
  ids[kCounts] = makeStorageBuffer(GpuRadixSort::countBytes(uint32_t(n)));
  ids[kNodeBoxes] = makeStorageBuffer(nodes * 24);
  ids[kChildren] = makeStorageBuffer(inner * 8);
  ids[kParents] = makeStorageBuffer(nodes * 4);
  const uint32_t noParent = ~0u, zero = 0;
  glNamedBufferSubData(ids[kParents], 0, 4, &noParent);  // the root's (node 0); the passes write the others
  ids[kInfo] = makeStorageBuffer(nodes * 8);
  ids[kCosts] = makeStorageBuffer(nodes * 8);
  ids[kCollapseCounters] = makeStorageBuffer(inner * 4);
  glClearNamedBufferData(ids[kCollapseCounters], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
}

void runCollapse(const ComputeProgram& collapse, const GLuint* ids, uint32_t n, const BuildOptions& options,
                 const std::string& builder) {
  GLuint slot = 0;
  for (int w : {kChildren, kParents, kNodeBoxes, kInfo, kCosts, kCollapseCounters})
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot++, ids[w]);
  collapse.set("u_count", n);
  collapse.set("u_maxLeaf", options.maxLeafSize);
  collapse.set("u_ct", options.cost.traversalCost);
  collapse.set("u_ci", options.cost.intersectionCost);
  collapse.dispatch(groupsFor(n), (builder + " collapse: SAH leaf collapse (gpubuild_collapse.glsl)").c_str());
}

Bvh onePrimitiveTree(const BuildInput& input, const GpuPackRequest* pack) {
  Bvh bvh;
  bvh.nodes.resize(1);
  bvh.nodes[0].bounds = input.boxes[0];
  bvh.nodes[0].count = 1;
  bvh.primIndices = {0};
  if (pack) packOnTheCpu(bvh, *pack);
  return bvh;
}

void checkGpuOptions(const std::string& builder, const BuildOptions& options, bool radius) {
  if (radius && (options.plocRadius < 1 || options.plocRadius > kMaxPlocRadius))
    throw std::invalid_argument(builder + ": plocRadius " + std::to_string(options.plocRadius) + " is outside 1.." +
                                std::to_string(kMaxPlocRadius));
  if (options.mortonSizeBits != 0)
    throw std::invalid_argument(builder + ": --morton-size-bits " + std::to_string(options.mortonSizeBits) +
                                " is not supported on the GPU (only 0: plain position codes)");
  if (radius && options.plocTopDown != 0)
    throw std::invalid_argument(builder + ": --ploc-top-down " + std::to_string(options.plocTopDown) +
                                " is not supported on the GPU (only 0: clustering up to the root)");
}

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
