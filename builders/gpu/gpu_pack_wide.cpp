// The GPU pack into cwbvh, host side (builders/gpu/gpu_pack_wide.hpp).
#include "builders/gpu/gpu_pack_wide.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "builders/bvh.hpp"
#include "builders/gpu/gpu_build_steps.hpp"
#include "layout/layout_cwbvh.hpp"
#include "render/gl_context.hpp"

namespace bvhlab::gpubuild {

namespace {

// gpubuild_wide_state.glsl's WideState as it lies in the buffer (std430: a uvec3 at 0, uints from 12, a
// uvec3 at 48).
struct WideState {
  uint32_t levelGroups[3] = {1, 1, 1};  // the next level's indirect dispatch (the root's level first)
  uint32_t levelBegin = 0, levelEnd = 1, queued = 1;  // the level's queue entries; all entries so far
  uint32_t leafCap = 1;                 // the collapsed tree's largest leaf (at least 1, as on the CPU)
  uint32_t largestLeaf = 0;             // the largest leaf slot past kCwbvhMaxLeaf (0: none)
  uint32_t levels = 0, rootInfinite = 0, pad[2] = {0, 0};
  uint32_t nodeGroups[3] = {0, 1, 1};   // the node pass's indirect dispatch, set when the levels end
  uint32_t pad3 = 0;
};
static_assert(sizeof(WideState) == 64 && offsetof(WideState, nodeGroups) == 48);

// gpubuild_pack_*.glsl's PackState (builders/gpu/gpu_pack.cpp): the wide numbering's jumping rounds
// get their workgroups from the level gate.
struct JumpState {
  uint32_t groups = 0, one_y = 1, one_z = 1, unfinished = 0, finalHalf = 0, depth = 0;
};
static_assert(sizeof(JumpState) == 24);

}  // namespace

WidePackPrograms::WidePackPrograms()
    : leafCap("gpubuild_wide_leafcap.glsl", "", {"gpubuild_wide_state.glsl"}),
      costs("gpubuild_wide_costs.glsl", "",
            {"gpubuild_wide_state.glsl", "gpubuild_tree_area.glsl", "gpubuild_exact_division.glsl"}),
      level("gpubuild_wide_level.glsl", "", {"gpubuild_wide_state.glsl"}),
      levelGate("gpubuild_wide_gate.glsl", "", {"gpubuild_wide_state.glsl"}),
      nodes("gpubuild_wide_nodes.glsl", "", {"gpubuild_wide_state.glsl"}) {}

std::array<std::pair<const char*, uint64_t>, 10> GpuWidePack::buffers(uint64_t n) {
  const uint64_t inner = std::max<uint64_t>(1, n - 1);  // wide nodes are at most the binary inner nodes
  return {{{"wide costs (cwbvh pack)", inner * 64},
           {"wide node counts (cwbvh pack)", inner * 32},
           {"wide decisions (cwbvh pack)", inner * 8},
           {"wide queue (cwbvh pack)", inner * 16},
           {"wide path sums (cwbvh pack)", 2 * inner * 16},
           {"wide scratch (cwbvh pack)", 7 * inner * 16},
           {"node stream (cwbvh pack)", 5 * inner * 16},
           {"v1 triangle stream (cwbvh pack)", n * 3 * 16},
           {"v1 attribute stream (cwbvh pack)", n * 4 * 16},
           {"wide ancestors (cwbvh pack)", 2 * inner * 4}}};
}

void GpuWidePack::checkLimits(uint64_t n, const GpuLimits& limits) {
  for (const auto& [what, bytes] : buffers(n))
    if (bytes > limits.maxStorageBlockBytes)
      throw InputError("GPU pack: " + std::to_string(n) + " primitives need a " + std::to_string(bytes) +
                       "-byte shader storage buffer (" + what + "); GL_MAX_SHADER_STORAGE_BLOCK_SIZE is " +
                       std::to_string(limits.maxStorageBlockBytes) + " bytes here");
}

GpuWidePack::GpuWidePack(uint32_t primitives) : n_(primitives), bound_(std::max<uint32_t>(1, primitives - 1)) {
  const uint64_t inner = bound_;
  ids_[kCosts] = makeStorageBuffer(inner * 64);
  ids_[kCounts] = makeStorageBuffer(inner * 32);
  ids_[kDecisions] = makeStorageBuffer(inner * 8);
  ids_[kCounters] = makeStorageBuffer(inner * 4);
  const WideState state;
  ids_[kState] = makeStorageBuffer(sizeof state, &state);
  const JumpState jump;
  ids_[kJumpState] = makeStorageBuffer(sizeof jump, &jump);
  ids_[kQueue] = makeStorageBuffer(inner * 16);
  ids_[kSteps] = makeStorageBuffer(2 * inner * 16);
  ids_[kAncestors] = makeStorageBuffer(2 * inner * 4);
  ids_[kScratch] = makeStorageBuffer(7 * inner * 16);
  ids_[kV1Triangles] = makeStorageBuffer(uint64_t(primitives) * 3 * 16);
  ids_[kV1Attributes] = makeStorageBuffer(uint64_t(primitives) * 4 * 16);
  // The root's queue entry (binary node 0, no parent) and its zero step; every other entry's ancestor
  // starts as none, so that the jumping rounds' invocations past the last entry change nothing.
  const uint32_t none = 0xffffffffu, zero = 0;
  const glm::uvec4 root{0u, none, 0u, 0u}, step{0u};
  glNamedBufferSubData(ids_[kQueue], 0, sizeof root, &root);
  glNamedBufferSubData(ids_[kSteps], 0, sizeof step, &step);
  glClearNamedBufferData(ids_[kAncestors], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &none);
  glClearNamedBufferData(ids_[kCounters], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  checkGl("GPU pack (cwbvh): making the buffers");
}

GpuWidePack::~GpuWidePack() { glDeleteBuffers(GLsizei(ids_.size()), ids_.data()); }

void GpuWidePack::run(const WidePackPrograms& programs, const ComputeProgram& jump, const ComputeProgram& jumpGate,
                      const GpuTreeBuffers& tree, GLuint binarySteps, GLuint binaryState, GLuint nodeStream,
                      GLuint triangleStream, GLuint attributeStream, PhaseStamps& stamps) const {
  auto bind = [](std::initializer_list<GLuint> buffers) {
    GLuint slot = 0;
    for (GLuint b : buffers) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot++, b);
  };
  const uint32_t nodes = 2 * n_ - 1;
  bind({tree.parents, tree.info, ids_[kState]});
  programs.leafCap.set("u_nodes", nodes);
  programs.leafCap.dispatch(groupsFor(nodes), "GPU pack (cwbvh) leaf cap (gpubuild_wide_leafcap.glsl)");

  bind({tree.children, tree.parents, tree.nodeBoxes, tree.info, ids_[kCosts], ids_[kCounts], ids_[kDecisions],
        ids_[kCounters], ids_[kState]});
  const CostModel cost;  // the CPU collapses every wide layout with the default model (layout/collapse_v1.cpp)
  programs.costs.set("u_count", n_);
  programs.costs.set("u_ct", cost.traversalCost);
  programs.costs.set("u_ci", cost.intersectionCost);
  programs.costs.dispatch(groupsFor(n_), "GPU pack (cwbvh) costs: the wide collapse (gpubuild_wide_costs.glsl)");
  stamps.mark("wide_costs");

  programs.level.set("u_count", n_);
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, ids_[kState]);
  for (uint32_t level = 0; level < kMaxWideLevels; ++level) {
    bind({tree.children, tree.nodeBoxes, tree.info, ids_[kCounts], ids_[kDecisions], binarySteps, binaryState,
          ids_[kState], ids_[kQueue], ids_[kSteps], ids_[kAncestors], ids_[kScratch]});
    programs.level.dispatchIndirect(0, "GPU pack (cwbvh) level: one level of wide nodes (gpubuild_wide_level.glsl)");
    bind({ids_[kState], ids_[kJumpState]});
    programs.levelGate.dispatch(1, "GPU pack (cwbvh) level gate (gpubuild_wide_gate.glsl)");
  }
  stamps.mark("wide_levels");

