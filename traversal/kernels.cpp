#include "traversal/kernels.hpp"

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "traversal/kernel_stack_ordered.hpp"
#include "traversal/kernel_stack_unordered.hpp"
#include "traversal/kernel_stackless.hpp"

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
       "kernel_stack_unordered.glsl", BVHLAB_KERNEL_MIRRORS(glsl::stack_unordered)},
      {"stack-ordered", "explicit stack, nearer child first, pending nodes beyond the closest hit skipped",
       "kernel_stack_ordered.glsl", BVHLAB_KERNEL_MIRRORS(glsl::stack_ordered)},
      {"stackless", "no stack: depth-first walk following escape links", "kernel_stackless.glsl",
       BVHLAB_KERNEL_MIRRORS(glsl::stackless)},
  };
  return table;
}
#undef BVHLAB_KERNEL_MIRRORS

const KernelInfo& findKernel(const std::string& name) {
  for (const KernelInfo& k : kernels())
    if (k.name == name) return k;
  std::ostringstream msg;
  msg << "unknown traversal kernel '" << name << "'; valid kernels:";
  for (const KernelInfo& k : kernels()) msg << ' ' << k.name;
  throw std::invalid_argument(msg.str());
}

int stackSizeFor(uint32_t treeDepth) {
  if (treeDepth > uint32_t(std::numeric_limits<int>::max()))
    throw std::invalid_argument("stackSizeFor: tree depth " + std::to_string(treeDepth) + " is too large");
  return std::max(1, int(treeDepth));
}

}  // namespace bvhlab
