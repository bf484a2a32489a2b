// Refit on several threads (builders/refit.hpp refitSchedule): the schedule's tasks are whole
// subtrees, and boxes, SAH sums and errors are the one-thread refit's for any thread count.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/refit.hpp"
#include "builders/update.hpp"
#include "builder_test_util.hpp"
#include "datasets/scene.hpp"
#include "update_test_clips.hpp"

namespace bvhlab {
namespace {

using testing::Clip;
using testing::explodeClip;
using testing::identical;

// A refit schedule (refitSchedule) cuts the post-order into subtrees: every task a contiguous range
// that is exactly one subtree (its root last, its size the subtree's), the tasks and `top` together
// every position once, and `top` only inner nodes whose children come before them.
TEST(RefitThreads, ScheduleTasksAreWholeSubtreesCoveringTheOrderOnce) {
  const Clip clip = explodeClip(80, 40, 1);  // 6,400 triangles
  UpdateOptions options;
  const auto strategy = makeUpdateStrategy("refit", options);
  strategy->update(clip.frame(0));
  const Bvh& tree = strategy->tree();
  for (unsigned threads : {1u, 2u, 4u, 16u}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    const RefitSchedule s = refitSchedule(tree, threads);
    EXPECT_EQ(s.order, refitOrder(tree));
    if (threads == 1) {
      ASSERT_EQ(s.tasks.size(), 1u);
      EXPECT_TRUE(s.top.empty());
      continue;
    }
    EXPECT_GT(s.tasks.size(), size_t(threads)) << "too few tasks to share";
    std::vector<int> covered(s.order.size(), 0);
    std::vector<uint32_t> size(tree.nodes.size(), 1);
    for (const uint32_t i : s.order)
      if (!tree.nodes[i].isLeaf()) size[i] = 1 + size[tree.nodes[i].left] + size[tree.nodes[i].right];
    for (size_t t = 0; t < s.tasks.size(); ++t) {
      const auto [begin, end] = s.tasks[t];
      ASSERT_LT(begin, end);
      if (t > 0) EXPECT_LE(s.tasks[t - 1].second, begin) << "tasks overlap or are out of order";
      EXPECT_EQ(size[s.order[end - 1]], end - begin) << "task " << t << " is not one whole subtree";
      for (uint32_t p = begin; p < end; ++p) ++covered[p];
    }
    std::vector<int> position(tree.nodes.size(), -1);
    for (size_t p = 0; p < s.order.size(); ++p) position[s.order[p]] = int(p);
    for (const uint32_t p : s.top) {
      ++covered[p];
      const BvhNode& node = tree.nodes[s.order[p]];
      ASSERT_FALSE(node.isLeaf());
      EXPECT_LT(position[node.left], int(p));
      EXPECT_LT(position[node.right], int(p));
    }
    EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), std::ptrdiff_t(covered.size()));
  }
}

// The boxes and SAH sums of a refit on 2, 4 or 16 threads are the one-thread refit's bit for bit, at
// every frame of an explosion, and equal sahCost of the refit tree; of two bad triangles in
// different tasks the error names the one first in the refit order, for any thread count.
TEST(RefitThreads, SameBoxesSumsAndErrorsForAnyThreadCount) {
  const Clip clip = explodeClip(80, 40, 5);
  UpdateOptions options;
  const auto strategy = makeUpdateStrategy("rebuild", options);
  strategy->update(clip.frame(2));  // a tree whose leaves list triangles in an order unlike the frame's
  const Bvh base = strategy->tree();
  const CostModel cost;
  for (uint32_t f = 0; f < clip.frames(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    Bvh one = base;
    SahSums oneSums;
    refitBvh(one, refitOrder(one), clip.frame(f), &oneSums);
    for (unsigned threads : {2u, 4u, 16u}) {
      Bvh many = base;
      SahSums manySums;
      refitBvh(many, refitSchedule(many, threads), clip.frame(f), threads, &manySums);
      EXPECT_TRUE(identical(one, many)) << threads << " threads";
      EXPECT_EQ(manySums.innerArea, oneSums.innerArea);
      EXPECT_EQ(manySums.leafArea, oneSums.leafArea);
    }
    EXPECT_EQ(sahCost(oneSums, one.nodes[0].bounds.halfArea(), cost), sahCost(one, cost));
  }
  // Two non-finite triangles, in the first and in the last task of a 4-thread schedule.
  const RefitSchedule s = refitSchedule(base, 4);
  ASSERT_GT(s.tasks.size(), 1u);
  auto leafTriangle = [&](uint32_t position) {
    for (uint32_t p = position;; ++p)
      if (base.nodes[s.order[p]].isLeaf()) return base.primIndices[base.nodes[s.order[p]].first];
  };
  const uint32_t first = leafTriangle(s.tasks.front().first), last = leafTriangle(s.tasks.back().first);
  std::vector<glm::vec3> v0(clip.v0[0]);
  v0[first].y = std::numeric_limits<float>::quiet_NaN();
  v0[last].x = std::numeric_limits<float>::infinity();
  const FrameTriangles bad{v0, clip.v1[0], clip.v2[0]};
  for (unsigned threads : {1u, 4u}) {
    Bvh tree = base;
    try {
      refitBvh(tree, refitSchedule(tree, threads), bad, threads);
      ADD_FAILURE() << "a non-finite vertex was refit, " << threads << " threads";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("triangle " + std::to_string(first) + " "), std::string::npos)
          << threads << " threads: " << e.what();
    }
  }
}

}  // namespace
}  // namespace bvhlab
