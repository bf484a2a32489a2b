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
      collapse_("gpubuild_collapse.glsl", "", {"gpubuild_tree_area.glsl"}) {}

void GpuLbvh::checkLimits(size_t n, bool pack) const {
  checkBuildLimits("lbvh-gpu", n, limits_, sharedBuildBuffers(n, pack));
}

Bvh GpuLbvh::build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
                   const GpuPackRequest* pack) const {
  checkGpuOptions("lbvh-gpu", options, /*radius=*/false);
  const size_t count = input.boxes.size();
  checkLimits(count, pack != nullptr);
  if (times) *times = GpuPhaseTimes{};
  const uint32_t n = uint32_t(count);
  if (n == 1) return onePrimitiveTree(input, pack);  // lbvh's tree: one leaf; nothing to sort or link
  const uint32_t inner = n - 1;

  enum { kLabels = kSharedBuffers, kFitCounters, kBuffers };
  BuildBuffers<kBuffers, 6> b;
  const auto wallStart = std::chrono::steady_clock::now();
  const bool soupBoxes = pack && pack->boxesFromSoup;  // the boxes pass fills them (phase `boxes`)
  makeSharedBuffers(b.ids.data(), input, soupBoxes);
  b.ids[kLabels] = makeStorageBuffer(uint64_t(n) * 4);
  b.ids[kFitCounters] = makeStorageBuffer(uint64_t(inner) * 4);
  const uint32_t zero = 0;
  glClearNamedBufferData(b.ids[kFitCounters], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
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
  runCollapse(collapse_, b.ids.data(), n, options, "lbvh-gpu");
  stamps.mark("collapse");
  if (packJob) packJob->run(treeBuffers(b.ids.data()), stamps);
  checkGl("lbvh-gpu: timer queries");
  glFinish();
  const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wallStart).count();

  if (times) {
    stamps.read(*times);
    times->wallMs = wallMs;
  }
  if (packJob) packJob->download();

  return downloadClusteredTree("lbvh-gpu", treeBuffers(b.ids.data()), n);
}

}  // namespace bvhlab::gpubuild
