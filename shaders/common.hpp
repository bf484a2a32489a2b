// common.hpp — C++ mirror of common.glsl. Mirrors read like their GLSL: `using namespace glm`
// inside namespace bvhlab::glsl, same names, same order of operations.
#pragma once
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

namespace bvhlab::glsl {
using namespace glm;

struct Ray {
  vec3 origin;
  vec3 dir;
};

struct MeshHit {
  float t;
  int tri;
  vec2 bary;
};

// The GLSL globals become one struct the CPU caller owns (one per ray/pixel).
struct Counters {
  uint32_t nodeVisits = 0;
  uint32_t triTests = 0;
  uint32_t boxTests = 0;
  uint32_t meshRays = 0;
  bool stackOverflow = false;
  // Bytes fetched, counted by the traversal mirrors only (the GLSL kernels do not count them): node
  // texels, triangle records (index and vertex texels for the indexed format) and stack entries
  // pushed and popped. Each kernel_*.hpp states how its counts are derived; docs/layouts.md.
  uint64_t nodeBytes = 0;
  uint64_t triangleBytes = 0;
  uint64_t stackBytes = 0;
};

constexpr float INF = std::numeric_limits<float>::infinity();
constexpr float PI = 3.14159265358979f;

}  // namespace bvhlab::glsl
