// The GPU builders as an animated clip's per-frame rebuild kept on the GPU (render/gpu_clip_build.hpp):
// a GPU builder (lbvh-gpu, ploc-gpu, plocpp-gpu, hploc-gpu) compiled once, a soup buffer kept for the
// clip, every frame's boxes computed from it on the GPU (phase `boxes`), the tree built and packed into
// v1 or bvh2-cb streams that stay on the GPU for the tracer.
#pragma once
#include <memory>
#include <string>

#include "builders/bvh.hpp"
#include "render/gpu_clip_build.hpp"

namespace bvhlab {

// A GPU builder into `layout` (v1 or bvh2-cb); nullptr for another builder or layout. Needs no GL
// context: the first build() compiles the programs in the context current then (every build must
// run in that one), and builds once untimed before the timed build: the driver compiles the programs
// at their first dispatch, which no later frame pays.
std::unique_ptr<GpuClipBuilder> makeResidentClipBuilder(const std::string& builder, const BuildOptions& options,
                                                        const std::string& layout);

}  // namespace bvhlab
