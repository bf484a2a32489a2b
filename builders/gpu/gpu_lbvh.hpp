// lbvh-gpu: the CPU lbvh's tree (builders/lbvh.cpp), built by GLSL compute passes in the current GL
// context. Phases (each timed by GL timestamp queries):
//   morton     centroid bounds (atomics), the grid (one invocation, the CPU's float rounding), codes
//   sort       stable radix sort by (code, index) (builders/gpu/gpu_radix_sort.hpp)
//   hierarchy  labels for equal-code runs and Karras's radix tree (gpubuild_labels/hierarchy.glsl)
//   fit        boxes bottom-up with atomic counters
//   collapse   the SAH leaf collapse's counts, inner-node counts and costs, bottom-up likewise
// The download (outside the timed phases) reads the Karras tree and the collapse's results back and
// emits the collapsed tree in the depth-first order builders/collapse.hpp emits: the same Bvh, node
// for node, as `lbvh` (so the same tree_hash).
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "builders/bvh.hpp"
#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_morton.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_radix_sort.hpp"

namespace bvhlab::gpubuild {

// Milliseconds per phase of one build, in the order above; empty when nothing ran on the GPU (one
// primitive).
struct GpuPhaseTimes {
  std::vector<std::pair<std::string, double>> phases;
  // ploc-gpu: the clustering passes that merged, the passes issued (a batch's passes past the last one
  // dispatch nothing) and the CPU's reads of the pass state. 0 for lbvh-gpu, which reads nothing back.
  uint32_t passes = 0, passesIssued = 0, readbacks = 0;
  // plocpp-gpu: fused passes run again with the split kernels because a workgroup's look-back gave up
  // waiting (gpubuild_ploc_fused.glsl; llvmpipe bounds every loop); 0 for the others.
  uint32_t fusedFallbacks = 0;
  // Wall-clock (steady_clock) from the build's first buffer allocation to its last timed pass finished
  // (glFinish): what the build holds up a frame on one timeline, allocations, submissions and ploc-gpu's
  // readbacks included; the download after it is not. 0 where nothing ran on the GPU.
  double wallMs = 0.0;
  double totalMs() const;
};

class GpuLbvh {
 public:
  // Compiles the passes in the current context; `limits` replaces the implementation's (tests).
  explicit GpuLbvh(std::optional<GpuLimits> limits = std::nullopt);

  // Throws InputError naming GL_MAX_SHADER_STORAGE_BLOCK_SIZE or GL_MAX_COMPUTE_WORK_GROUP_COUNT when
  // the input needs more than the limits allow (before any GL work), std::invalid_argument for Morton
  // size bits (not implemented on the GPU), std::runtime_error naming the pass for a GL error.
  // With `pack`, the tree is also packed on the GPU (builders/gpu/gpu_pack.hpp; phase `pack`) and the
  // streams downloaded into pack->out.
  Bvh build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times = nullptr,
            const GpuPackRequest* pack = nullptr) const;

  // The check build() makes first.
  void checkLimits(size_t primitives, bool pack = false) const;

 private:
  GpuLimits limits_;
  MortonPasses morton_;
  ComputeProgram labels_, hierarchy_, fit_, collapse_;
  GpuRadixSort sort_;
  GpuPacker packer_;
};

}  // namespace bvhlab::gpubuild
