// GL-timed GPU builds in a run's JSON (render/gpu_build_timing.hpp).
#include "render/gpu_build_timing.hpp"

#include <stdexcept>

#include "builders/builder.hpp"
#include "render/prepared_scene.hpp"

namespace bvhlab {

namespace {
GpuBuildTimer& timer() {
  static GpuBuildTimer t;
  return t;
}
}  // namespace

void setGpuBuildTimer(GpuBuildTimer t) { timer() = std::move(t); }

void addGpuBuildTiming(nlohmann::json& j, const PreparedScene& prepared, const std::string& builder,
                       const BuildOptions& options, int builds) {
  if (builds <= 0 || !findBuilder(builder).gpu || prepared.soup.size() == 0) return;
  if (!timer()) throw std::logic_error("--gpu-builds: no GPU build timer is registered (registerGpuBuilders)");
  const TriangleSoup& soup = prepared.soup;
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const GpuBuildTiming t = timer()(builder, BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, options,
                                   size_t(builds), prepared.packed.layout, prepared.packed.triangleFormat, soup);
  j["gpu_build_ms"] = t.medianMs;
  j["gpu_build_ms_ci_low"] = t.totalMs ? nlohmann::json(t.totalMs->low) : nlohmann::json();
  j["gpu_build_ms_ci_high"] = t.totalMs ? nlohmann::json(t.totalMs->high) : nlohmann::json();
  j["gpu_builds"] = t.builds;
  j["gpu_pack"] = t.packLayout.empty() ? nlohmann::json() : nlohmann::json(t.packLayout);
  nlohmann::json phases = nlohmann::json::object();
  for (const auto& [phase, ms] : t.phaseMedianMs) phases[phase] = ms;
  j["gpu_build_phases_ms"] = phases;
}

}  // namespace bvhlab
