// The traversal kernel registry. A kernel is one GLSL file (traversal/kernel_*.glsl, defining
// traceClosest and traceAny over the modules storage_*.glsl, its layout's accessor modules
// (layout/layouts.hpp: layout.glsl for v1), ray_box.glsl, ray_triangle.glsl) plus its C++ mirror
// (kernel_*.hpp). Each kernel walks one layout (KernelInfo::layout). Adding a kernel = those two
// files and one line in kernels.cpp, in its layout's table. Over a two-level tree the same kernel file
// is the BLAS and the TLAS walk (traversal/two_level.glsl; the kernels with one: two_level.hpp).
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
  std::string layout;       // the layout whose NODE stream it walks (layout/layouts.hpp), e.g. "v1"
  TraceClosestFn traceClosest;  // mirror with the fast tests (Moller-Trumbore, slab)
  TraceAnyFn traceAny;
  // The mirror instantiated with each (triangle test, box test) pair (traversal/robustness.hpp), by
  // Robustness::testsIndex(); closest(r) / any(r) pick the one a variant runs.
  std::array<TraceClosestFn, 4> closestByTests;
  std::array<TraceAnyFn, 4> anyByTests;
  // The kernel is designed for persistent threads in the compute path (shaders/trace_rays.glsl): a
  // fixed number of invocations taking batches of rays from an atomic counter (render/ray_tracer_gl.cpp).
  // They are used only where persistentThreadsOn says so.
  bool persistentThreads = false;
  // #define lines put before the kernel's GLSL file (a variant of a shared file: bvh4-/bvh8-fetch-whole).
  std::string glslDefines = "";
  TraceClosestFn closest(Robustness r) const { return closestByTests[size_t(r.testsIndex())]; }
  TraceAnyFn any(Robustness r) const { return anyByTests[size_t(r.testsIndex())]; }
};

// The kernels of layout v1, the default layout (what every v1 test and sweep iterates over).
// Whether the compute path runs `kernel` with persistent threads on the GL implementation named
// `renderer` (GL_RENDERER): only a kernel designed for them (KernelInfo::persistentThreads), and by
// default not on llvmpipe. There every shader invocation has ONE budget of 65,535 loop iterations shared
// by all its loops (gallivm's loop limiter, LP_MAX_TGSI_LOOP_ITERATIONS), after which every loop exits:
// a persistent invocation tracing hundreds of rays exhausts it, and its last rays end their walks early
// (measured: 5 to 17 of 65,536 diffuse bunny rays returned as misses, each traced after about 300 rays
// in its invocation; tests/test_persistent_threads.cpp shows the budget). BVHLAB_PERSISTENT_THREADS=1
// turns them on anyway, =0 off everywhere.
bool persistentThreadsOn(const KernelInfo& kernel, const std::string& renderer);
const std::vector<KernelInfo>& kernels();
// The kernels that walk `layout`; throws std::invalid_argument naming the valid layouts.
const std::vector<KernelInfo>& kernelsFor(const std::string& layout);
// Every registered kernel, layout by layout in layouts() order.
std::vector<const KernelInfo*> allKernels();
// Any layout's kernel. Throws std::invalid_argument naming the valid kernels when `name` is unknown.
const KernelInfo& findKernel(const std::string& name);
// `name` if it walks `layout` ("" = the layout's default kernel). Throws std::invalid_argument for an
// unknown layout or kernel, or a kernel of another layout, naming the kernels valid for `layout`.
const KernelInfo& findKernel(const std::string& layout, const std::string& name);

// BVH_STACK_SIZE for a packed tree of this depth (root alone = 1): enough for every registered
// kernel, so a stack kernel never overflows on that tree. Each kernel derives its own bound in its
// GLSL file (stack-unordered needs D, stack-ordered D - 1); this is the largest, and at least 1.
int stackSizeFor(uint32_t treeDepth);
// BVH_STACK_SIZE for this packed tree in its own layout: stackSizeFor(depth) for the binary layouts,
// the wide kernels' bound max(1, (W - 1)(D - 1)) for bvh4/bvh8/cwbvh (D: the wide tree's depth;
// traversal/kernel_wide_stack.glsl and kernel_cwbvh_stack.glsl derive it). What every caller with a
// PackedBvh should use.
int stackSizeFor(const PackedBvh& packed);

}  // namespace bvhlab
