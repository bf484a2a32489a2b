// What the GPU builders' passes share (builders/gpu/gpu_lbvh.cpp, gpu_ploc.cpp, gpu_hploc.cpp): the
// workgroup size of the per-primitive passes, the refusal of sizes past the GL limits, the buffers of
// one build, the per-phase GL timestamps and the untimed download.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <glad/gl.h>

#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_lbvh.hpp"  // GpuPhaseTimes
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_radix_sort.hpp"
#include "builders/bvh.hpp"
#include "datasets/scene.hpp"         // InputError
#include "render/gl_context.hpp"      // isSoftwareRenderer

namespace bvhlab::gpubuild {

constexpr uint32_t kGroup = 256;  // local_size_x of every per-primitive, per-node and per-cluster pass

inline uint32_t groupsFor(uint64_t items) { return uint32_t((items + kGroup - 1) / kGroup); }

// Refuses a dispatch of one invocation per primitive in workgroups of `group` that needs more
// workgroups than `limits` allow: an InputError naming the builder and GL_MAX_COMPUTE_WORK_GROUP_COUNT.
inline void checkWorkGroups(const char* builder, size_t n, const GpuLimits& limits, uint32_t group) {
  const uint64_t groups = (uint64_t(n) + group - 1) / group;
  if (groups > limits.maxWorkGroupsX)
    throw InputError(std::string(builder) + ": " + std::to_string(n) + " primitives need " + std::to_string(groups) +
                     " workgroups of " + std::to_string(group) +
                     " in one dispatch; GL_MAX_COMPUTE_WORK_GROUP_COUNT (x) is " + std::to_string(limits.maxWorkGroupsX) +
                     " here");
}

// Refuses, before any work, a build of n primitives whose storage buffers (what each holds, its bytes)
// or one-dispatch workgroup count exceed `limits`: an InputError naming the builder and the limit.
inline void checkBuildLimits(const char* builder, size_t n, const GpuLimits& limits,
                             const std::vector<std::pair<const char*, uint64_t>>& buffers) {
  for (const auto& [what, bytes] : buffers)
    if (bytes > limits.maxStorageBlockBytes)
      throw InputError(std::string(builder) + ": " + std::to_string(n) + " primitives need a " +
                       std::to_string(bytes) + "-byte shader storage buffer (" + what +
                       "); GL_MAX_SHADER_STORAGE_BLOCK_SIZE is " + std::to_string(limits.maxStorageBlockBytes) +
                       " bytes here");
  checkWorkGroups(builder, n, limits, kGroup);
}

// The storage buffers both GPU builders bind for n primitives (what each holds, its bytes), plus the GPU
// pack's with `pack`: each builder adds its own and checks them all with checkBuildLimits.
inline std::vector<std::pair<const char*, uint64_t>> sharedBuildBuffers(uint64_t n, bool pack) {
  const uint64_t nodes = 2 * n - 1;
  std::vector<std::pair<const char*, uint64_t>> buffers = {{"node boxes", nodes * 24},
                                                           {"primitive boxes", n * 24},
                                                           {"node costs", nodes * 8},
                                                           {"node counts", nodes * 8},
                                                           {"sort keys", n * 12},
                                                           {"radix digit counts", GpuRadixSort::countBytes(uint32_t(n))}};
  if (pack)
    for (const auto& buffer : GpuPacker::buffers(n)) buffers.push_back(buffer);
  return buffers;
}

template <class T>
std::vector<T> download(GLuint buffer, size_t count) {
  std::vector<T> out(count);
  if (count) glGetNamedBufferSubData(buffer, 0, GLsizeiptr(count * sizeof(T)), out.data());
  return out;
}

// The Count buffers of one build, deleted with it; the storage-buffer slots [0, Slots) the passes bind
// are cleared first, so that no binding names a deleted buffer afterwards.
template <size_t Count, GLuint Slots>
struct BuildBuffers {
  std::array<GLuint, Count> ids{};
  BuildBuffers() = default;
  BuildBuffers(const BuildBuffers&) = delete;
  BuildBuffers& operator=(const BuildBuffers&) = delete;
  ~BuildBuffers() {
    for (GLuint slot = 0; slot < Slots; ++slot) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot, 0);
    glDeleteBuffers(GLsizei(ids.size()), ids.data());
  }
};

