// The two-level mirrors of the kernels that have a two-level walk (traversal/two_level.hpp).
#include "traversal/two_level.hpp"

#include <array>
#include <utility>

namespace bvhlab {

namespace {

using glsl::Tests;
using namespace glsl::two_level;

template <class Walk>
std::array<TwoLevelMirror, 4> mirrors() {
  using MS = Tests<TriangleTest::MollerTrumbore, BoxTest::Slab>;
  using MR = Tests<TriangleTest::MollerTrumbore, BoxTest::Robust>;
  using WS = Tests<TriangleTest::Watertight, BoxTest::Slab>;
  using WR = Tests<TriangleTest::Watertight, BoxTest::Robust>;
  // Robustness::testsIndex() order.
  return {TwoLevelMirror{traceClosest<MS, Walk>, traceAny<MS, Walk>}, TwoLevelMirror{traceClosest<MR, Walk>, traceAny<MR, Walk>},
          TwoLevelMirror{traceClosest<WS, Walk>, traceAny<WS, Walk>}, TwoLevelMirror{traceClosest<WR, Walk>, traceAny<WR, Walk>}};
}

const std::vector<std::pair<std::string, std::array<TwoLevelMirror, 4>>>& table() {
  static const std::vector<std::pair<std::string, std::array<TwoLevelMirror, 4>>> t = {
      {"stack-unordered", mirrors<UnorderedWalk>()},
      {"stack-ordered", mirrors<OrderedWalk>()},
      {"stackless", mirrors<StacklessWalk>()},
      {"bvh2cb-stack-ordered", mirrors<Bvh2cbWalk>()},
      {"bvh2cb-aila-laine", mirrors<Bvh2cbAilaLaineWalk>()},
  };
  return t;
}

}  // namespace

bool hasTwoLevelWalk(const std::string& kernel) {
  for (const auto& [name, m] : table())
    if (name == kernel) return true;
  return false;
}

TwoLevelMirror twoLevelMirror(const std::string& kernel, Robustness r) {
  std::string names;
  for (const auto& [name, m] : table()) {
    if (name == kernel) return m[size_t(r.testsIndex())];
    names += " " + name;
  }
  throw std::invalid_argument("kernel '" + kernel + "' has no two-level walk; kernels with one:" + names);
}

}  // namespace bvhlab
