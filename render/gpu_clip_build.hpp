// An animated clip's per-frame rebuild kept on the GPU: `trace --update rebuild` with a GPU builder
// (lbvh-gpu, ploc-gpu) into layout v1 or bvh2-cb with raw triangles. The builder's programs are compiled
// once for the clip; each frame its triangles go to the GPU once (the GPU pack's soup texels, in a
// buffer kept for the clip), and the boxes, the tree and the layout's streams are made there by compute
// passes, which the tracer then binds as they lie (GlRayTracer::setTreeBuffers): nothing goes back
// through the CPU between a frame's vertices and its traced tree. The tree and its streams are also
// downloaded, after the timing, for the frame's statistics and checks (SAH, tree_hash, stack depth).
//
// The GPU builders' library sits above this one (as for render/gpu_build_timing.hpp), so it hands its
// factory in at registration (registerGpuBuilders) through setGpuClipBuilderFactory.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "builders/bvh.hpp"
#include "layout/layout.hpp"

namespace bvhlab {

// One frame's build on the GPU.
struct GpuClipFrame {
  Bvh tree;          // downloaded after the timing
  PackedBvh packed;  // the streams, downloaded likewise
  // The streams on the GPU (node, triangle, attribute storage buffers of uvec4 texels): the builder's,
  // valid until its next build.
  unsigned streams[3] = {0, 0, 0};
  double uploadMs = 0.0;  // the frame's soup texels into the clip's buffer: glFinish, then steady_clock to glFinish
  // The build and pack from that buffer, wall-clock: from the first buffer allocation to the end of the
  // last pass (glFinish), readbacks of ploc-gpu's pass state included, the download not.
  double buildMs = 0.0;
  double gpuMs = 0.0;  // the same passes by GL timestamps (the sum of `phases`)
  std::vector<std::pair<std::string, double>> phases;
};

class GpuClipBuilder {
 public:
  virtual ~GpuClipBuilder() = default;
  // Builds the frame's tree from `soup` (the same triangle count every frame) in the current context.
  // Throws InputError for non-finite vertices (checked on the CPU first, untimed), as the CPU builders.
  virtual GpuClipFrame build(const TriangleSoup& soup) = 0;
};

// (builder, options, layout): a GPU clip builder, or nullptr where the builder is not a GPU builder or
// the GPU does not pack `layout`. Made without a GL context: its first build compiles its programs in
// the context current then, and every later build must run in that one.
using GpuClipBuilderFactory =
    std::function<std::unique_ptr<GpuClipBuilder>(const std::string&, const BuildOptions&, const std::string&)>;
void setGpuClipBuilderFactory(GpuClipBuilderFactory factory);

// The factory's builder for raw triangles, or nullptr (another triangle format, no factory registered,
// a CPU builder, a layout the GPU does not pack).
std::unique_ptr<GpuClipBuilder> makeGpuClipBuilder(const std::string& builder, const BuildOptions& options,
                                                   const std::string& layout, const std::string& triangleFormat);

}  // namespace bvhlab
