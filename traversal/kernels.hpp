// The traversal kernel registry. A kernel is one GLSL file (traversal/kernel_*.glsl, defining
// traceClosest and traceAny over the modules storage_*.glsl, layout.glsl, ray_box.glsl,
// ray_triangle.glsl) plus its C++ mirror (kernel_*.hpp). Adding a kernel = those two files and one
// line in kernels.cpp.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "shaders/common.hpp"
#include "traversal/layout.hpp"  // the decoding mirrors (loadTriangle, loadAttributes, ...) for CPU tracers
#include "traversal/robustness.hpp"  // Robustness, parseRobustness, robustnessNames (callers include this header)

namespace bvhlab {

// The mirrors' entry points: GLSL's traceClosest / traceAny with the storage first and the
// counters (GLSL globals) last. A PackedBvh converts to a glsl::Storage implicitly.
using TraceClosestFn = bool (*)(const glsl::Storage&, glsl::Ray, float tMin, float tMax, glsl::MeshHit&,
                                glsl::Counters&);
using TraceAnyFn = bool (*)(const glsl::Storage&, glsl::Ray, float tMin, float tMax, glsl::Counters&);

struct KernelInfo {
  std::string name;         // e.g. "stack-ordered"
  std::string description;  // one line for `bvhlab kernels`
  std::string glslFile;     // e.g. "kernel_stack_ordered.glsl"
  TraceClosestFn traceClosest;  // mirror with the fast tests (Moller-Trumbore, slab)
  TraceAnyFn traceAny;
  // The mirror instantiated with each (triangle test, box test) pair (traversal/robustness.hpp), by
  // Robustness::testsIndex(); closest(r) / any(r) pick the one a variant runs.
  std::array<TraceClosestFn, 4> closestByTests;
  std::array<TraceAnyFn, 4> anyByTests;
  TraceClosestFn closest(Robustness r) const { return closestByTests[size_t(r.testsIndex())]; }
  TraceAnyFn any(Robustness r) const { return anyByTests[size_t(r.testsIndex())]; }
};

const std::vector<KernelInfo>& kernels();
// Throws std::invalid_argument naming the valid kernels when `name` is unknown.
const KernelInfo& findKernel(const std::string& name);

// BVH_STACK_SIZE for a packed tree of this depth (root alone = 1): enough for every registered
// kernel, so a stack kernel never overflows on that tree. Each kernel derives its own bound in its
// GLSL file (stack-unordered needs D, stack-ordered D - 1); this is the largest, and at least 1.
int stackSizeFor(uint32_t treeDepth);

}  // namespace bvhlab
