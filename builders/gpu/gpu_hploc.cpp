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
      collapse_("gpubuild_collapse.glsl", "", {"gpubuild_tree_area.glsl"}) {}

void GpuHploc::checkLimits(size_t n, bool pack) const {
  std::vector<std::pair<const char*, uint64_t>> buffers = sharedBuildBuffers(n, pack);
  buffers.push_back({"cluster lists", uint64_t(n) * 8});
  buffers.push_back({"waiting ends", uint64_t(n) * 4});
  checkBuildLimits(kName, n, limits_, buffers);
  checkWorkGroups(kName, n, limits_, kHplocGroup);  // the hierarchy's workgroups of 32
}

Bvh GpuHploc::build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
                    const GpuPackRequest* pack) const {
  checkGpuOptions(kName, options, /*radius=*/true);
  const size_t count = input.boxes.size();
  checkLimits(count, pack != nullptr);
  if (times) *times = GpuPhaseTimes{};
  const uint32_t n = uint32_t(count);
  if (n == 1) return onePrimitiveTree(input, pack);  // hploc's tree: one leaf; nothing to sort or cluster

  enum { kLists = kSharedBuffers, kWaiting, kBuffers };
  BuildBuffers<kBuffers, 7> b;
  const auto wallStart = std::chrono::steady_clock::now();
  const bool soupBoxes = pack && pack->boxesFromSoup;  // the boxes pass fills them (phase `boxes`)
  makeSharedBuffers(b.ids.data(), input, soupBoxes);
  b.ids[kLists] = makeStorageBuffer(uint64_t(n) * 8);
  b.ids[kWaiting] = makeStorageBuffer(uint64_t(n) * 4);  // the made-node counter, then n - 1 boundaries
  const uint32_t none = ~0u, zero = 0;
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
  hierarchy_.set("u_radius", options.plocRadius);
  hierarchy_.dispatch(hplocGroupsFor(n), "hploc-gpu hierarchy: climb and cluster (gpubuild_hploc.glsl)");
  stamps.mark("hierarchy");
  runCollapse(collapse_, b.ids.data(), n, options, kName);
  stamps.mark("collapse");
  const GpuTreeBuffers tree = treeBuffers(b.ids.data());
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
  if (made != n - 1)
    throw std::runtime_error("hploc-gpu hierarchy: " + std::to_string(made) + " inner nodes made of " +
                             std::to_string(n - 1));
  return downloadClusteredTree(kName, tree, n);
}

}  // namespace bvhlab::gpubuild
