// The GPU pack into layout cwbvh (layout/layout_cwbvh.hpp): a GPU builder's collapsed binary tree,
// still in its build buffers, collapsed to width 8 and packed by compute passes into the streams
// layout/pack_cwbvh.cpp writes for the tree the build downloads, texel for texel. Timed inside the
// builders' `pack` phase, after the binary pack's edges, pointer jumping and v1 triangle order
// (builders/gpu/gpu_pack.hpp), which it reads:
//   leaf cap   the collapsed tree's largest leaf (gpubuild_wide_leafcap.glsl)
//   costs      the SAH-optimal collapse's dynamic program bottom-up, with the wide nodes each choice
//              makes (gpubuild_wide_costs.glsl)
//   levels     top-down, one indirect dispatch per level of the wide tree: children, grid, slots by
//              octant, quantised bytes, and each inner child's step for the numbering
//              (gpubuild_wide_level.glsl, gpubuild_wide_gate.glsl); at most kMaxWideLevels levels
//   numbering  pointer jumping over the wide nodes (gpubuild_pack_jump.glsl)
//   nodes      each node's 5 texels at its index, its leaves' triangles copied from v1's order
//              (gpubuild_wide_nodes.glsl)
// This is the SAH collapse the CPU uses for every wide layout (Ylitie, Karras & Laine 2017), not
// H-PLOC's greedy conversion, so that a GPU build gives the CPU's cwbvh streams of the same tree.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <utility>

#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_pack.hpp"

namespace bvhlab::gpubuild {

// Level dispatches issued: wide trees up to this depth. A deeper one is an error at download. The wide
// tree is at most as deep as the collapsed binary tree, and a Morton builder's binary tree is at most
// 63 levels of code bits plus the balanced trees of equal-code runs; 64 wide levels are far past the
// trees of any scene here (a wide node spans two or more binary levels wherever it has more than two
// children). Empty level dispatches cost a GPU only their launch.
constexpr uint32_t kMaxWideLevels = 64;

// The programs, compiled once per packer, on its first cwbvh pack.
struct WidePackPrograms {
  WidePackPrograms();
  ComputeProgram leafCap, costs, level, levelGate, nodes;
};

// The buffers and passes of one build's cwbvh pack.
class GpuWidePack {
 public:
  // The storage buffers a cwbvh pack of n primitives adds to the binary pack's (for the limit check).
  static std::array<std::pair<const char*, uint64_t>, 10> buffers(uint64_t n);
  // Refuses, before any work, a pack whose buffers exceed `limits`: an InputError naming the buffer
  // and GL_MAX_SHADER_STORAGE_BLOCK_SIZE.
  static void checkLimits(uint64_t n, const GpuLimits& limits);
  explicit GpuWidePack(uint32_t primitives);
  ~GpuWidePack();
  GpuWidePack(const GpuWidePack&) = delete;
  GpuWidePack& operator=(const GpuWidePack&) = delete;

  // v1's triangle streams, which the binary pack's triangle pass fills for this pack to reorder.
  GLuint v1Triangles() const { return ids_[kV1Triangles]; }
  GLuint v1Attributes() const { return ids_[kV1Attributes]; }

  // The passes. `binarySteps` and `binaryState` are the binary pack's path sums and state; the streams
  // are written to `nodeStream` (5 texels per wide node, room for n - 1), `triangleStream` and
  // `attributeStream` (3 and 4 texels per primitive).
  void run(const WidePackPrograms& programs, const ComputeProgram& jump, const ComputeProgram& jumpGate,
           const GpuTreeBuffers& tree, GLuint binarySteps, GLuint binaryState, GLuint nodeStream, GLuint triangleStream,
           GLuint attributeStream, PhaseStamps& stamps) const;

  // After run: the wide nodes written and PackedBvh::depth. Throws std::runtime_error for a wide tree
  // deeper than kMaxWideLevels, a root whose half area overflows a float, or a leaf of more triangles
  // than layout cwbvh stores (the last two as packCwbvh does).
  std::pair<uint32_t, uint32_t> nodesAndDepth() const;

 private:
  enum { kCosts, kCounts, kDecisions, kCounters, kState, kJumpState, kQueue, kSteps, kAncestors, kScratch,
         kV1Triangles, kV1Attributes, kBuffers };
  uint32_t n_ = 0, bound_ = 0;
  std::array<GLuint, kBuffers> ids_{};
};

}  // namespace bvhlab::gpubuild
