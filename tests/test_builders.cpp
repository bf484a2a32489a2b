// Every registered builder, through the registry, against the invariants every consumer of a Bvh
// relies on (layout packer, traversal kernels, statistics), on generated and degenerate inputs and
// the bunny.
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "builder_test_util.hpp"
#include "datasets/scene.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using testing::PrimitiveSet;

using testing::builderNames;
using testing::identical;
using testing::sameBox;

// The SAH cost, written out independently of builders/stats.cpp:
// Ct * sum_inner A(n) / A(root) + Ci * sum_leaf A(n) / A(root) * count(n).
double referenceSah(const Bvh& bvh, const CostModel& cost) {
  double sum = 0.0;
  for (const BvhNode& node : bvh.nodes)
    sum += node.isLeaf() ? cost.intersectionCost * double(node.bounds.halfArea()) * node.count
                         : cost.traversalCost * double(node.bounds.halfArea());
  return sum / bvh.nodes[0].bounds.halfArea();
}

// The union of `parts` covers the box `prim` (closed boxes). Exact: the parts' faces cut `prim` into
// a grid of cells; every cell is covered iff some part contains each cell's corners, edge midpoints
// and centre, i.e. every grid coordinate and every midpoint between two consecutive ones (midpoints
// of floats are exact in double). Beyond 12 parts, a fixed random sample of points instead.
bool boxCovered(const Aabb& prim, const std::vector<Aabb>& parts) {
  for (const Aabb& p : parts)
    if (p.contains(prim)) return true;
  auto inSome = [&](const glm::dvec3& x) {
    for (const Aabb& p : parts)
      if (glm::all(glm::lessThanEqual(glm::dvec3(p.min), x)) && glm::all(glm::lessThanEqual(x, glm::dvec3(p.max))))
        return true;
    return false;
  };
  std::vector<double> samples[3];
  for (int a = 0; a < 3; ++a) {
    std::vector<double> c{prim.min[a], prim.max[a]};
    for (const Aabb& p : parts)
      for (float v : {p.min[a], p.max[a]})
        if (v > prim.min[a] && v < prim.max[a]) c.push_back(v);
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
    for (size_t k = 0; k < c.size(); ++k) {
      samples[a].push_back(c[k]);
      if (k + 1 < c.size()) samples[a].push_back(0.5 * (c[k] + c[k + 1]));
    }
  }
  if (parts.size() <= 12) {
    for (double x : samples[0])
      for (double y : samples[1])
        for (double z : samples[2])
          if (!inSome({x, y, z})) return false;
    return true;
  }
  std::mt19937 rng(1);
  for (int k = 0; k < 20000; ++k) {
    glm::dvec3 x;
    for (int a = 0; a < 3; ++a) x[a] = samples[a][std::uniform_int_distribution<size_t>(0, samples[a].size() - 1)(rng)];
    if (!inSome(x)) return false;
  }
  return true;
}

// Structural invariants. Returns the depth (root alone = 1). For a builder that splits primitives
// (testing::splitsPrimitives): every primitive referenced at least once, at most
// BuildOptions::sbvhReferenceBudget x n references, each leaf box inside the union of its
// primitives' boxes, and each primitive (a box here: these inputs give no triangles) covered by the
// union of the boxes of the leaves that reference it. For every other builder: each primitive exactly
// once and leaf box = union of its primitives' boxes.
uint32_t checkTree(const Bvh& bvh, const PrimitiveSet& set, uint32_t maxLeafSize, bool splits = false,
                   double referenceBudget = BuildOptions{}.sbvhReferenceBudget) {
  const size_t n = set.size();
  const size_t refs = bvh.primIndices.size();
  EXPECT_FALSE(bvh.nodes.empty());
  if (splits) {
    EXPECT_GE(refs, n);
    EXPECT_LE(double(refs), std::floor(referenceBudget * double(n)));
  } else {
    EXPECT_EQ(refs, n);
  }
  EXPECT_LE(bvh.nodes.size(), 2 * std::max<size_t>(refs, 1) - 1);
  std::vector<int> referenced(n, 0);
  std::vector<std::vector<Aabb>> leafBoxes(splits ? n : 0);
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
        if (splits) leafBoxes[prim].push_back(node.bounds);
      }
      if (splits)
        EXPECT_TRUE(tight.contains(node.bounds) && !node.bounds.empty())
            << "leaf " << index << " box is empty or outside the union of its primitives";
      else
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
    if (splits ? referenced[i] < 1 : referenced[i] != 1) {
      ADD_FAILURE() << "primitive " << i << " referenced " << referenced[i] << " times";
      break;
    }
  if (splits)
    for (size_t i = 0; i < n; ++i)
      if (referenced[i] > 0 && !boxCovered(set.boxes[i], leafBoxes[i])) {
        ADD_FAILURE() << "primitive " << i << " is not covered by the boxes of the " << referenced[i]
                      << " leaves that reference it";
        break;
      }
  return maxDepth;
}

// Builds, checks the invariants and the reported statistics; returns the tree.
Bvh buildChecked(const std::string& builder, const PrimitiveSet& set, BuildOptions options, BuildStats* out = nullptr) {
  BuildStats stats;
  Bvh bvh = buildBvh(builder, set.input(), options, &stats);
  const bool splits = testing::splitsPrimitives(builder);
  const uint32_t depth = checkTree(bvh, set, options.maxLeafSize, splits, options.sbvhReferenceBudget);
  EXPECT_EQ(stats.references, bvh.primIndices.size());
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
  // A builder that splits primitives may cut the pair by a plane (cheaper by the SAH than two
  // coinciding leaves) and end with more leaves.
  if (testing::splitsPrimitives(GetParam()))
    EXPECT_GE(buildChecked(GetParam(), set, options).nodes.size(), 3u);
  else
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
    const uint32_t logDepth = 2 + uint32_t(std::ceil(std::log2(double(set.size()))));
    if (!testing::splitsPrimitives(GetParam())) {
      EXPECT_LE(computeStats(bvh, options.cost).depth, logDepth);
    } else {
      // Spatial splits need no centroid axis: a plane through the nested boxes keeps every reference
      // on one side and sends the straddlers' clipped outer parts to the other, one layer of box
      // sizes per level, each level paid for by the reference budget (here 17 sizes: depth ~30).
      // Still nowhere near linear.
      EXPECT_LE(computeStats(bvh, options.cost).depth, 4 * logDepth);
    }
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
    BVHLAB_SKIP_OR_FAIL(testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`");
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
    BVHLAB_SKIP_OR_FAIL(testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`");
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
