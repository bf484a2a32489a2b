// hploc-gpu's passes and download (builders/gpu/gpu_hploc.hpp).
#include "builders/gpu/gpu_hploc.hpp"

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/gpu/gpu_build_steps.hpp"
#include "builders/hploc.hpp"
#include "datasets/scene.hpp"  // InputError
#include "render/gl_context.hpp"

namespace bvhlab::gpubuild {

namespace {
constexpr const char* kName = "hploc-gpu";
constexpr uint32_t kHplocGroup = detail::hploc::kGroup;  // gpubuild_hploc.glsl's local_size_x
uint32_t hplocGroupsFor(uint64_t n) { return uint32_t((n + kHplocGroup - 1) / kHplocGroup); }
}  // namespace

GpuHploc::GpuHploc(std::optional<GpuLimits> limits)
    : limits_(limits ? *limits : queryGpuLimits()),
      hierarchy_("gpubuild_hploc.glsl", "", {"gpubuild_ploc_pairs.glsl"}),
      collapse_("gpubuild_collapse.glsl") {}

void GpuHploc::checkLimits(size_t n, bool pack) const {
  std::vector<std::pair<const char*, uint64_t>> buffers = sharedBuildBuffers(n, pack);
  buffers.push_back({"cluster lists", uint64_t(n) * 8});
  buffers.push_back({"waiting ends", uint64_t(n) * 4});
  checkBuildLimits(kName, n, limits_, buffers);
  if (uint64_t(hplocGroupsFor(n)) > limits_.maxWorkGroupsX)
    throw InputError(std::string(kName) + ": " + std::to_string(n) + " primitives need " +
                     std::to_string(hplocGroupsFor(n)) + " workgroups of " + std::to_string(kHplocGroup) +
                     " in one dispatch; GL_MAX_COMPUTE_WORK_GROUP_COUNT (x) is " +
                     std::to_string(limits_.maxWorkGroupsX) + " here");
}

Bvh GpuHploc::build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
                    const GpuPackRequest* pack) const {
  const uint32_t radius = options.plocRadius;
  if (radius < 1 || radius > kMaxPlocRadius)
    throw std::invalid_argument(std::string(kName) + ": plocRadius " + std::to_string(radius) + " is outside 1.." +
                                std::to_string(kMaxPlocRadius));
  if (options.mortonSizeBits != 0)
    throw std::invalid_argument(std::string(kName) + ": --morton-size-bits " + std::to_string(options.mortonSizeBits) +
                                " is not supported on the GPU (only 0: plain position codes)");
  if (options.plocTopDown != 0)
    throw std::invalid_argument(std::string(kName) + ": --ploc-top-down " + std::to_string(options.plocTopDown) +
                                " is not supported (only 0: clustering up to the root)");
  const size_t count = input.boxes.size();
  checkLimits(count, pack != nullptr);
  if (times) *times = GpuPhaseTimes{};
  const uint32_t n = uint32_t(count);
  if (n == 1) {  // hploc's tree of one primitive: one leaf; nothing to sort or cluster
    Bvh bvh;
    bvh.nodes.resize(1);
    bvh.nodes[0].bounds = input.boxes[0];
    bvh.nodes[0].count = 1;
    bvh.primIndices = {0};
    if (pack) packOnTheCpu(bvh, *pack);
    return bvh;
  }
  const uint32_t inner = n - 1, nodes = 2 * n - 1;

  enum { kBoxes, kCentroids, kBoundKeys, kGrid, kKeys, kScratch, kCounts, kNodeBoxes, kChildren, kParents, kInfo,
         kCosts, kCollapseCounters, kLists, kWaiting };
  BuildBuffers<15, 7> b;
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
  b.ids[kNodeBoxes] = makeStorageBuffer(uint64_t(nodes) * 24);
  b.ids[kChildren] = makeStorageBuffer(uint64_t(inner) * 8);
  b.ids[kParents] = makeStorageBuffer(uint64_t(nodes) * 4);
  const uint32_t none = ~0u, zero = 0;
  glNamedBufferSubData(b.ids[kParents], 0, 4, &none);  // the root's (node 0); the merges write the others
  b.ids[kInfo] = makeStorageBuffer(uint64_t(nodes) * 8);
  b.ids[kCosts] = makeStorageBuffer(uint64_t(nodes) * 8);
  b.ids[kCollapseCounters] = makeStorageBuffer(uint64_t(inner) * 4);
  glClearNamedBufferData(b.ids[kCollapseCounters], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  b.ids[kLists] = makeStorageBuffer(uint64_t(n) * 8);
  b.ids[kWaiting] = makeStorageBuffer(uint64_t(n) * 4);  // the made-node counter, then n - 1 boundaries
  glClearNamedBufferData(b.ids[kWaiting], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &none);
  glNamedBufferSubData(b.ids[kWaiting], 0, 4, &zero);
  checkGl("hploc-gpu: uploading the input");

  auto bind = [&](std::initializer_list<int> which) {
    GLuint slot = 0;
    for (int w : which) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot++, b.ids[w]);
  };
  std::optional<GpuPackJob> packJob;  // the soup uploaded before the timed phases
  if (pack) packJob.emplace(packer_, *pack, n);
  PhaseStamps stamps;
  if (soupBoxes) packJob->soupBoxes(b.ids[kBoxes], b.ids[kCentroids], stamps);
  morton_.run(kName, n, options.mortonGrid, b.ids[kCentroids], b.ids[kBoundKeys], b.ids[kGrid], b.ids[kKeys]);
  stamps.mark("morton");
  sort_.sort(b.ids[kKeys], b.ids[kScratch], b.ids[kCounts], n);
  stamps.mark("sort");
  bind({kKeys, kBoxes, kNodeBoxes, kChildren, kParents, kLists, kWaiting});
  hierarchy_.set("u_count", n);
  hierarchy_.set("u_radius", radius);
  hierarchy_.dispatch(hplocGroupsFor(n), "hploc-gpu hierarchy: climb and cluster (gpubuild_hploc.glsl)");
  stamps.mark("hierarchy");
  bind({kChildren, kParents, kNodeBoxes, kInfo, kCosts, kCollapseCounters});
  collapse_.set("u_count", n);
  collapse_.set("u_maxLeaf", options.maxLeafSize);
  collapse_.set("u_ct", options.cost.traversalCost);
  collapse_.set("u_ci", options.cost.intersectionCost);
  collapse_.dispatch(groupsFor(n), "hploc-gpu collapse: SAH leaf collapse (gpubuild_collapse.glsl)");
  stamps.mark("collapse");
  const GpuTreeBuffers tree{b.ids[kChildren], b.ids[kParents], b.ids[kNodeBoxes], b.ids[kInfo], b.ids[kKeys]};
  if (packJob) packJob->run(tree, stamps);
  checkGl("hploc-gpu: timer queries");
  glFinish();
  const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wallStart).count();
  if (times) {
    stamps.read(*times);
    times->wallMs = wallMs;
  }
  if (packJob) packJob->download();
  uint32_t made = 0;
  glGetNamedBufferSubData(b.ids[kWaiting], 0, 4, &made);
  if (made != inner)
    throw std::runtime_error("hploc-gpu hierarchy: " + std::to_string(made) + " inner nodes made of " +
                             std::to_string(inner));
  return downloadClusteredTree(kName, tree, n);
}

}  // namespace bvhlab::gpubuild
