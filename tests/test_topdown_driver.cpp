// The top-down driver (builders/build_util.hpp buildTopDown, SubtreeTeam) on its own, with a stepper
// that halves ranges: the same nodes in the same order for any thread count, and a stepper's exception
// rethrown by the driver, whether it comes from the top levels (the calling thread) or from a subtree
// (any thread), with no thread left waiting.
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab::detail {
namespace {

struct HalfTask {
  uint32_t node = 0, begin = 0, end = 0;
};

// Splits every range of two or more at its middle, children's boxes the halves of x; throws on the
// range [throwBegin, throwEnd) if it is ever asked for.
struct Halver {
  uint32_t throwBegin = ~0u, throwEnd = ~0u;
  NodeStep<HalfTask> step(const HalfTask& task, const Aabb& box) const {
    if (task.begin == throwBegin && task.end == throwEnd) throw std::runtime_error("stepper failed");
    NodeStep<HalfTask> s;
    if (task.end - task.begin < 2) return s;
    const uint32_t mid = task.begin + (task.end - task.begin) / 2;
    const float cut = 0.5f * (box.min.x + box.max.x);
    s.leaf = false;
    s.childBox[0] = s.childBox[1] = box;
    s.childBox[0].max.x = cut;
    s.childBox[1].min.x = cut;
    s.child[0] = {0, task.begin, mid};
    s.child[1] = {0, mid, task.end};
    return s;
  }
};

std::vector<BvhNode> build(uint32_t n, unsigned threads, Halver halver = {}) {
  const Aabb root{{0, 0, 0}, {1, 1, 1}};
  return buildTopDown(root, HalfTask{0, 0, n}, threads, [&] { return halver; });
}

bool sameNodes(const std::vector<BvhNode>& a, const std::vector<BvhNode>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(BvhNode)) == 0;
}

TEST(TopDownDriver, SameNodesInTheSameOrderForAnyThreadCount) {
  for (uint32_t n : {kParallelMinInput - 1, kParallelMinInput, 50000u}) {
    const std::vector<BvhNode> one = build(n, 1);
    ASSERT_EQ(one.size(), 2 * size_t(n) - 1) << n;
    uint32_t leaves = 0;
    for (const BvhNode& node : one) leaves += node.isLeaf() ? node.count : 0;
    EXPECT_EQ(leaves, n);
    for (unsigned threads : {2u, 3u, 8u}) EXPECT_TRUE(sameNodes(one, build(n, threads))) << n << ", " << threads << " threads";
  }
}

TEST(TopDownDriver, RethrowsAStepperExceptionFromTheLevelsOrASubtree) {
  const uint32_t n = 50000;  // cut = n / kSubtreeFraction: ranges above it are levels, below subtrees
  const uint32_t levelRange = n / 2, subtreeRange = n / 64;
  ASSERT_GT(levelRange, n / kSubtreeFraction);
  ASSERT_LE(subtreeRange, n / kSubtreeFraction);
  // The halving makes [0, n / 2^k) a node at every depth k; [0, n/64) lies below the cut.
  for (unsigned threads : {1u, 2u, 4u}) {
    for (uint32_t range : {levelRange, subtreeRange}) {
      Halver failing;
      failing.throwBegin = 0;
      failing.throwEnd = range;
      EXPECT_THROW(build(n, threads, failing), std::runtime_error) << threads << " threads, range " << range;
    }
    EXPECT_NO_THROW(build(n, threads)) << threads << " threads";  // and the driver still works
  }
}

}  // namespace
}  // namespace bvhlab::detail
