// lbvh-gpu's passes and download (builders/gpu/gpu_lbvh.hpp).
#include "builders/gpu/gpu_lbvh.hpp"

#include <array>
#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/gpu/gpu_build_steps.hpp"
#include "datasets/scene.hpp"  // InputError
#include "render/gl_context.hpp"

namespace bvhlab::gpubuild {

static_assert(sizeof(Aabb) == 24 && sizeof(glm::vec3) == 12, "boxes and centroids are uploaded as they lie");

double GpuPhaseTimes::totalMs() const {
  double sum = 0.0;
  for (const auto& [name, ms] : phases) sum += ms;
  return sum;
}

GpuLbvh::GpuLbvh(std::optional<GpuLimits> limits)
    : limits_(limits ? *limits : queryGpuLimits()),
      labels_("gpubuild_labels.glsl"),
      hierarchy_("gpubuild_hierarchy.glsl"),
      fit_("gpubuild_fit.glsl"),
      collapse_("gpubuild_collapse.glsl") {}

void GpuLbvh::checkLimits(size_t n, bool pack) const {
  checkBuildLimits("lbvh-gpu", n, limits_, sharedBuildBuffers(n, pack));
}

Bvh GpuLbvh::build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
                   const GpuPackRequest* pack) const {
  if (options.mortonSizeBits != 0)
    throw std::invalid_argument("lbvh-gpu: --morton-size-bits " + std::to_string(options.mortonSizeBits) +
                                " is not supported on the GPU (only 0: plain position codes)");
  const size_t count = input.boxes.size();
  checkLimits(count, pack != nullptr);
  if (times) *times = GpuPhaseTimes{};
  const uint32_t n = uint32_t(count);
  if (n == 1) {  // lbvh's tree of one primitive: one leaf; nothing to sort or link
    Bvh bvh;
    bvh.nodes.resize(1);
    bvh.nodes[0].bounds = input.boxes[0];
    bvh.nodes[0].count = 1;
    bvh.primIndices = {0};
    if (pack) packOnTheCpu(bvh, *pack);
    return bvh;
  }
  const uint32_t inner = n - 1, nodes = 2 * n - 1;

  enum { kBoxes, kCentroids, kBoundKeys, kGrid, kKeys, kScratch, kCounts, kLabels, kChildren, kParents, kNodeBoxes,
         kInfo, kCosts, kFitCounters, kCollapseCounters };
  BuildBuffers<15, 6> b;
  const auto wallStart = std::chrono::steady_clock::now();
  const bool soupBoxes = pack && pack->boxesFromSoup;  // the boxes pass fills them (phase `boxes`)
  b.ids[kBoxes] = makeStorageBuffer(uint64_t(n) * 24, soupBoxes ? nullptr : input.boxes.data());
  b.ids[kCentroids] = makeStorageBuffer(uint64_t(n) * 12, soupBoxes ? nullptr : input.centroids.data());
  const uint32_t initialKeys[6] = {~0u, ~0u, ~0u, 0u, 0u, 0u};  // min keys from the top, max from the bottom
  b.ids[kBoundKeys] = makeStorageBuffer(sizeof initialKeys, initialKeys);
  b.ids[kGrid] = makeStorageBuffer(6 * 4);
  b.ids[kKeys] = makeStorageBuffer(uint64_t(n) * 12);
  b.ids[kScratch] = makeStorageBuffer(uint64_t(n) * 12);
  b.ids[kCounts] = makeStorageBuffer(GpuRadixSort::countBytes(n));
  b.ids[kLabels] = makeStorageBuffer(uint64_t(n) * 4);
  b.ids[kChildren] = makeStorageBuffer(uint64_t(inner) * 8);
  b.ids[kParents] = makeStorageBuffer(uint64_t(nodes) * 4);
  const uint32_t noParent = ~0u;
  glNamedBufferSubData(b.ids[kParents], 0, 4, &noParent);  // the root's; the hierarchy writes the others
  b.ids[kNodeBoxes] = makeStorageBuffer(uint64_t(nodes) * 24);
  b.ids[kInfo] = makeStorageBuffer(uint64_t(nodes) * 8);
  b.ids[kCosts] = makeStorageBuffer(uint64_t(nodes) * 8);
  const uint32_t zero = 0;
  for (int counters : {kFitCounters, kCollapseCounters}) {
    b.ids[counters] = makeStorageBuffer(uint64_t(inner) * 4);
    glClearNamedBufferData(b.ids[counters], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  }
  checkGl("lbvh-gpu: uploading the input");

  auto bind = [&](std::initializer_list<int> which) {
    GLuint slot = 0;
    for (int w : which) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot++, b.ids[w]);
  };

  std::optional<GpuPackJob> packJob;  // the soup uploaded before the timed phases
  if (pack) packJob.emplace(packer_, *pack, n);
  PhaseStamps stamps;
  if (soupBoxes) packJob->soupBoxes(b.ids[kBoxes], b.ids[kCentroids], stamps);
  morton_.run("lbvh-gpu", n, options.mortonGrid, b.ids[kCentroids], b.ids[kBoundKeys], b.ids[kGrid], b.ids[kKeys]);
  stamps.mark("morton");
  // sort
  sort_.sort(b.ids[kKeys], b.ids[kScratch], b.ids[kCounts], n);
  stamps.mark("sort");
  // hierarchy
  bind({kKeys, kLabels});
  labels_.set("u_count", n);
  labels_.dispatch(groupsFor(n), "lbvh-gpu hierarchy: equal-code labels (gpubuild_labels.glsl)");
  bind({kKeys, kLabels, kChildren, kParents});
  hierarchy_.set("u_count", n);
  hierarchy_.dispatch(groupsFor(inner), "lbvh-gpu hierarchy: radix tree (gpubuild_hierarchy.glsl)");
  stamps.mark("hierarchy");
  // fit
  bind({kBoxes, kKeys, kChildren, kParents, kNodeBoxes, kFitCounters});
  fit_.set("u_count", n);
  fit_.dispatch(groupsFor(n), "lbvh-gpu fit: boxes bottom-up (gpubuild_fit.glsl)");
  stamps.mark("fit");
  // collapse
  bind({kChildren, kParents, kNodeBoxes, kInfo, kCosts, kCollapseCounters});
  collapse_.set("u_count", n);
  collapse_.set("u_maxLeaf", options.maxLeafSize);
  collapse_.set("u_ct", options.cost.traversalCost);
  collapse_.set("u_ci", options.cost.intersectionCost);
  collapse_.dispatch(groupsFor(n), "lbvh-gpu collapse: SAH leaf collapse (gpubuild_collapse.glsl)");
  stamps.mark("collapse");
  if (packJob) packJob->run({b.ids[kChildren], b.ids[kParents], b.ids[kNodeBoxes], b.ids[kInfo], b.ids[kKeys]}, stamps);
  checkGl("lbvh-gpu: timer queries");
  glFinish();
  const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wallStart).count();

  if (times) {
    stamps.read(*times);
    times->wallMs = wallMs;
  }
  if (packJob) packJob->download();

  // Download (untimed) and the depth-first emission of builders/collapse.hpp's emitCollapsed: an
  // emitted inner node's children take the slots base, base + 1, then the left child's descendants,
  // then the right's; primitives in leaf order, which is the sorted order (a subtree is a range).
  const std::vector<GpuKey> keys = download<GpuKey>(b.ids[kKeys], n);
  const std::vector<uint32_t> children = download<uint32_t>(b.ids[kChildren], 2 * size_t(inner));
  const std::vector<Aabb> boxes = download<Aabb>(b.ids[kNodeBoxes], nodes);
  const std::vector<uint32_t> info = download<uint32_t>(b.ids[kInfo], 2 * size_t(nodes));  // count, inner
  checkGl("lbvh-gpu: download");
  Bvh bvh;
  bvh.nodes.resize(1 + 2 * size_t(info[1]));
  bvh.primIndices.resize(n);
  for (uint32_t k = 0; k < n; ++k) bvh.primIndices[k] = keys[k].id;
  struct Item {
    uint32_t node, slot, base, prim;
  };
  std::vector<Item> stack{{0, 0, 1, 0}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    BvhNode& out = bvh.nodes[it.slot];
    out.bounds = boxes[it.node];
    if (info[2 * it.node + 1] == 0) {  // one leaf (a full-tree leaf, or a collapsed subtree)
      out.first = it.prim;
      out.count = info[2 * it.node];
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