// GL timestamps between the phases of one build, each followed by glFlush on a software renderer:
// llvmpipe takes a timestamp when it runs its command queue, not where the query was issued (without
// the flush, measured: lbvh-gpu's collapse phase read 0.04 ms and its fit phase took its time). A GPU
// records a timestamp where the command stream reaches it, so there no flush is issued: ploc-gpu marks
// two phases per clustering pass, and a flush each would submit the passes in small pieces, which
// costs the CPU time and can leave the GPU idle between them.
// mark(phase) ends an interval of `phase`; a phase met several times (PLOC's passes) sums its intervals,
// in the order phases first appear. The queries are deleted on every way out, a GL error's included.
class PhaseStamps {
 public:
  PhaseStamps() : flush_(isSoftwareRenderer(reinterpret_cast<const char*>(glGetString(GL_RENDERER)))) { stamp(); }
  ~PhaseStamps() {
    if (!ids_.empty()) glDeleteQueries(GLsizei(ids_.size()), ids_.data());
  }
  PhaseStamps(const PhaseStamps&) = delete;
  PhaseStamps& operator=(const PhaseStamps&) = delete;
  void mark(const char* phase) {
    phases_.push_back(phase);
    stamp();
  }
  void read(GpuPhaseTimes& times) const {
    std::vector<GLuint64> at(ids_.size());
    for (size_t q = 0; q < ids_.size(); ++q) glGetQueryObjectui64v(ids_[q], GL_QUERY_RESULT, &at[q]);
    std::map<std::string, size_t> index;
    for (size_t p = 0; p < phases_.size(); ++p) {
      const auto [it, fresh] = index.emplace(phases_[p], times.phases.size());
      if (fresh) times.phases.emplace_back(phases_[p], 0.0);
      times.phases[it->second].second += double(at[p + 1] - at[p]) * 1e-6;
    }
  }

 private:
  void stamp() {
    GLuint id = 0;
    glGenQueries(1, &id);
    ids_.push_back(id);
    glQueryCounter(id, GL_TIMESTAMP);
    if (flush_) glFlush();
  }
  bool flush_;
  std::vector<GLuint> ids_;
  std::vector<std::string> phases_;
};

// The download (untimed) of a tree whose subtrees need not be ranges of the sorted order (ploc-gpu,
// hploc-gpu) and the depth-first emission of builders/collapse.hpp's emitCollapsed: an emitted inner
// node's children take the slots base, base + 1, then the left child's descendants, then the right's;
// a leaf's primitives are its subtree's full-tree leaves, left first. The buffers are GpuTreeBuffers'
// (root at node 0); a GL error names `builder`.
Bvh downloadClusteredTree(const std::string& builder, const GpuTreeBuffers& tree, uint32_t n);

// The buffers every GPU build makes, at the front of its BuildBuffers in this order (a builder's own
// enum continues from kSharedBuffers): the primitives' boxes and centroids, the centroid bounds' keys,
// the grid, the sort's keys, scratch and digit counts, and the tree (node boxes, children, parents),
// with the collapse's info, costs and counters.
enum SharedBuffer : int { kBoxes, kCentroids, kBoundKeys, kGrid, kKeys, kScratch, kCounts, kNodeBoxes, kChildren,
                          kParents, kInfo, kCosts, kCollapseCounters, kSharedBuffers };
// Makes them in ids[0 .. kSharedBuffers) for n >= 2 primitives: the boxes and centroids uploaded (left
// unset with `soupBoxes`: the pack's boxes pass fills them), the bounds' starting keys, the root's
// parent (node 0) ~0u, the collapse counters 0.
void makeSharedBuffers(GLuint* ids, const BuildInput& input, bool soupBoxes);

// The shared buffers as the pack and the download read them.
inline GpuTreeBuffers treeBuffers(const GLuint* ids) {
  return {ids[kChildren], ids[kParents], ids[kNodeBoxes], ids[kInfo], ids[kKeys]};
}

// The phase `collapse`: builders/collapse.hpp's SAH leaf collapse bottom-up (gpubuild_collapse.glsl)
// over the shared buffers, the pass labelled with `builder`.
void runCollapse(const ComputeProgram& collapse, const GLuint* ids, uint32_t n, const BuildOptions& options,
                 const std::string& builder);

// The tree of one primitive, one leaf, as every builder makes it (packed on the CPU with `pack`): a GPU
// builder runs nothing on the GPU for it.
Bvh onePrimitiveTree(const BuildInput& input, const GpuPackRequest* pack);

// Refuses (std::invalid_argument naming the option) what no GPU builder implements: Morton size bits,
// and for the clustering builders (`radius`: ploc-gpu, plocpp-gpu, hploc-gpu) a radius outside
// 1..kMaxPlocRadius and --ploc-top-down.
void checkGpuOptions(const std::string& builder, const BuildOptions& options, bool radius);

}  // namespace bvhlab::gpubuild
