// The GPU pack: a GPU builder's tree, still in its build buffers, packed into layout v1, bvh2-cb or
// cwbvh (layout/layout.hpp, layout/layout_bvh2cb.hpp, layout/layout_cwbvh.hpp) by compute passes, so that a build on the GPU gives
// the streams a renderer binds without a round trip through the CPU. Timed as the builders' `pack`
// phase (builders/gpu/gpu_lbvh.hpp, gpu_ploc.hpp):
//   edges      every node's step from its parent: v1 slot, bvh2-cb record and first-primitive offsets,
//              depth, and whether a collapsed leaf hides it (gpubuild_pack_edges.glsl)
//   jump       pointer-jumping rounds until every node holds the sum over its path from the root, each
//              round dispatched indirectly and stopped on the GPU once done (gpubuild_pack_jump.glsl,
//              gpubuild_pack_gate.glsl): ceil(log2(depth)) rounds, at most kMaxJumpRounds
//   nodes      the NODE stream (gpubuild_pack_nodes.glsl, one program per layout)
//   triangles  the TRIANGLE and ATTRIBUTE streams in leaf order, gathered from the soup's texels
//              (gpubuild_pack_triangles.glsl)
// cwbvh takes the edges, the jumping and v1's triangle order, and goes on to the wide collapse and its
// packing instead of the node pass (builders/gpu/gpu_pack_wide.hpp).
// The streams are those layout/pack.cpp and pack_bvh2cb.cpp write for the Bvh the build downloads,
// (pack_cwbvh.cpp for cwbvh) texel for texel (tests/test_gpu_pack.cpp). The soup's texels (7 per triangle, in original order) are
// uploaded before the timed phases, as a renderer keeps its triangles resident on the GPU.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "builders/gpu/gpu_compute.hpp"
#include "layout/layout.hpp"

namespace bvhlab::gpubuild {

class PhaseStamps;
struct WidePackPrograms;
class GpuWidePack;

// The layouts the GPU pack writes (with the raw triangle format): v1, bvh2-cb and cwbvh.
bool gpuPackable(const std::string& layout);

// The CPU's pack of `bvh` into a gpuPackable layout: what the GPU pack must equal.
PackedBvh cpuPackFor(const Bvh& bvh, const TriangleSoup& soup, const std::string& layout);

// Rounds of pointer jumping issued: trees up to 2^16 levels deep. A deeper tree is an error at download.
constexpr uint32_t kMaxJumpRounds = 16;

// A build's streams left on the GPU (GpuPackRequest::keep): storage buffers of uvec4 texels, as the
// renderer binds them (render/ray_tracer_gl.hpp setTreeBuffers). The holder deletes them
// (deleteStreams) or hands them to the next build, which deletes them before it fills the struct again.
struct GpuStreamBuffers {
  GLuint node = 0, triangle = 0, attribute = 0;
};
void deleteStreams(GpuStreamBuffers& streams);

// What a build packs and where the downloaded streams go.
struct GpuPackRequest {
  std::string layout;                // gpuPackable
  const TriangleSoup* soup = nullptr;  // the triangles the build's input was made from (same order)
  PackedBvh* out = nullptr;          // filled after the build (untimed download)
  // The soup's texels already on the GPU (uploadSoupTexels; not owned), for repeated builds of one soup;
  // 0: each build uploads them.
  GLuint soupTexels = 0;
  // The build takes its boxes and centroids from the soup's texels on the GPU (phase `boxes`,
  // gpubuild_soup_boxes.glsl: bit for bit the CPU's triangle boxes and centroids) instead of uploading
  // the input's: triangles that are on the GPU already (an animated clip's frame). The input's boxes
  // must be the soup's triangles' (the CPU still validates them before the build).
  bool boxesFromSoup = false;
  // With keep, the streams stay on the GPU after the build: *keep's old buffers are deleted and the new
  // ones put there (the caller owns them). The download into `out` happens all the same.
  GpuStreamBuffers* keep = nullptr;
};

// `soup`'s 7 texels per triangle in original order: its 3 TRIANGLE and 4 ATTRIBUTE texels as
// layout/pack.cpp writes them for the raw format.
std::vector<glm::uvec4> soupTexels(const TriangleSoup& soup);
// A storage buffer holding soupTexels(soup) (the caller deletes it).
GLuint uploadSoupTexels(const TriangleSoup& soup);

// The build buffers the pack reads, as the GPU builders lay them out: children (2 per inner node),
// parents (per node; the root's ~0u), node boxes (6 floats per node), info (count and emitted inner
// nodes per node, from the collapse pass), sorted keys (GpuKey); nodes numbered inner 0 .. n - 2
// (root 0), leaves n - 1 + sorted position.
struct GpuTreeBuffers {
  GLuint children = 0, parents = 0, nodeBoxes = 0, info = 0, keys = 0;
};

// The CPU's pack of `bvh` into request.out (layout/pack.cpp, pack_bvh2cb.cpp): what a GPU builder gives
// for one primitive, where it builds nothing on the GPU (uploaded into request.keep's buffers with keep).
void packOnTheCpu(const Bvh& bvh, const GpuPackRequest& request);

// The pack's programs, compiled once per builder object.
class GpuPacker {
 public:
  GpuPacker();
  ~GpuPacker();
  // The storage buffers a pack of n primitives adds to a build (for checkBuildLimits).
  static std::array<std::pair<const char*, uint64_t>, 6> buffers(uint64_t n);

 private:
  friend class GpuPackJob;
  const WidePackPrograms& widePrograms() const;  // compiled at the first cwbvh pack
  ComputeProgram edges_, jump_, gate_, nodesV1_, nodesBvh2cb_, triangles_, soupBoxes_;
  mutable std::unique_ptr<WidePackPrograms> wide_;
};

// One build's pack: constructed before the timed phases (checks the request, uploads the soup's
// texels, makes the buffers), run() after the collapse pass (marks `pack`), download() after the
// timestamps are read. Throws std::invalid_argument for a layout the GPU does not pack or a soup of
// another size, InputError for cwbvh buffers past GL_MAX_SHADER_STORAGE_BLOCK_SIZE, std::runtime_error
// for a GL error (naming the pass) or a tree deeper than 2^kMaxJumpRounds levels (cwbvh:
// GpuWidePack::nodesAndDepth's errors).
class GpuPackJob {
 public:
  GpuPackJob(const GpuPacker& packer, const GpuPackRequest& request, uint32_t primitives);
  ~GpuPackJob();  // hands the streams to request.keep, or deletes them
  GpuPackJob(const GpuPackJob&) = delete;
  GpuPackJob& operator=(const GpuPackJob&) = delete;
  // With request.boxesFromSoup: the primitives' boxes (6 floats each) and centroids (3 floats) from
  // the soup's texels into the build's buffers (marks `boxes`). Run first, before `morton`.
  void soupBoxes(GLuint boxes, GLuint centroids, PhaseStamps& stamps) const;
  void run(const GpuTreeBuffers& tree, PhaseStamps& stamps);
  void download() const;

 private:
  enum { kSoup, kSteps, kAncestors, kState, kNodeStream, kTriangleStream, kAttributeStream, kBuffers };
  const GpuPacker& packer_;
  GpuPackRequest request_;
  uint32_t n_ = 0;
  GpuTreeBuffers tree_;
  std::array<GLuint, kBuffers> ids_{};  // ids_[kSoup] is 0 where the request's soupTexels are used
  GLuint soup_ = 0;                     // the soup texels the pack reads
  std::unique_ptr<GpuWidePack> wide_;   // layout cwbvh's buffers and passes
};

}  // namespace bvhlab::gpubuild
