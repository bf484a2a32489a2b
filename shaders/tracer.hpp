// tracer.hpp — C++ mirror of the tracer modules (scene.glsl, shade.glsl, world*.glsl, trace_full.glsl,
// trace_report.glsl, main.glsl). It runs the uber path (every module, runtime switches), which the
// tests prove equal to every specialised shader. Used as the oracle for the GLSL renderer.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "layout/layout.hpp"
#include "shaders/assemble.hpp"
#include "shaders/scene_data.hpp"

namespace bvhlab {

struct ReferenceImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;       // RGBA8 bottom-up, as glReadPixels returns it
  std::vector<glm::uvec4> stats;   // as the COUNT_STATS render target
  std::vector<uint32_t> boxTests;  // as its box-test target (o_boxTests)
  double ms = 0.0;
};

// shade.glsl's offsetRayOrigin: a secondary ray's origin, p moved off the surface towards `towards`
// (the side the new ray leaves into) by 1e-4 of `magnitude` or, with OriginOffset::Ulp (RAY_OFFSET_ULP),
// by Waechter & Binder's ULP offset with its absolute branch scaled by `magnitude`
// (shaders/offset_ulp.glsl). magnitude = max|o| + t |d| of the ray that found p (hitMagnitude).
glm::vec3 offsetRayOrigin(glm::vec3 p, glm::vec3 towards, float magnitude, OriginOffset offset);

// Renders with the C++ mirror on all cores.
ReferenceImage renderReference(const Scene& scene, const SceneData& data, const PackedBvh& bvh,
                               const ShaderOptions& options, const FrameOptions& frame);

}  // namespace bvhlab
