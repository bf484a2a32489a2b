// Every registered builder, through the registry, against the invariants every consumer of a Bvh
// relies on (layout packer, traversal kernels, statistics), on generated and degenerate inputs and
// the bunny.
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/scene.hpp"

namespace bvhlab {
namespace {

using testing::PrimitiveSet;

std::vector<std::string> builderNames() {
  std::vector<std::string> names;
  for (const BuilderInfo& info : builders()) names.push_back(info.name);
  return names;
}

bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

// The SAH of the brief, written out independently of builders/stats.cpp:
// Ct * sum_inner A(n) / A(root) + Ci * sum_leaf A(n) / A(root) * count(n).
double referenceSah(const Bvh& bvh, const CostModel& cost) {
  double sum = 0.0;
  for (const BvhNode& node : bvh.nodes)
    sum += node.isLeaf() ? cost.intersectionCost * double(node.bounds.halfArea()) * node.count
                         : cost.traversalCost * double(node.bounds.halfArea());
  return sum / bvh.nodes[0].bounds.halfArea();
}

// Structural invariants. Returns the depth (root alone = 1).
uint32_t checkTree(const Bvh& bvh, const PrimitiveSet& set, uint32_t maxLeafSize) {
  const size_t n = set.size();
  EXPECT_FALSE(bvh.nodes.empty());
  EXPECT_LE(bvh.nodes.size(), 2 * n - 1);
  EXPECT_EQ(bvh.primIndices.size(), n);
  std::vector<int> referenced(n, 0);
  std::vector<int> reached(bvh.nodes.size(), 0);
  uint32_t maxDepth = 0;
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};
  while (!stack.empty()) {
    auto [index, depth] = stack.back();
    stack.pop_back();
    if (index >= bvh.nodes.size()) {
      ADD_FAILURE() << "child index " << index << " out of range";
      return 0;
    }
    if (reached[index]++) {
      ADD_FAILURE() << "node " << index << " reached twice";
      return 0;
    }
    maxDepth = std::max(maxDepth, depth);
    const BvhNode& node = bvh.nodes[index];
    if (node.isLeaf()) {
      EXPECT_LE(node.count, maxLeafSize) << "leaf " << index;
      if (size_t(node.first) + node.count > bvh.primIndices.size()) {
        ADD_FAILURE() << "leaf " << index << " range out of primIndices";
        continue;
      }
      Aabb tight;
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        const uint32_t prim = bvh.primIndices[k];
        if (prim >= n) {
          ADD_FAILURE() << "primitive index " << prim << " out of range";
          continue;
        }
        ++referenced[prim];
        tight.grow(set.boxes[prim]);
      }
      EXPECT_TRUE(sameBox(node.bounds, tight)) << "leaf " << index << " box is not the union of its primitives";
    } else {
      const BvhNode& l = bvh.nodes.at(node.left);
      const BvhNode& r = bvh.nodes.at(node.right);
      EXPECT_TRUE(node.bounds.contains(l.bounds) && node.bounds.contains(r.bounds)) << "node " << index;
      Aabb tight = l.bounds;
      tight.grow(r.bounds);
      EXPECT_TRUE(sameBox(node.bounds, tight)) << "node " << index << " box is not the union of its children";
      stack.push_back({node.right, depth + 1});
      stack.push_back({node.left, depth + 1});
    }
  }
  EXPECT_EQ(std::count(reached.begin(), reached.end(), 0), 0) << "nodes unreachable from the root";
  for (size_t i = 0; i < n; ++i)
    if (referenced[i] != 1) {
      ADD_FAILURE() << "primitive " << i << " referenced " << referenced[i] << " times";
      break;
    }
  return maxDepth;
}

bool identical(const Bvh& a, const Bvh& b) {
  if (a.nodes.size() != b.nodes.size() || a.primIndices != b.primIndices) return false;
  for (size_t i = 0; i < a.nodes.size(); ++i) {
    const BvhNode &x = a.nodes[i], &y = b.nodes[i];
    if (!sameBox(x.bounds, y.bounds) || x.count != y.count ||
        (x.isLeaf() ? x.first != y.first : (x.left != y.left || x.right != y.right)))
      return false;
  }
  return true;
}