  bind({ids_[kSteps], ids_[kAncestors], ids_[kJumpState]});
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, ids_[kJumpState]);
  jump.set("u_nodes", bound_);
  for (uint32_t round = 0; round < kMaxJumpRounds; ++round) {
    jump.set("u_from", round % 2);
    jump.dispatchIndirect(0, "GPU pack (cwbvh) numbering: a pointer-jumping round (gpubuild_pack_jump.glsl)");
    jumpGate.set("u_wrote", 1 - round % 2);
    jumpGate.dispatch(1, "GPU pack (cwbvh) numbering: the gate (gpubuild_pack_gate.glsl)");
  }

  bind({ids_[kState], ids_[kQueue], ids_[kSteps], ids_[kJumpState], ids_[kScratch], ids_[kV1Triangles],
        ids_[kV1Attributes], nodeStream, triangleStream, attributeStream});
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, ids_[kState]);
  programs.nodes.set("u_bound", bound_);
  programs.nodes.dispatchIndirect(offsetof(WideState, nodeGroups),
                                  "GPU pack (cwbvh) nodes: the node and triangle streams (gpubuild_wide_nodes.glsl)");
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  stamps.mark("wide_nodes");
}

std::pair<uint32_t, uint32_t> GpuWidePack::nodesAndDepth() const {
  WideState state;
  glGetNamedBufferSubData(ids_[kState], 0, sizeof state, &state);
  checkGl("GPU pack (cwbvh): reading the state");
  if (state.levelGroups[0] != 0)
    throw std::runtime_error("GPU pack (cwbvh): the wide tree is deeper than " + std::to_string(kMaxWideLevels) +
                             " levels (kMaxWideLevels level dispatches); pack it on the CPU (layout/pack_cwbvh.cpp)");
  if (state.rootInfinite != 0)
    throw std::runtime_error("GPU pack (cwbvh): the root box's half area overflows a float; the wide collapse "
                             "refuses it, as collapseWide does (\"the root box is not finite\")");
  if (state.largestLeaf > kCwbvhMaxLeaf)
    throw std::runtime_error("packCwbvh: a leaf of " + std::to_string(state.largestLeaf) +
                             " triangles; layout cwbvh stores at most " + std::to_string(kCwbvhMaxLeaf) +
                             " per leaf (a 7-bit count): build with --leaf-size " + std::to_string(kCwbvhMaxLeaf) +
                             " or less");
  return {state.queued, state.levels + 1};
}

}  // namespace bvhlab::gpubuild
