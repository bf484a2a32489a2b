#include "traversal/kernels.hpp"

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "traversal/kernel_stack_ordered.hpp"
#include "traversal/kernel_stack_unordered.hpp"
#include "traversal/kernel_stackless.hpp"

namespace bvhlab {

const std::vector<KernelInfo>& kernels() {
  static const std::vector<KernelInfo> table = {
      {"stack-unordered", "explicit stack, both hit children pushed in fixed order (the report's Algorithm 2)",
       "kernel_stack_unordered.glsl", glsl::stack_unordered::traceClosest<>, glsl::stack_unordered::traceAny<>,
       glsl::stack_unordered::traceClosest<glsl::RobustTests>, glsl::stack_unordered::traceAny<glsl::RobustTests>},
      {"stack-ordered", "explicit stack, nearer child first, pending nodes beyond the closest hit skipped",
       "kernel_stack_ordered.glsl", glsl::stack_ordered::traceClosest<>, glsl::stack_ordered::traceAny<>,
       glsl::stack_ordered::traceClosest<glsl::RobustTests>, glsl::stack_ordered::traceAny<glsl::RobustTests>},
      {"stackless", "no stack: depth-first walk following escape links", "kernel_stackless.glsl",
       glsl::stackless::traceClosest<>, glsl::stackless::traceAny<>,
       glsl::stackless::traceClosest<glsl::RobustTests>, glsl::stackless::traceAny<glsl::RobustTests>},
  };
  return table;
}

const KernelInfo& findKernel(const std::string& name) {
  for (const KernelInfo& k : kernels())
    if (k.name == name) return k;
  std::ostringstream msg;
  msg << "unknown traversal kernel '" << name << "'; valid kernels:";
  for (const KernelInfo& k : kernels()) msg << ' ' << k.name;
  throw std::invalid_argument(msg.str());
}

Robustness parseRobustness(const std::string& name) {
  if (name == "fast") return Robustness::Fast;
  if (name == "watertight") return Robustness::Watertight;
  throw std::invalid_argument("unknown robustness variant '" + name + "' (valid: fast, watertight)");
}

const char* robustnessName(Robustness r) { return r == Robustness::Fast ? "fast" : "watertight"; }

const std::vector<std::string>& robustnessNames() {
  static const std::vector<std::string> names = {"fast", "watertight"};
  return names;
}

int stackSizeFor(uint32_t treeDepth) {
  if (treeDepth > uint32_t(std::numeric_limits<int>::max()))
    throw std::invalid_argument("stackSizeFor: tree depth " + std::to_string(treeDepth) + " is too large");
  return std::max(1, int(treeDepth));
}

}  // namespace bvhlab
