// hploc-gpu: H-PLOC's tree (builders/hploc.hpp; the CPU's `hploc`, node for node), built by GLSL
// compute passes in the current GL context. Phases (each timed by GL timestamp queries):
//   morton     centroid bounds, grid and codes: lbvh-gpu's passes (builders/gpu/gpu_morton.hpp)
//   sort       lbvh-gpu's stable radix sort by (code, index) (builders/gpu/gpu_radix_sort.hpp)
//   hierarchy  one dispatch: the radix tree climbed bottom-up and the subtrees clustered by ploc's
//              passes within workgroups of 32, boxes included (gpubuild_hploc.glsl); the phase
//              holds what lbvh-gpu's hierarchy and fit phases do, and all of ploc-gpu's clustering
//   collapse   lbvh-gpu's SAH leaf collapse, bottom-up (gpubuild_collapse.glsl)
//   pack       with a pack request: into v1 or bvh2-cb on the GPU (builders/gpu/gpu_pack.hpp)
// Nothing is read back between the phases: one dispatch does what ploc-gpu's passes and readbacks do.
// The download (untimed) reads the tree back and emits the collapsed tree as builders/collapse.hpp
// emits it. cwbvh is packed on the CPU from the downloaded tree, as for the other GPU builders (the
// paper's one-launch wide conversion is not implemented).
#pragma once
#include <optional>

#include "builders/bvh.hpp"
#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_lbvh.hpp"  // GpuPhaseTimes
#include "builders/gpu/gpu_morton.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_radix_sort.hpp"

namespace bvhlab::gpubuild {

class GpuHploc {
 public:
  // Compiles the passes in the current context; `limits` replaces the implementation's (tests).
  explicit GpuHploc(std::optional<GpuLimits> limits = std::nullopt);

  // Throws InputError naming GL_MAX_SHADER_STORAGE_BLOCK_SIZE or GL_MAX_COMPUTE_WORK_GROUP_COUNT when
  // the input needs more than the limits allow (before any GL work), std::invalid_argument for a
  // radius outside 1..kMaxPlocRadius, Morton size bits or plocTopDown (not implemented on the GPU),
  // std::runtime_error naming the pass for a GL error.
  // With `pack`, the tree is also packed on the GPU (phase `pack`) and the streams downloaded into
  // pack->out.
  Bvh build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times = nullptr,
            const GpuPackRequest* pack = nullptr) const;

  // The check build() makes first.
  void checkLimits(size_t primitives, bool pack = false) const;

 private:
  GpuLimits limits_;
  MortonPasses morton_;
  ComputeProgram hierarchy_, collapse_;
  GpuRadixSort sort_;
  GpuPacker packer_;
};

}  // namespace bvhlab::gpubuild
