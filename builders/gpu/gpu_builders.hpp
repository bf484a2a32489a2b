// The GPU builders' place in the builder registry (builders/builder.hpp) and their timing. The CPU
// builders' library has no GL in it: this library (after render, which makes GL contexts) adds the
// GPU builders to the registry at run time, and every program that should offer them calls
// registerGpuBuilders() first (the bvhlab app does, before it parses a command).
//
// A GPU builder builds in the current GL context (render, trace, measure: the renderer's; view: the
// window's). When no context is current (build, or a run before any rendering) it makes a headless
// one for the build: OSMesa, or EGL when BVHLAB_GPU_BUILD_BACKEND=egl (the path to a GPU). In a
// context it did not make it restores the program and shader storage bindings it changed.
#pragma once
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "builders/bvh.hpp"
#include "layout/layout.hpp"
#include "render/gpu_build_timing.hpp"

namespace bvhlab {

// Adds lbvh-gpu, ploc-gpu, plocpp-gpu and hploc-gpu to builders(), timeGpuBuild as the runs' GPU build timer
// (render/gpu_build_timing.hpp) and makeResidentClipBuilder as the clips' GPU rebuild
// (render/gpu_clip_build.hpp), once; later calls do nothing.
void registerGpuBuilders();

// The registry's entry for lbvh-gpu: gpubuild::GpuLbvh in the current or a headless context.
Bvh buildLbvhGpu(const BuildInput& input, const BuildOptions& options);
// The registry's entry for ploc-gpu: gpubuild::GpuPloc likewise.
Bvh buildPlocGpu(const BuildInput& input, const BuildOptions& options);
// The registry's entry for plocpp-gpu: gpubuild::GpuPloc with PlocPasses::Fused likewise.
Bvh buildPlocppGpu(const BuildInput& input, const BuildOptions& options);

// The registry's entry for hploc-gpu: gpubuild::GpuHploc likewise.
Bvh buildHplocGpu(const BuildInput& input, const BuildOptions& options);

namespace gpubuild {
struct GpuPhaseTimes;
struct GpuPackRequest;
// A GPU builder's object (GpuLbvh, GpuPloc, GpuHploc), its programs compiled in the current context,
// behind one interface: what timeGpuBuild and the clips' GPU rebuild hold.
class AnyGpuBuilder {
 public:
  virtual ~AnyGpuBuilder() = default;
  virtual Bvh build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
                    const GpuPackRequest* pack) const = 0;
  virtual void checkLimits(size_t primitives, bool pack) const = 0;
};
// Throws std::invalid_argument when `builder` is not one of the GPU builders.
std::unique_ptr<AnyGpuBuilder> makeGpuBuilder(const std::string& builder);
}  // namespace gpubuild

// GpuBuildTiming: render/gpu_build_timing.hpp (runs record it through the timer registerGpuBuilders sets).
// With `packLayout` (v1 or bvh2-cb: gpubuild::gpuPackable) and the `soup` the input was made from, every
// build also packs on the GPU (phase `pack`), and the last build's streams are checked texel for texel
// against the CPU's pack of its tree: a difference throws std::runtime_error naming the stream and texel.
// Throws std::invalid_argument when `builder` is not a GPU builder.
GpuBuildTiming timeGpuBuild(const std::string& builder, const BuildInput& input, const BuildOptions& options,
                            size_t builds, const std::string& packLayout = "", const TriangleSoup* soup = nullptr);

}  // namespace bvhlab
