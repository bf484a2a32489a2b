// The GPU clip builders' factory (render/gpu_clip_build.hpp).
#include "render/gpu_clip_build.hpp"

namespace bvhlab {

namespace {
GpuClipBuilderFactory& factory() {
  static GpuClipBuilderFactory f;
  return f;
}
}  // namespace

void setGpuClipBuilderFactory(GpuClipBuilderFactory f) { factory() = std::move(f); }

std::unique_ptr<GpuClipBuilder> makeGpuClipBuilder(const std::string& builder, const BuildOptions& options,
                                                   const std::string& layout, const std::string& triangleFormat) {
  if (triangleFormat != "raw" || !factory()) return nullptr;
  return factory()(builder, options, layout);
}

}  // namespace bvhlab
