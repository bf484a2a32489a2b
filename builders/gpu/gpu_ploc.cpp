// ploc-gpu's passes and download (builders/gpu/gpu_ploc.hpp).
#include "builders/gpu/gpu_ploc.hpp"

#include <array>
#include <chrono>
#include <optional>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/gpu/gpu_build_steps.hpp"
#include "datasets/scene.hpp"  // InputError
#include "render/gl_context.hpp"

namespace bvhlab::gpubuild {

namespace {

constexpr uint32_t kClusterBytes = 28;  // a cluster as the shaders store it: box (6 floats), node

// gpubuild_ploc_next.glsl's PassState as it lies in the buffer (std430: uvec3 then uints, no padding).
// ticket and done are gpubuild_ploc_fused.glsl's counters (workgroups started, finished), 0 between passes.
struct PassState {
  uint32_t groups = 0, one_y = 1, one_z = 1;  // the indirect dispatch of nn, count and merge
  uint32_t clusters = 0, passes = 0, stuck = 0;
  uint32_t ticket = 0, done = 0;
};
static_assert(sizeof(PassState) == 32);

// gpubuild_ploc_fused.glsl's bit in PassState::stuck when a look-back gave up waiting.
constexpr uint32_t kLookBackGaveUp = 2;
// gpubuild_ploc_fused.glsl's look-back status words keep a count in their low 29 bits.
constexpr uint64_t kFusedMaxPrimitives = uint64_t(1) << 29;

// The passes that take `clusters` down to one when each keeps kKeptPerPass of its clusters (the
// measured rate, gpu_ploc.cpp's pass loop): ceil(ln(clusters) / -ln(kKeptPerPass)), at least 1.
constexpr double kKeptPerPass = 0.8;
uint32_t passesToOne(uint32_t clusters) {
  if (clusters <= 2) return 1;
  return uint32_t(std::ceil(std::log(double(clusters)) / -std::log(kKeptPerPass)));
}

}  // namespace

GpuPloc::GpuPloc(std::optional<GpuLimits> limits, PlocPasses passes)
    : limits_(limits ? *limits : queryGpuLimits()),
      passes_(passes),
      runs_("gpubuild_ploc_runs.glsl"),
      clusters_("gpubuild_ploc_clusters.glsl"),
      nn_("gpubuild_ploc_nn.glsl", "", {"gpubuild_ploc_pairs.glsl"}),
      count_("gpubuild_ploc_count.glsl"),
      scan_("gpubuild_scan.glsl"),
      scanPass_("gpubuild_scan.glsl", "#define COUNT_FROM_PASS_STATE 1\n"),
      merge_("gpubuild_ploc_merge.glsl", "", {"gpubuild_ploc_pairs.glsl"}),
      next_("gpubuild_ploc_next.glsl"),
      collapse_("gpubuild_collapse.glsl", "", {"gpubuild_tree_area.glsl"}) {
  if (passes_ == PlocPasses::Fused) fused_.emplace("gpubuild_ploc_fused.glsl", "", std::vector<std::string>{"gpubuild_ploc_pairs.glsl"});
}

void GpuPloc::checkLimits(size_t n, bool pack) const {
  std::vector<std::pair<const char*, uint64_t>> buffers = sharedBuildBuffers(n, pack);
  buffers.push_back({"clusters", uint64_t(n) * kClusterBytes});
  checkBuildLimits(name(), n, limits_, buffers);
  if (passes_ == PlocPasses::Fused && n >= kFusedMaxPrimitives)
    throw InputError(std::string(name()) + ": " + std::to_string(n) + " primitives; its pass counts clusters in 29 bits (" +
                     std::to_string(kFusedMaxPrimitives) + " primitives at most)");
}

Bvh GpuPloc::build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
                   const GpuPackRequest* pack) const {
  checkGpuOptions(name(), options, /*radius=*/true);
  const uint32_t radius = options.plocRadius;
  const size_t count = input.boxes.size();
  checkLimits(count, pack != nullptr);
  if (times) *times = GpuPhaseTimes{};
  const uint32_t n = uint32_t(count);
  if (n == 1) return onePrimitiveTree(input, pack);  // ploc's tree: one leaf; nothing to sort or cluster
  const uint32_t blocks = groupsFor(n);

  enum { kClustersA = kSharedBuffers, kClustersB, kNearest, kSums, kState, kStatus, kBuffers };
  BuildBuffers<kBuffers, 8> b;
  const auto wallStart = std::chrono::steady_clock::now();
  const bool soupBoxes = pack && pack->boxesFromSoup;  // the boxes pass fills them (phase `boxes`)
  makeSharedBuffers(b.ids.data(), input, soupBoxes);
  const uint32_t zero = 0;
  b.ids[kClustersA] = makeStorageBuffer(uint64_t(n) * kClusterBytes);
  b.ids[kClustersB] = makeStorageBuffer(uint64_t(n) * kClusterBytes);
  b.ids[kNearest] = makeStorageBuffer(uint64_t(n) * 4);  // the runs' slots, then each pass's neighbours
  const bool fused = passes_ == PlocPasses::Fused;
  if (fused) {  // the look-back's status words: kept and merged per workgroup, 0 = not yet written
    b.ids[kStatus] = makeStorageBuffer(uint64_t(2 * blocks) * 4);
    glClearNamedBufferData(b.ids[kStatus], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  }
  b.ids[kSums] = makeStorageBuffer(uint64_t(2 * blocks) * 4);
  const PassState initial;
  b.ids[kState] = makeStorageBuffer(sizeof initial, &initial);
  uint32_t issued = 0, readbacks = 0;
  checkGl((std::string(name()) + ": uploading the input").c_str());

  auto bind = [&](std::initializer_list<int> which) {
    GLuint slot = 0;
    for (int w : which) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot++, b.ids[w]);
  };
  std::optional<GpuPackJob> packJob;  // the soup uploaded before the timed phases
  if (pack) packJob.emplace(packer_, *pack, n);
  PhaseStamps stamps;
  if (soupBoxes) packJob->soupBoxes(b.ids[kBoxes], b.ids[kCentroids], stamps);
  morton_.run(name(), n, options.mortonGrid, b.ids[kCentroids], b.ids[kBoundKeys], b.ids[kGrid], b.ids[kKeys]);
  stamps.mark("morton");
  // sort
  sort_.sort(b.ids[kKeys], b.ids[kScratch], b.ids[kCounts], n);
  stamps.mark("sort");
  // clusters: leaves, runs counted, scanned, one tree per run
  bind({kKeys, kBoxes, kNodeBoxes, kSums});
  runs_.set("u_count", n);
  runs_.dispatch(blocks, pass("clusters: leaves and runs of equal codes (gpubuild_ploc_runs.glsl)").c_str());
  bind({kSums});
  scan_.set("u_count", 2 * blocks);
  scan_.dispatch(1, pass("clusters: scan (gpubuild_scan.glsl)").c_str());
  bind({kKeys, kNodeBoxes, kChildren, kParents, kNearest, kSums, kClustersA});
  clusters_.set("u_count", n);
  clusters_.dispatch(blocks, pass("clusters: a tree per run of equal codes (gpubuild_ploc_clusters.glsl)").c_str());
  stamps.mark("clusters");

  // Clustering passes until one cluster is left (each merges at least one pair: builders/ploc.cpp),
  // each nn, count, scan, merge and next (the pass state, on the GPU), dispatched indirectly from the
  // state. The CPU reads the state back once per batch of passes, not once per pass: a pass keeps about
  // 0.8 of its clusters (measured: 0.72 to 0.83 per pass on the armadillo at radius 16, 44 passes), so
  // a batch is the passes that would take its clusters down to one at that rate; passes issued after
  // the last one dispatch 0 workgroups.
  bind({kSums});
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, b.ids[kState]);
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, b.ids[kState]);
  next_.set("u_first", blocks);
  next_.dispatch(1, pass("clusters: the first pass state (gpubuild_ploc_next.glsl)").c_str());
  next_.set("u_first", 0u);
  nn_.set("u_radius", radius);
  if (fused_) {
    fused_->set("u_radius", radius);
    fused_->set("u_giveUpPass", giveUpPass_);
  }
  PassState state;
  state.clusters = n;  // at most; the runs of equal codes make fewer
  int from = kClustersA, to = kClustersB;
  // One clustering pass of the split kernels from `from` into `to`.
  auto splitPass = [&](int from, int to) {
    bind({from, kNearest});
    nn_.dispatchIndirect(0, pass("nn: nearest neighbours (gpubuild_ploc_nn.glsl)").c_str());
    stamps.mark("nn");
    bind({kNearest, kSums});
    count_.dispatchIndirect(0, pass("merge: counts (gpubuild_ploc_count.glsl)").c_str());
    bind({kSums});
    scanPass_.dispatch(1, pass("merge: scan (gpubuild_scan.glsl)").c_str());
    bind({from, kNearest, kSums, to, kNodeBoxes, kChildren, kParents});
    merge_.dispatchIndirect(0, pass("merge: merge and compact (gpubuild_ploc_merge.glsl)").c_str());
    bind({kSums});
    next_.dispatch(1, pass("merge: the next pass state (gpubuild_ploc_next.glsl)").c_str());
    stamps.mark("merge");
  };
  auto readState = [&] {
    glGetNamedBufferSubData(b.ids[kState], 0, sizeof state, &state);
    checkGl((std::string(name()) + ": reading the pass state back").c_str());
    stamps.mark("readback");
    ++readbacks;
  };
  uint32_t fallbacks = 0;
  while (state.clusters > 1) {
    const uint32_t batch = passesToOne(state.clusters);
    for (uint32_t k = 0; k < batch; ++k) {
      if (fused) {
        bind({from, to, kNodeBoxes, kChildren, kParents, kStatus});
        fused_->dispatchIndirect(0, pass("passes: one fused clustering pass (gpubuild_ploc_fused.glsl)").c_str());
        stamps.mark("passes");
      } else {
        splitPass(from, to);
      }
      std::swap(from, to);
    }
    // A batch past the last pass still swaps: the last pass's output is not needed, only its nodes.
    readState();
    issued += batch;
    if (state.stuck & kLookBackGaveUp) {
      // A fused pass whose look-back gave up wrote no cluster it could not place and left the state as
      // it was; the passes after it dispatched nothing. It runs again with the split kernels, from its
      // input: clusters A after an even number of passes, B after an odd one.
      ++fallbacks;
      from = state.passes % 2 == 0 ? kClustersA : kClustersB;
      to = from == kClustersA ? kClustersB : kClustersA;
      state.stuck = 0;
      state.groups = groupsFor(state.clusters);
      state.ticket = state.done = 0;
      glNamedBufferSubData(b.ids[kState], 0, sizeof state, &state);
      glClearNamedBufferData(b.ids[kStatus], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
      splitPass(from, to);
      std::swap(from, to);
      ++issued;
      readState();
    }
    if (state.stuck)
      throw std::runtime_error(pass("merge: pass ") + std::to_string(state.passes + 1) + " over " +
                               std::to_string(state.clusters) + " clusters merged none");
  }
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, 0);

  runCollapse(collapse_, b.ids.data(), n, options, name());
  stamps.mark("collapse");
  if (packJob) packJob->run(treeBuffers(b.ids.data()), stamps);
  checkGl((std::string(name()) + ": timer queries").c_str());
  glFinish();
  const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wallStart).count();
  if (times) {
    stamps.read(*times);
    times->wallMs = wallMs;
    times->passes = state.passes;
    times->passesIssued = issued;
    times->readbacks = readbacks;
    times->fusedFallbacks = fallbacks;
  }
  if (packJob) packJob->download();

  return downloadClusteredTree(name(), treeBuffers(b.ids.data()), n);
}

}  // namespace bvhlab::gpubuild
