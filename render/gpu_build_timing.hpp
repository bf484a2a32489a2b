// GL-timed builds of a GPU builder (builders/gpu/gpu_builders.hpp) recorded in a run's JSON, so that
// trace and render runs (and the report's builder table) give a GPU builder's build time as the GPU
// takes it, beside the CPU builders' wall-clock build_ms. The GPU builders' library sits above this
// one, so it hands its timer in at registration (registerGpuBuilders) through setGpuBuildTimer.
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "builders/bvh.hpp"
#include "layout/layout.hpp"
#include "render/frame_stats.hpp"

namespace bvhlab {

struct PreparedScene;

// A GPU builder's GL-timed build: `builds` builds after one untimed warm-up (the driver compiles the
// shaders at the first dispatch), the median total with its order-statistic interval
// (render/frame_stats.hpp; none below kMinValuesForInterval builds) and each phase's median.
struct GpuBuildTiming {
  std::optional<Interval> totalMs;
  double medianMs = 0.0;
  std::vector<std::pair<std::string, double>> phaseMedianMs;
  size_t builds = 0;
  // ploc-gpu's clustering passes, passes issued and pass-state readbacks per build (the same in every
  // build of one input); 0 for lbvh-gpu.
  uint32_t passes = 0, passesIssued = 0, readbacks = 0;
  // plocpp-gpu's fused passes run again split (GpuPhaseTimes::fusedFallbacks), summed over the builds.
  uint32_t fusedFallbacks = 0;
  std::string packLayout;  // the layout the builds packed into on the GPU ("" = none)
  std::string renderer;    // GL_RENDERER of the context that built
};

// (builder, input, options, builds, layout, triangle format, soup): the builds, packing into `layout`
// on the GPU where it can (v1 or bvh2-cb with raw triangles).
using GpuBuildTimer = std::function<GpuBuildTiming(const std::string&, const BuildInput&, const BuildOptions&, size_t,
                                                   const std::string&, const std::string&, const TriangleSoup&)>;
void setGpuBuildTimer(GpuBuildTimer timer);

// For a GPU builder and builds > 0: `builds` GL-timed builds of the prepared scene's triangles with
// `options` in the current context, added to `j` as gpu_build_ms (the median), gpu_build_ms_ci_low and
// _ci_high (null below kMinValuesForInterval builds), gpu_builds, gpu_pack (the layout packed on the
// GPU, or null) and gpu_build_phases_ms. Nothing for a CPU builder or builds == 0. Throws
// std::logic_error when no timer was set (a program that did not register the GPU builders).
void addGpuBuildTiming(nlohmann::json& j, const PreparedScene& prepared, const std::string& builder,
                       const BuildOptions& options, int builds);

}  // namespace bvhlab