// Builds, checks the invariants and the reported statistics; returns the tree.
Bvh buildChecked(const std::string& builder, const PrimitiveSet& set, BuildOptions options, BuildStats* out = nullptr) {
  BuildStats stats;
  Bvh bvh = buildBvh(builder, set.input(), options, &stats);
  const uint32_t depth = checkTree(bvh, set, options.maxLeafSize);
  EXPECT_EQ(stats.builder, builder);
  EXPECT_EQ(stats.primitives, set.size());
  EXPECT_EQ(stats.nodes, bvh.nodes.size());
  EXPECT_EQ(stats.depth, depth);
  EXPECT_LE(stats.primsPerLeafMax, options.maxLeafSize);
  EXPECT_GE(stats.buildMs, 0.0);
  if (bvh.nodes[0].bounds.halfArea() > 0.0f) {
    const double reference = referenceSah(bvh, options.cost);
    EXPECT_NEAR(stats.sahCost, reference, 1e-9 * reference) << set.name;
  }
  if (out) *out = stats;
  return bvh;
}

// ---- every builder, every leaf size ------------------------------------------------------------

class EveryBuilderAndLeafSize : public ::testing::TestWithParam<std::tuple<std::string, uint32_t>> {};

TEST_P(EveryBuilderAndLeafSize, GeneratedSoupsKeepInvariants) {
  const auto& [builder, leafSize] = GetParam();
  BuildOptions options;
  options.maxLeafSize = leafSize;
  for (const PrimitiveSet& set : {testing::randomSoup(6000), testing::gridSoup(50, 60), testing::sphereSoup(60, 50, 0.2f)}) {
    SCOPED_TRACE(set.name);
    BuildStats stats;
    buildChecked(builder, set, options, &stats);
    EXPECT_GT(stats.sahCost, 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Builders, EveryBuilderAndLeafSize,
                         ::testing::Combine(::testing::ValuesIn(builderNames()), ::testing::Values(1u, 2u, 4u, 8u, 16u)),
                         [](const auto& info) {
                           std::string name = std::get<0>(info.param) + "_leaf" + std::to_string(std::get<1>(info.param));
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// ---- every builder ------------------------------------------------------------------------------

class EveryBuilder : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryBuilder, IsDeterministic) {
  const PrimitiveSet set = testing::randomSoup(50000, 7);
  BuildOptions one, many;
  one.threads = 1;
  many.threads = 4;
  const Bvh a = buildBvh(GetParam(), set.input(), many);
  const Bvh b = buildBvh(GetParam(), set.input(), many);
  const Bvh c = buildBvh(GetParam(), set.input(), one);
  EXPECT_TRUE(identical(a, b)) << "two builds of the same input differ";
  EXPECT_TRUE(identical(a, c)) << "the tree depends on the thread count";
}

TEST_P(EveryBuilder, LargestLeafSize) {
  BuildOptions options;
  options.maxLeafSize = kMaxLeafSize;  // Embree caps its leaves at 32, which honours the limit too
  BuildStats stats;
  buildChecked(GetParam(), testing::sphereSoup(40, 30), options, &stats);
  EXPECT_GT(stats.leaves, 1u);
}

TEST_P(EveryBuilder, OnePrimitive) {
  PrimitiveSet set;
  set.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const Bvh bvh = buildChecked(GetParam(), set, {});
  ASSERT_EQ(bvh.nodes.size(), 1u);
  EXPECT_TRUE(bvh.nodes[0].isLeaf());
}

TEST_P(EveryBuilder, TwoIdenticalTriangles) {
  PrimitiveSet set;
  set.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  set.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  BuildOptions options;
  options.maxLeafSize = 1;
  EXPECT_EQ(buildChecked(GetParam(), set, options).nodes.size(), 3u);
  options.maxLeafSize = 4;  // one leaf or two: the SAH builders keep them together, Embree LOW does not
  buildChecked(GetParam(), set, options);
}

TEST_P(EveryBuilder, AllCentroidsEqual) {
  PrimitiveSet set;
  for (int i = 0; i < 3000; ++i) {  // different boxes, one common centroid
    const float s = 0.001f * float(1 + i % 17);
    set.addBox({glm::vec3(-s), glm::vec3(s)}, glm::vec3(0.0f));
  }
  for (uint32_t leafSize : {1u, 4u, 16u}) {
    BuildOptions options;
    options.maxLeafSize = leafSize;
    const Bvh bvh = buildChecked(GetParam(), set, options);
    // Without a usable centroid axis a builder can only halve: the depth must stay logarithmic.
    EXPECT_LE(computeStats(bvh, options.cost).depth, 2 + uint32_t(std::ceil(std::log2(double(set.size())))));
  }
}

TEST_P(EveryBuilder, IdenticalPointPrimitives) {
  PrimitiveSet set;  // zero-extent boxes, all at one point: zero root area
  for (int i = 0; i < 1000; ++i) set.addBox({glm::vec3(0.5f), glm::vec3(0.5f)}, glm::vec3(0.5f));
  BuildStats stats;
  buildChecked(GetParam(), set, {}, &stats);
  EXPECT_TRUE(std::isfinite(stats.sahCost));
}

TEST_P(EveryBuilder, ZeroExtentBoxes) {
  PrimitiveSet set;  // points on a curve
  for (int i = 0; i < 4000; ++i) {
    const glm::vec3 p(std::cos(0.01f * i), std::sin(0.013f * i), 0.001f * i);
    set.addBox({p, p}, p);
  }
  BuildStats stats;
  buildChecked(GetParam(), set, {}, &stats);
  EXPECT_TRUE(std::isfinite(stats.sahCost));
}

TEST_P(EveryBuilder, ExponentiallySpacedPrimitivesDoNotExhaustTheStack) {
  // Each SAH split peels off the farthest few primitives: a deep, list-like tree.
  PrimitiveSet set;
  for (int i = 0; i < 3000; ++i) {
    const float x = std::pow(1.02f, float(i));
    set.addBox({glm::vec3(x, 0, 0), glm::vec3(x + 0.01f, 0.01f, 0.01f)}, glm::vec3(x + 0.005f, 0.005f, 0.005f));
  }
  buildChecked(GetParam(), set, {});
}

TEST_P(EveryBuilder, MillionTrianglesOnAPlane) {
  const PrimitiveSet set = testing::planeSoup(1000000);
  BuildStats stats;
  buildChecked(GetParam(), set, {}, &stats);
  EXPECT_TRUE(std::isfinite(stats.sahCost));
}

TEST_P(EveryBuilder, Bunny) {
  const PrimitiveSet bunny = testing::loadTriangles(testing::bunnyPath());
  if (bunny.size() == 0)
    GTEST_SKIP() << testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`";
  BuildStats stats;
  buildChecked(GetParam(), bunny, {}, &stats);
  EXPECT_GT(stats.sahCost, 0.0);
}

TEST_P(EveryBuilder, EmptyInputIsAnError) {
  EXPECT_THROW(buildBvh(GetParam(), BuildInput{}, {}), InputError);
}

INSTANTIATE_TEST_SUITE_P(Builders, EveryBuilder, ::testing::ValuesIn(builderNames()), [](const auto& info) {
  std::string name = info.param;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
});

// ---- the registry and input validation ----------------------------------------------------------

TEST(Registry, HasTheRequiredBuilders) {
  for (const char* name : {"median", "sah-binned", "sah-sweep", "embree"}) EXPECT_NO_THROW(findBuilder(name)) << name;
}

TEST(Registry, UnknownBuilderListsTheValidNames) {
  try {
    findBuilder("no-such-builder");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no-such-builder"), std::string::npos) << what;
    for (const std::string& name : builderNames()) EXPECT_NE(what.find(name), std::string::npos) << what;
  }
}

TEST(Validation, BadInputNamesThePrimitive) {
  PrimitiveSet set = testing::randomSoup(10);
  set.boxes[3].max.y = std::nanf("");
  try {
    buildBvh("sah-binned", set.input(), {});
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("primitive 3"), std::string::npos) << e.what();
  }
  set = testing::randomSoup(10);
  set.boxes[7].min.x = -std::numeric_limits<float>::infinity();
  EXPECT_THROW(buildBvh("median", set.input(), {}), InputError);
  set = testing::randomSoup(10);
  set.centroids[2].z = std::nanf("");
  EXPECT_THROW(buildBvh("median", set.input(), {}), InputError);
  set = testing::randomSoup(10);
  std::swap(set.boxes[5].min, set.boxes[5].max);  // inverted box
  EXPECT_THROW(buildBvh("median", set.input(), {}), InputError);
}

TEST(Validation, MismatchedSpansAndBadOptions) {
  const PrimitiveSet set = testing::randomSoup(10);
  EXPECT_THROW(buildBvh("median", BuildInput{set.boxes, std::span(set.centroids).first(9)}, {}), InputError);
  BuildOptions options;
  options.maxLeafSize = 0;
  EXPECT_THROW(buildBvh("median", set.input(), options), std::invalid_argument);
  options.maxLeafSize = kMaxLeafSize + 1;
  EXPECT_THROW(buildBvh("median", set.input(), options), std::invalid_argument);
  options = {};
  options.bins = 1;
  EXPECT_THROW(buildBvh("sah-binned", set.input(), options), std::invalid_argument);
}

TEST(Validation, SceneTooLargeForFloatAreas) {
  PrimitiveSet set = testing::randomSoup(10);
  set.boxes[0].max = glm::vec3(3e38f);  // finite, but its extent times another overflows
  EXPECT_THROW(buildBvh("median", set.input(), {}), InputError);
}

// ---- builder-specific properties -----------------------------------------------------------------

// The median builder's tree is complete (every level full except the last, filled from the left)
// and every leaf is full except the last one.
TEST(Median, CompleteTreeWithFullLeaves) {
  for (size_t n : {1u, 2u, 5u, 17u, 1000u, 4097u, 9999u}) {
    for (uint32_t leafSize : {1u, 3u, 4u, 16u}) {
      const PrimitiveSet set = testing::randomSoup(n, uint32_t(n));
      BuildOptions options;
      options.maxLeafSize = leafSize;
      const Bvh bvh = buildChecked("median", set, options);
      const size_t leaves = (n + leafSize - 1) / leafSize;
      EXPECT_EQ(bvh.nodes.size(), 2 * leaves - 1);
      // Leaves in left-to-right order with their depths.
      std::vector<std::pair<uint32_t, uint32_t>> order;  // (count, depth)
      std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
      while (!stack.empty()) {
        auto [i, d] = stack.back();
        stack.pop_back();
        const BvhNode& node = bvh.nodes[i];
        if (node.isLeaf()) {
          order.push_back({node.count, d});
        } else {
          stack.push_back({node.right, d + 1});
          stack.push_back({node.left, d + 1});
        }
      }
      const uint32_t deepest = uint32_t(std::ceil(std::log2(double(leaves))));
      bool shallowSeen = false;
      for (size_t k = 0; k < order.size(); ++k) {
        if (k + 1 < order.size()) {
          EXPECT_EQ(order[k].first, leafSize) << "n " << n << " leaf " << k;
        }
        EXPECT_TRUE(order[k].second == deepest || order[k].second + 1 == deepest) << "n " << n;
        if (order[k].second != deepest) {
          shallowSeen = true;
        } else {
          EXPECT_FALSE(shallowSeen) << "n " << n << ": the deepest level is not filled from the left";
        }
      }
    }
  }
}

// The SAH builders against the reference and against the median split.
TEST(Quality, SahBuildersMatchEmbreeMediumOnTheBunny) {
  const PrimitiveSet bunny = testing::loadTriangles(testing::bunnyPath());
  if (bunny.size() == 0)
    GTEST_SKIP() << testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`";
  BuildStats embree, median, stats;
  buildBvh("embree", bunny.input(), {}, &embree);
  buildBvh("median", bunny.input(), {}, &median);
  for (const char* name : {"sah-binned", "sah-sweep"}) {
    buildBvh(name, bunny.input(), {}, &stats);
    EXPECT_LE(stats.sahCost, 1.01 * embree.sahCost) << name;
    EXPECT_LT(stats.sahCost, median.sahCost) << name;
  }
}

TEST(Quality, SweepIsAtLeastAsGoodAsBinnedOnRandomSoups) {
  // Not a theorem (greedy choices compound), but a large gap either way would point at a bug.
  const PrimitiveSet set = testing::randomSoup(20000, 3);
  BuildStats sweep, binned;
  buildBvh("sah-sweep", set.input(), {}, &sweep);
  buildBvh("sah-binned", set.input(), {}, &binned);
  EXPECT_LE(sweep.sahCost, 1.02 * binned.sahCost);
}

}  // namespace
}  // namespace bvhlab
