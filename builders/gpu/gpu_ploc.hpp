// ploc-gpu: the CPU ploc's tree (builders/ploc.cpp, BuildOptions::plocRadius; without plocTopDown),
// built by GLSL compute passes in the current GL context. Phases (each timed by GL timestamp queries):
//   morton    centroid bounds, grid and codes: lbvh-gpu's passes (gpubuild_bounds/grid/morton.glsl)
//   sort      lbvh-gpu's stable radix sort by (code, index) (builders/gpu/gpu_radix_sort.hpp)
//   clusters  the leaves and one balanced tree per run of equal codes (gpubuild_ploc_runs/clusters.glsl)
//   nn        per clustering pass: every cluster's nearest neighbour within the radius (gpubuild_ploc_nn.glsl)
//   merge     per pass: mutual pairs merge, the clusters compacted by a prefix scan, the next pass's
//             count and workgroups written on the GPU (gpubuild_ploc_count.glsl, gpubuild_scan.glsl,
//             gpubuild_ploc_merge.glsl, gpubuild_ploc_next.glsl); passes are dispatched indirectly
//   readback  per batch of passes: the GPU idle while the CPU reads the pass state back (24 bytes),
//             which decides whether another batch is issued (GpuPhaseTimes::readbacks: how many)
//   collapse  lbvh-gpu's SAH leaf collapse, bottom-up (gpubuild_collapse.glsl)
// Nodes are numbered as the CPU numbers them (leaves n - 1 + sorted position, inner nodes downwards
// from n - 2 as they are made, the root at 0), merges within a pass in order. The download (untimed)
// reads the tree back and emits the collapsed tree as builders/collapse.hpp emits it: the same Bvh,
// node for node, as `ploc` at the same radius (so the same tree_hash).
//
// plocpp-gpu (PlocPasses::Fused): the same build with each clustering pass one dispatch instead of five
// (gpubuild_ploc_fused.glsl: PLOC++'s fused pass, compaction by a single-pass scan with decoupled
// look-back); its phase `passes` replaces `nn` and `merge`. The same tree, node for node.
#pragma once
#include <optional>
#include <string>

#include "builders/bvh.hpp"
#include "builders/gpu/gpu_morton.hpp"
#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_lbvh.hpp"  // GpuPhaseTimes
#include "builders/gpu/gpu_radix_sort.hpp"

namespace bvhlab::gpubuild {

// How a clustering pass is dispatched: nn, count, scan, merge and next (ploc-gpu), or one fused
// kernel (plocpp-gpu).
enum class PlocPasses { Split, Fused };

class GpuPloc {
 public:
  // Compiles the passes in the current context; `limits` replaces the implementation's (tests).
  explicit GpuPloc(std::optional<GpuLimits> limits = std::nullopt, PlocPasses passes = PlocPasses::Split);
  const char* name() const { return passes_ == PlocPasses::Fused ? "plocpp-gpu" : "ploc-gpu"; }

  // Throws InputError naming GL_MAX_SHADER_STORAGE_BLOCK_SIZE or GL_MAX_COMPUTE_WORK_GROUP_COUNT when
  // the input needs more than the limits allow (before any GL work), std::invalid_argument for a
  // radius outside 1..kMaxPlocRadius and for Morton size bits or plocTopDown (not implemented on the
  // GPU), std::runtime_error naming the pass for a GL error.
  // With `pack`, the tree is also packed on the GPU (builders/gpu/gpu_pack.hpp; phase `pack`) and the
  // streams downloaded into pack->out.
  Bvh build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times = nullptr,
            const GpuPackRequest* pack = nullptr) const;

  // Tests only (plocpp-gpu): in every later build, the fused pass that starts after `passes` passes has
  // a workgroup give up its look-back at once, so that pass runs again with the split kernels (the tree
  // is the same). ~0u (the default): never.
  void giveUpInPass(uint32_t passes) { giveUpPass_ = passes; }

  // The check build() makes first.
  void checkLimits(size_t primitives, bool pack = false) const;

 private:
  std::string pass(const char* what) const { return std::string(name()) + " " + what; }  // a pass's label
  GpuLimits limits_;
  PlocPasses passes_;
  MortonPasses morton_;
  ComputeProgram runs_, clusters_, nn_, count_, scan_, scanPass_, merge_, next_, collapse_;
  std::optional<ComputeProgram> fused_;
  uint32_t giveUpPass_ = ~0u;
  GpuRadixSort sort_;
  GpuPacker packer_;
};

}  // namespace bvhlab::gpubuild
