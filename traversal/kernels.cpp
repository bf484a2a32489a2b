#include "traversal/kernels.hpp"

#include <cstdlib>
#include <cstring>

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "layout/layouts.hpp"
#include "traversal/kernel_bvh2cb_aila_laine.hpp"
#include "traversal/kernel_bvh2cb_stack.hpp"
#include "traversal/kernel_cwbvh_groups.hpp"
#include "traversal/kernel_cwbvh_stack.hpp"
#include "traversal/kernel_stack_ordered.hpp"
#include "traversal/kernel_stack_unordered.hpp"
#include "traversal/kernel_stackless.hpp"
#include "traversal/kernel_wide_stack.hpp"
#include "layout/layout_cwbvh.hpp"
#include "layout/layout_wide.hpp"

namespace bvhlab {

// One kernel's mirror instantiations: the fast pair first (KernelInfo::traceClosest / traceAny),
// then the four (triangle test, box test) pairs in Robustness::testsIndex() order.
#define BVHLAB_KERNEL_MIRRORS(ns)                                                                        \
  ns::traceClosest<glsl::FastTests>, ns::traceAny<glsl::FastTests>,                                      \
      {ns::traceClosest<glsl::Tests<TriangleTest::MollerTrumbore, BoxTest::Slab>>,                       \
       ns::traceClosest<glsl::Tests<TriangleTest::MollerTrumbore, BoxTest::Robust>>,                     \
       ns::traceClosest<glsl::Tests<TriangleTest::Watertight, BoxTest::Slab>>,                           \
       ns::traceClosest<glsl::Tests<TriangleTest::Watertight, BoxTest::Robust>>},                        \
      {ns::traceAny<glsl::Tests<TriangleTest::MollerTrumbore, BoxTest::Slab>>,                           \
       ns::traceAny<glsl::Tests<TriangleTest::MollerTrumbore, BoxTest::Robust>>,                         \
       ns::traceAny<glsl::Tests<TriangleTest::Watertight, BoxTest::Slab>>,                               \
       ns::traceAny<glsl::Tests<TriangleTest::Watertight, BoxTest::Robust>> }

const std::vector<KernelInfo>& kernels() {
  static const std::vector<KernelInfo> table = {
      {"stack-unordered", "explicit stack, both hit children pushed in fixed order (the report's Algorithm 2)",
       "kernel_stack_unordered.glsl", "v1", BVHLAB_KERNEL_MIRRORS(glsl::stack_unordered)},
      {"stack-ordered", "explicit stack, nearer child first, pending nodes beyond the closest hit skipped",
       "kernel_stack_ordered.glsl", "v1", BVHLAB_KERNEL_MIRRORS(glsl::stack_ordered)},
      {"stackless", "no stack: depth-first walk following escape links", "kernel_stackless.glsl", "v1",
       BVHLAB_KERNEL_MIRRORS(glsl::stackless)},
  };
  return table;
}

namespace {

const std::vector<KernelInfo>& bvh2cbKernels() {
  static const std::vector<KernelInfo> table = {
      {"bvh2cb-stack-ordered",
       "explicit stack over both child boxes of one record, nearer child first, leaves walked from the parent's slot",
       "kernel_bvh2cb_stack.glsl", "bvh2-cb", BVHLAB_KERNEL_MIRRORS(glsl::bvh2cb_stack)},
      {"bvh2cb-aila-laine",
       "Aila & Laine 2009/2012: while-while loop, postponed leaves (persistent threads in the compute path, except on llvmpipe)",
       "kernel_bvh2cb_aila_laine.glsl", "bvh2-cb", BVHLAB_KERNEL_MIRRORS(glsl::bvh2cb_aila_laine), true},
  };
  return table;
}

// bvh4 and bvh8 share one kernel file and mirror (the child count comes with each slot); the
// fetch-whole variants are the same file with WIDE_FETCH_WHOLE defined to the width.
KernelInfo withDefines(KernelInfo k, std::string defines) {
  k.glslDefines = std::move(defines);
  return k;
}

const std::vector<KernelInfo>& wideKernels(uint32_t width) {
  static const std::vector<KernelInfo> bvh4 = {
      {"bvh4-stack-ordered", "explicit stack: every child box of a 4-wide node tested, hits pushed nearest on top",
       "kernel_wide_stack.glsl", "bvh4", BVHLAB_KERNEL_MIRRORS(glsl::wide_stack)},
      withDefines({"bvh4-fetch-whole", "bvh4-stack-ordered's walk with each node's child slots fetched before its tests",
                   "kernel_wide_stack.glsl", "bvh4", BVHLAB_KERNEL_MIRRORS(glsl::WideWhole<4>)},
                  "#define WIDE_FETCH_WHOLE 4\n"),
  };
  static const std::vector<KernelInfo> bvh8 = {
      {"bvh8-stack-ordered", "explicit stack: every child box of an 8-wide node tested, hits pushed nearest on top",
       "kernel_wide_stack.glsl", "bvh8", BVHLAB_KERNEL_MIRRORS(glsl::wide_stack)},
      withDefines({"bvh8-fetch-whole", "bvh8-stack-ordered's walk with each node's child slots fetched before its tests",
                   "kernel_wide_stack.glsl", "bvh8", BVHLAB_KERNEL_MIRRORS(glsl::WideWhole<8>)},
                  "#define WIDE_FETCH_WHOLE 8\n"),
  };
  return width == 4 ? bvh4 : bvh8;
}

const std::vector<KernelInfo>& cwbvhKernels() {
  static const std::vector<KernelInfo> table = {
      {"cwbvh-stack-ordered",
       "explicit stack: every child box of a compressed 8-wide node decoded and tested, hits pushed nearest on top",
       "kernel_cwbvh_stack.glsl", "cwbvh", BVHLAB_KERNEL_MIRRORS(glsl::cwbvh_stack)},
      {"cwbvh-groups",
       "Ylitie et al. 2017: node groups by octant order (findMSB), lazy triangle groups, quantised plane tests",
       "kernel_cwbvh_groups.glsl", "cwbvh", BVHLAB_KERNEL_MIRRORS(glsl::cwbvh_groups)},
      withDefines({"cwbvh-groups-shared",
                   "cwbvh-groups with a short stack in the compute path: the top 8 entries in shared memory, older ones spilled",
                   "kernel_cwbvh_groups.glsl", "cwbvh", BVHLAB_KERNEL_MIRRORS(glsl::cwbvh_groups)},
                  "#define SHARED_STACK_ENTRIES 8\n"),
  };
  return table;
}

// The width W of a wide layout's tree, which bounds its kernels' stacks ((W - 1)(D - 1)); 0 for the
// binary layouts. (Not wideWidth: that one names the bvh4/bvh8 slot format, which cwbvh is not.)
uint32_t stackWidth(const std::string& layout) {
  if (layout == kLayoutCwbvh) return kCwbvhWidth;
  return wideWidth(layout);
}

std::string kernelList(const std::vector<KernelInfo>& table) {
  std::string list;
  for (const KernelInfo& k : table) list += (list.empty() ? "" : " ") + k.name;
  return list;
}

}  // namespace
#undef BVHLAB_KERNEL_MIRRORS

const std::vector<KernelInfo>& kernelsFor(const std::string& layout) {
  const std::string& name = findLayout(layout).name;  // an unknown layout names the valid ones
  if (name == "bvh2-cb") return bvh2cbKernels();
  if (name == kLayoutCwbvh) return cwbvhKernels();
  if (wideWidth(name) != 0) return wideKernels(wideWidth(name));
  return kernels();
}

std::vector<const KernelInfo*> allKernels() {
  std::vector<const KernelInfo*> all;
  for (const LayoutInfo& l : layouts())
    for (const KernelInfo& k : kernelsFor(l.name)) all.push_back(&k);
  return all;
}

const KernelInfo& findKernel(const std::string& name) {
  for (const KernelInfo* k : allKernels())
    if (k->name == name) return *k;
  std::ostringstream msg;
  msg << "unknown traversal kernel '" << name << "'; valid kernels:";
  for (const KernelInfo* k : allKernels()) msg << ' ' << k->name;
  throw std::invalid_argument(msg.str());
}

const KernelInfo& findKernel(const std::string& layout, const std::string& name) {
  const LayoutInfo& l = findLayout(layout);
  const std::vector<KernelInfo>& table = kernelsFor(l.name);
  const std::string& wanted = name.empty() ? l.defaultKernel : name;
  for (const KernelInfo& k : table)
    if (k.name == wanted) return k;
  for (const KernelInfo* k : allKernels())
    if (k->name == wanted)
      throw std::invalid_argument("kernel '" + wanted + "' walks layout " + k->layout + ", not " + l.name +
                                  "; kernels for layout " + l.name + ": " + kernelList(table));
  throw std::invalid_argument("unknown traversal kernel '" + wanted + "'; kernels for layout " + l.name + ": " +
                              kernelList(table) + " (every layout's: bvhlab kernels)");
}

int stackSizeFor(uint32_t treeDepth) {
  if (treeDepth > uint32_t(std::numeric_limits<int>::max()))
    throw std::invalid_argument("stackSizeFor: tree depth " + std::to_string(treeDepth) + " is too large");
  return std::max(1, int(treeDepth));
}

int stackSizeFor(const PackedBvh& packed) {
  const uint32_t depth = std::max<uint32_t>(1, packed.depth);
  const uint32_t width = stackWidth(packed.layout);
  if (width == 0) return stackSizeFor(depth);
  // The wide kernels' bound (kernel_wide_stack.glsl, kernel_cwbvh_stack.glsl): (W - 1)(D - 1) for the
  // wide tree's depth D.
  const uint64_t bound = std::max<uint64_t>(1, uint64_t(width - 1) * (depth - 1));
  if (bound > uint64_t(std::numeric_limits<int>::max()))
    throw std::invalid_argument("stackSizeFor: wide tree depth " + std::to_string(depth) + " is too large");
  return int(bound);
}

bool persistentThreadsOn(const KernelInfo& kernel, const std::string& renderer) {
  if (!kernel.persistentThreads) return false;
  const char* env = std::getenv("BVHLAB_PERSISTENT_THREADS");
  if (env && std::strcmp(env, "1") == 0) return true;
  if (env && std::strcmp(env, "0") == 0) return false;
  return renderer.find("llvmpipe") == std::string::npos;
}

}  // namespace bvhlab
