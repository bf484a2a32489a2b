// PLOC-specific properties (builders/ploc.cpp). The invariants every builder keeps (boxes, ranges,
// leaf sizes, degenerate inputs) are checked for ploc too by tests/test_builders.cpp's registry tests.
#include <algorithm>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <limits>
#include <random>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/collapse.hpp"
#include "builders/test_inputs.hpp"
#include "builder_test_util.hpp"
#include "datasets/procedural.hpp"
#include "datasets/random_draws.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using testing::PrimitiveSet;

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

// FNV-1a over everything testing::identical compares (node boxes' bit patterns, links, counts,
// primitive order): a fingerprint of a tree to pin it across code changes.
uint64_t treeHash(const Bvh& bvh) {
  uint64_t h = 1469598103934665603ULL;
  auto mix = [&h](uint32_t word) {
    for (int b = 0; b < 4; ++b) h = (h ^ ((word >> (8 * b)) & 0xff)) * 1099511628211ULL;
  };
  for (const BvhNode& node : bvh.nodes) {
    for (int a = 0; a < 3; ++a) mix(std::bit_cast<uint32_t>(node.bounds.min[a])), mix(std::bit_cast<uint32_t>(node.bounds.max[a]));
    mix(node.count);
    if (node.isLeaf())
      mix(node.first);
    else
      mix(node.left), mix(node.right);
  }
  for (uint32_t p : bvh.primIndices) mix(p);
  return h;
}

BuildOptions withRadius(uint32_t radius, uint32_t threads = 0, uint32_t leafSize = 4) {
  BuildOptions options;
  options.plocRadius = radius;
  options.threads = threads;
  options.maxLeafSize = leafSize;
  return options;
}

double sah(const std::string& builder, const PrimitiveSet& set, const BuildOptions& options) {
  BuildStats stats;
  buildBvh(builder, set.input(), options, &stats);
  return stats.sahCost;
}

// Leaves reached from the root: how often each primitive is referenced, and the depth (root = 1).
struct Walk {
  std::vector<int> references;
  uint32_t depth = 0;
  size_t leafEntries = 0;
};

Walk walk(const Bvh& bvh, size_t primitives) {
  Walk w;
  w.references.assign(primitives, 0);
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};
  while (!stack.empty()) {
    auto [index, depth] = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh.nodes.at(index);
    w.depth = std::max(w.depth, depth);
    if (!node.isLeaf()) {
      stack.push_back({node.right, depth + 1});
      stack.push_back({node.left, depth + 1});
      continue;
    }
    w.leafEntries += node.count;
    for (uint32_t k = node.first; k < node.first + node.count; ++k) ++w.references.at(bvh.primIndices.at(k));
  }
  return w;
}

// The size class builders/morton.hpp defines, the plain way: the square root of the box diagonal over
// the scene's, times 2^s, rounded down, at most 2^s - 1 (0 for a scene of one point).
std::vector<uint32_t> referenceSizeClasses(const PrimitiveSet& set, uint32_t sizeBits) {
  auto diagonal = [](const Aabb& b) { return glm::length(glm::dvec3(b.max) - glm::dvec3(b.min)); };
  Aabb scene;
  for (const Aabb& b : set.boxes) scene.grow(b);
  std::vector<uint32_t> classes(set.size(), 0);
  const double top = double((1u << sizeBits) - 1);
  for (size_t i = 0; i < set.size(); ++i)
    if (sizeBits > 0 && diagonal(scene) > 0.0)
      classes[i] = uint32_t(std::min(top, std::floor(std::sqrt(diagonal(set.boxes[i]) / diagonal(scene)) * (top + 1))));
  return classes;
}

// PLOC as its comment in builders/ploc.cpp defines it, written the plain way (scalar, sequential,
// every merged area computed from both ends; the codes bit by bit, with the grid and the size bits of
// builders/morton.hpp): the builder's vectorised, chunked, threaded passes must give exactly this tree.
Bvh referencePloc(const PrimitiveSet& set, uint32_t radius, uint32_t leafSize, uint32_t sizeBits = 0,
                  MortonGrid grid = MortonGrid::Cube) {
  const uint32_t n = uint32_t(set.size());
  Aabb bounds;
  for (const glm::vec3& c : set.centroids) bounds.grow(c);
  const float cells = float(1 << 21);
  // Cube: 2^21 cells over the longest centroid extent on every axis; Axes: over each axis's own.
  float longest = 0.0f;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, bounds.max[a] - bounds.min[a]);
  glm::vec3 scale(0.0f);
  for (int a = 0; a < 3; ++a) {
    const float extent = bounds.max[a] - bounds.min[a];
    const float over = grid == MortonGrid::Cube ? longest : extent;
    if (extent > 0.0f && std::isfinite(cells / over)) scale[a] = cells / over;
  }
  const std::vector<uint32_t> sizeClass = referenceSizeClasses(set, sizeBits);
  std::vector<std::pair<uint64_t, uint32_t>> keys(n);
  for (uint32_t i = 0; i < n; ++i) {
    const glm::vec3 q = glm::min((set.centroids[i] - bounds.min) * scale, glm::vec3(cells - 1.0f));
    const uint64_t cell[3] = {uint64_t(q.x), uint64_t(q.y), uint64_t(q.z)};
    // 63 bits from the top: position bits x, y, z of bit 20, then of bit 19, ...; after every 6 of them
    // the next size bit (most significant first) while there are size bits left; the position bits
    // that do not fit are the lowest ones.
    uint64_t code = 0;
    uint32_t positionBits = 0, sizeBitsWritten = 0;
    while (positionBits + sizeBitsWritten < 63) {
      if (sizeBitsWritten < sizeBits && sizeBitsWritten < positionBits / 6) {
        code = code << 1 | ((sizeClass[i] >> (sizeBits - 1 - sizeBitsWritten)) & 1);
        ++sizeBitsWritten;
      } else {
        code = code << 1 | ((cell[positionBits % 3] >> (20 - positionBits / 3)) & 1);
        ++positionBits;
      }
    }
    keys[i] = {code, i};
  }
  std::stable_sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) { return a.first < b.first; });

  std::vector<BvhNode> full(2 * size_t(n) - 1);
  uint32_t next = n - 1;
  auto merge = [&](uint32_t l, uint32_t r) {
    BvhNode& node = full[--next];
    node.bounds = full[l].bounds;
    node.bounds.grow(full[r].bounds);
    node.left = l, node.right = r;
    return next;
  };
  std::vector<uint32_t> clusters;
  for (uint32_t k = 0; k < n;) {
    std::vector<uint32_t> run;
    for (const uint64_t code = keys[k].first; k < n && keys[k].first == code; ++k) {
      full[n - 1 + k] = {set.boxes[keys[k].second], 0, 0, keys[k].second, 1};
      run.push_back(n - 1 + k);
    }
    while (run.size() > 1) {  // equal codes: pairs, level by level
      std::vector<uint32_t> up;
      for (size_t p = 0; p + 1 < run.size(); p += 2) up.push_back(merge(run[p], run[p + 1]));
      if (run.size() % 2) up.push_back(run.back());
      run = up;
    }
    clusters.push_back(run[0]);
  }
  while (clusters.size() > 1) testing::referencePlocPass(full, clusters, radius, merge);
  BuildOptions options;
  options.maxLeafSize = leafSize;
  return detail::collapseLeavesBySah(full, options);
}

TEST(Ploc, MatchesTheDefinition) {
  PrimitiveSet zeros;  // coordinates of -0 and +0 side by side, flat boxes, repeated centroids
  for (int i = 0; i < 3000; ++i) {
    const float z = i % 3 ? 0.0f : -0.0f, t = float(i % 40);
    zeros.addBox({glm::vec3(z, t, z), glm::vec3(z, t, i % 7 ? z : 1.0f)}, glm::vec3(z, t, z));
  }
  zeros.name = "signed-zeros";
  PrimitiveSet equalCodes = testing::randomSoup(2000, 8);  // plus runs of equal Morton codes
  for (int i = 0; i < 600; ++i) equalCodes.addBox(equalCodes.boxes[i % 7], equalCodes.centroids[i % 7]);
  for (const PrimitiveSet& set : {testing::randomSoup(40000, 6), testing::sphereSoup(120, 90, 0.2f), zeros, equalCodes}) {
    for (uint32_t radius : {1u, 3u, 16u, 37u}) {
      SCOPED_TRACE(set.name + " radius " + std::to_string(radius));
      EXPECT_TRUE(testing::identical(buildBvh("ploc", set.input(), withRadius(radius, 2)), referencePloc(set, radius, 4)));
    }
    for (uint32_t sizeBits : {1u, 5u, 9u}) {  // Morton size bits (builders/morton.hpp)
      SCOPED_TRACE(set.name + " size bits " + std::to_string(sizeBits));
      BuildOptions options = withRadius(16, 2);
      options.mortonSizeBits = sizeBits;
      EXPECT_TRUE(testing::identical(buildBvh("ploc", set.input(), options), referencePloc(set, 16, 4, sizeBits)));
    }
    for (uint32_t sizeBits : {0u, 5u}) {  // the per-axis grid
      SCOPED_TRACE(set.name + " axes grid, size bits " + std::to_string(sizeBits));
      BuildOptions options = withRadius(16, 2);
      options.mortonSizeBits = sizeBits;
      options.mortonGrid = MortonGrid::Axes;
      EXPECT_TRUE(testing::identical(buildBvh("ploc", set.input(), options),
                                     referencePloc(set, 16, 4, sizeBits, MortonGrid::Axes)));
    }
  }
}

TEST(Ploc, AxesGridWithoutSizeBitsGivesTheTreesOfBeforeSizeBits) {
  // Hashes of the trees ploc (radius 16) and lbvh built before Morton size bits existed (commit fd0daaa),
  // when the codes were always on the per-axis grid: mortonSizeBits = 0 with MortonGrid::Axes must
  // keep those codes, so those trees, bit for bit.
  const struct {
    PrimitiveSet set;
    uint64_t ploc, lbvh;
  } cases[] = {{testing::randomSoup(20000, 3), 0x2e75286c4eaed287, 0x4b136980f4f651f},
                 {testing::sphereSoup(120, 90, 0.2f), 0x9a2d1e571b1ead78, 0x104c8c0f8cf3faad}};
  for (const auto& c : cases) {
    BuildOptions axes = withRadius(16, 2);
    axes.mortonGrid = MortonGrid::Axes;
    const uint64_t ploc = treeHash(buildBvh("ploc", c.set.input(), axes));
    const uint64_t lbvh = treeHash(buildBvh("lbvh", c.set.input(), axes));
    EXPECT_EQ(ploc, c.ploc) << c.set.name;
    EXPECT_EQ(lbvh, c.lbvh) << c.set.name;
  }
}

TEST(Ploc, SameTreeForAnyThreadCount) {
  // Large enough for several search chunks (8192 clusters each) in the first passes.
  for (const PrimitiveSet& set : {testing::randomSoup(60000, 11), testing::sphereSoup(200, 150, 0.2f)}) {
    SCOPED_TRACE(set.name);
    for (uint32_t radius : {1u, 16u, 100u}) {
      const Bvh one = buildBvh("ploc", set.input(), withRadius(radius, 1));
      for (uint32_t threads : {2u, 8u})
        EXPECT_TRUE(testing::identical(one, buildBvh("ploc", set.input(), withRadius(radius, threads))))
            << "radius " << radius << ", " << threads << " threads";
    }
    BuildOptions sized = withRadius(16, 1);  // with Morton size bits
    sized.mortonSizeBits = 6;
    const Bvh one = buildBvh("ploc", set.input(), sized);
    for (uint32_t threads : {2u, 8u}) {
      sized.threads = threads;
      EXPECT_TRUE(testing::identical(one, buildBvh("ploc", set.input(), sized))) << "size bits 6, " << threads << " threads";
    }
  }
}

TEST(Ploc, EveryPrimitiveReferencedExactlyOnce) {
  PrimitiveSet clumps = testing::randomSoup(3000, 5);  // plus exact duplicates and shared centroids
  for (size_t i = 0; i < 1000; ++i) clumps.addBox(clumps.boxes[i], clumps.centroids[i]);
  for (int i = 0; i < 500; ++i) {
    const float s = 0.001f * float(1 + i % 7);
    clumps.addBox({glm::vec3(0.5f - s), glm::vec3(0.5f + s)}, glm::vec3(0.5f));
  }
  for (const PrimitiveSet& set : {testing::randomSoup(20000, 4), clumps, testing::planeSoup(5000)}) {
    for (uint32_t leafSize : {1u, 4u, 16u}) {
      for (uint32_t radius : {1u, 16u, 64u}) {
        SCOPED_TRACE(set.name + " leaf " + std::to_string(leafSize) + " radius " + std::to_string(radius));
        const Bvh bvh = buildBvh("ploc", set.input(), withRadius(radius, 0, leafSize));
        ASSERT_EQ(bvh.primIndices.size(), set.size());
        const Walk w = walk(bvh, set.size());
        EXPECT_EQ(w.leafEntries, set.size());
        EXPECT_EQ(std::count(w.references.begin(), w.references.end(), 1), ptrdiff_t(set.size()));
      }
    }
  }
}

TEST(Ploc, BadRadiusIsAnInvalidArgument) {
  const PrimitiveSet set = testing::randomSoup(100);
  for (uint32_t radius : {0u, 1025u}) {
    try {
      buildBvh("ploc", set.input(), withRadius(radius));
      FAIL() << "radius " << radius << " accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("plocRadius " + std::to_string(radius)), std::string::npos) << what;
      EXPECT_NE(what.find("1..1024"), std::string::npos) << what;
    }
  }
  // The extremes of the range work, also with a window wider than the input.
  for (uint32_t radius : {1u, 1024u}) EXPECT_NO_THROW(buildBvh("ploc", set.input(), withRadius(radius)));
}

TEST(Ploc, LargerRadiusIsNotWorseOnRandomSoups) {
  // Not a theorem (greedy merges compound), but radius 1 sees only the two Morton neighbours, radius
  // 16 up to 32 candidates: measured 12% lower SAH with 16 (seeds 1-3, 20k triangles), and 1.5%
  // lower again with 64. A larger radius losing clearly would point at a broken search.
  for (uint32_t seed : {1u, 2u, 3u}) {
    const PrimitiveSet set = testing::randomSoup(20000, seed);
    const double r1 = sah("ploc", set, withRadius(1)), r16 = sah("ploc", set, withRadius(16)),
                 r64 = sah("ploc", set, withRadius(64));
    EXPECT_LT(r16, 0.95 * r1) << "seed " << seed;
    EXPECT_LT(r64, 1.01 * r16) << "seed " << seed;
  }
}

TEST(Ploc, SahBelowSahBinnedOnRandomSoups) {
  // Overlapping boxes of mixed sizes are where clustering beats top-down splits: measured 0.90-0.91x
  // sah-binned (seeds 1-3, 20k triangles, leaf 4).
  for (uint32_t seed : {1u, 2u, 3u}) {
    const PrimitiveSet set = testing::randomSoup(20000, seed);
    EXPECT_LE(sah("ploc", set, withRadius(16)), 0.97 * sah("sah-binned", set, {})) << "seed " << seed;
  }
}

TEST(Ploc, SahNearSahBinnedOnTheBunny) {
  // Measured 1.09x sah-binned (37.35 vs 34.25, leaf 4): the quality target of 1.05x is NOT met on
  // scanned meshes (elephant and armadillo also 1.09x); radius 8..1024 does not change that (the
  // greedy merge order, not the window, is the limit). The bound guards against regressions.
  const PrimitiveSet bunny = testing::loadTriangles(testing::bunnyPath());
  if (bunny.size() == 0) BVHLAB_SKIP_OR_FAIL(testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`");
  EXPECT_LE(sah("ploc", bunny, withRadius(16)), 1.12 * sah("sah-binned", bunny, {}));
}

BuildOptions withTopDown(uint32_t fraction, uint32_t threads = 0, uint32_t leafSize = 4) {
  BuildOptions options = withRadius(16, threads, leafSize);
  options.plocTopDown = fraction;
  return options;
}

// PLOC with an SAH top (BuildOptions::plocTopDown): the same tree for any thread count, every
// primitive once, and a fraction above the primitive count leaves nothing to the top: plain PLOC.
TEST(Ploc, TopDownSameTreeForAnyThreadCount) {
  for (const PrimitiveSet& set : {testing::randomSoup(60000, 11), testing::sphereSoup(200, 150, 0.2f)}) {
    SCOPED_TRACE(set.name);
    for (uint32_t fraction : {2u, 4u, 64u}) {
      const Bvh one = buildBvh("ploc", set.input(), withTopDown(fraction, 1));
      EXPECT_FALSE(testing::identical(one, buildBvh("ploc", set.input(), withTopDown(0, 1))))
          << "top-down " << fraction << " built plain PLOC's tree";
      for (uint32_t threads : {2u, 8u})
        EXPECT_TRUE(testing::identical(one, buildBvh("ploc", set.input(), withTopDown(fraction, threads))))
            << "top-down " << fraction << ", " << threads << " threads";
    }
  }
}

// Every inner node's box is its children's union, left.grow(right), bit for bit, the top's nodes
// as much as the clustered ones: with coordinates of -0 and +0 side by side, a union taken in another
// order (sah-binned's own box of a top node) keeps the same value but may flip a zero's sign.
TEST(Ploc, TopDownInnerBoxesAreTheirChildrensUnions) {
  PrimitiveSet zeros;
  for (int i = 0; i < 20000; ++i) {
    const float z = i % 3 ? 0.0f : -0.0f, t = float(i % 97) - 48.0f, u = float(i % 89) - 44.0f;
    zeros.addBox({glm::vec3(z, t, u), glm::vec3(i % 5 ? z : 1.0f, t, u + 0.5f)}, glm::vec3(z, t, u));
  }
  zeros.name = "signed-zeros";
  for (const PrimitiveSet& set : {zeros, testing::randomSoup(20000, 12)})
    for (uint32_t fraction : {2u, 4u, 16u}) {
      SCOPED_TRACE(set.name + " top-down " + std::to_string(fraction));
      const Bvh bvh = buildBvh("ploc", set.input(), withTopDown(fraction, 1, 1));  // leaf 1: no collapse
      size_t inner = 0, differ = 0;
      for (const BvhNode& node : bvh.nodes) {
        if (node.isLeaf()) continue;
        Aabb u = bvh.nodes[node.left].bounds;
        u.grow(bvh.nodes[node.right].bounds);
        ++inner;
        differ += std::memcmp(&u, &node.bounds, sizeof u) != 0;
      }
      EXPECT_EQ(inner, set.size() - 1);
      EXPECT_EQ(differ, 0u);
    }
}

TEST(Ploc, TopDownReferencesEveryPrimitiveOnce) {
  PrimitiveSet clumps = testing::randomSoup(3000, 5);  // plus exact duplicates and shared centroids
  for (size_t i = 0; i < 1000; ++i) clumps.addBox(clumps.boxes[i], clumps.centroids[i]);
  for (const PrimitiveSet& set : {testing::randomSoup(20000, 4), clumps, testing::planeSoup(5000)})
    for (uint32_t leafSize : {1u, 4u, 16u})
      for (uint32_t fraction : {1u, 4u, 1024u}) {
        SCOPED_TRACE(set.name + " leaf " + std::to_string(leafSize) + " top-down " + std::to_string(fraction));
        const Bvh bvh = buildBvh("ploc", set.input(), withTopDown(fraction, 0, leafSize));
        ASSERT_EQ(bvh.primIndices.size(), set.size());
        const Walk w = walk(bvh, set.size());
        EXPECT_EQ(w.leafEntries, set.size());
        EXPECT_EQ(std::count(w.references.begin(), w.references.end(), 1), ptrdiff_t(set.size()));
        auto contains = [](const Aabb& outer, const Aabb& inner) {
          return glm::all(glm::lessThanEqual(outer.min, inner.min)) && glm::all(glm::greaterThanEqual(outer.max, inner.max));
        };
        size_t outside = 0;  // children or primitives outside their node's box
        for (const BvhNode& node : bvh.nodes)
          if (node.isLeaf())
            for (uint32_t k = node.first; k < node.first + node.count; ++k)
              outside += !contains(node.bounds, set.boxes[bvh.primIndices[k]]);
          else
            outside += !contains(node.bounds, bvh.nodes[node.left].bounds) + !contains(node.bounds, bvh.nodes[node.right].bounds);
        EXPECT_EQ(outside, 0u);
      }
}

TEST(Ploc, TopDownAboveThePrimitiveCountIsPlainPloc) {
  const PrimitiveSet set = testing::randomSoup(1000, 3);  // n / 1024 = 0: no cluster is left to the top
  EXPECT_TRUE(testing::identical(buildBvh("ploc", set.input(), withTopDown(1024)), buildBvh("ploc", set.input(), withTopDown(0))));
  try {
    buildBvh("ploc", set.input(), withTopDown(1025));
    FAIL() << "top-down 1025 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("plocTopDown 1025 is outside 0..1024"), std::string::npos) << e.what();
  }
}

TEST(Ploc, TopDownBringsTheSahWithin5PercentOfSahBinnedOnTheBunny) {
  // Measured (leaf 4, vertex-mean centroids as here): plain PLOC 1.098x sah-binned's SAH, with the
  // last n/4 clusters split by binned SAH 1.035x (the target: 1.05x). The SAH top recovers
  // what PLOC loses in the upper levels (docs/builders.md).
  const PrimitiveSet bunny = testing::loadTriangles(testing::bunnyPath());
  if (bunny.size() == 0) BVHLAB_SKIP_OR_FAIL(testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`");
  const double binned = sah("sah-binned", bunny, {}), plain = sah("ploc", bunny, withTopDown(0)),
               top = sah("ploc", bunny, withTopDown(4));
  EXPECT_LE(top, 1.05 * binned);
  EXPECT_LT(top, 0.97 * plain);
}

TEST(Ploc, EqualBoxesPairUpInsteadOfChaining) {
  // 4096 equal boxes on a line, equally spaced: every merged area ties with the next. The tie rule
  // pairs (2k, 2k+1) each pass, so the tree is perfectly balanced (a chain would be 4096 deep).
  PrimitiveSet set;
  for (int i = 0; i < 4096; ++i) set.addBox({glm::vec3(float(i), 0, 0), glm::vec3(float(i) + 0.5f, 1, 1)},
                                            glm::vec3(float(i) + 0.25f, 0.5f, 0.5f));
  const Bvh bvh = buildBvh("ploc", set.input(), withRadius(16, 0, 1));
  EXPECT_EQ(walk(bvh, set.size()).depth, 13u);  // log2(4096) + 1
}

TEST(Ploc, CoincidentCentroidsMakeABalancedTree) {
  // Nested boxes around one centre (equal Morton codes): clustered by area they would chain; as a run
  // they start as one balanced cluster.
  PrimitiveSet set;
  for (int i = 0; i < 1000; ++i) {
    const float s = 0.001f * float(1 + i % 17);
    set.addBox({glm::vec3(-s), glm::vec3(s)}, glm::vec3(0.0f));
  }
  const Bvh bvh = buildBvh("ploc", set.input(), withRadius(16, 0, 1));
  EXPECT_EQ(walk(bvh, set.size()).depth, 11u);  // ceil(log2(1000)) + 1
}

// ---- measurements (not run by default) -----------------------------------------------------------
// ./tests/test_ploc --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_RadiusCurve'
// prints docs/builders.md's radius table: per mesh (PLOC_MESH: one of the names below), sah-binned and
// ploc at each radius: SAH, ray cost, single-thread build CPU ms, median [min-max] of 5 runs.

// Node visits + triangle tests per ray of an ordered stack traversal over the Bvh itself (both
// children's boxes tested, the nearer pushed last; closest hit, Moller-Trumbore): a layout-free
// count, so builders compare without a packer in between.
double rayCost(const Bvh& bvh, const PrimitiveSet& set, const std::vector<glm::vec3>& origins,
               const std::vector<glm::vec3>& directions) {
  auto slab = [](const Aabb& b, const glm::vec3& o, const glm::vec3& inv, float tMax, float& tNear) {
    const glm::vec3 t0 = (b.min - o) * inv, t1 = (b.max - o) * inv;
    const glm::vec3 lo = glm::min(t0, t1), hi = glm::max(t0, t1);
    tNear = std::max(std::max(lo.x, lo.y), std::max(lo.z, 0.0f));
    return tNear <= std::min(std::min(hi.x, hi.y), std::min(hi.z, tMax));
  };
  double cost = 0.0;
  std::vector<uint32_t> stack;
  for (size_t r = 0; r < origins.size(); ++r) {
    const glm::vec3 o = origins[r], d = directions[r], inv = 1.0f / d;
    float t = std::numeric_limits<float>::max(), near = 0.0f, nearRight = 0.0f;
    stack.assign(1, 0);
    while (!stack.empty()) {
      const BvhNode& n = bvh.nodes[stack.back()];
      stack.pop_back();
      cost += 1.0;
      if (n.isLeaf()) {
        for (uint32_t k = n.first; k < n.first + n.count; ++k) {
          cost += 1.0;
          const uint32_t i = bvh.primIndices[k];
          const glm::vec3 e1 = set.v1[i] - set.v0[i], e2 = set.v2[i] - set.v0[i], p = glm::cross(d, e2);
          const float det = glm::dot(e1, p);
          if (det == 0.0f) continue;  // parallel to the triangle's plane
          const glm::vec3 s = o - set.v0[i], q = glm::cross(s, e1);
          const float u = glm::dot(s, p) / det, v = glm::dot(d, q) / det, h = glm::dot(e2, q) / det;
          if (u >= 0.0f && v >= 0.0f && u + v <= 1.0f && h > 0.0f && h < t) t = h;
        }
        continue;
      }
      const bool left = slab(bvh.nodes[n.left].bounds, o, inv, t, near);
      const bool right = slab(bvh.nodes[n.right].bounds, o, inv, t, nearRight);
      if (left && right) {
        stack.push_back(near <= nearRight ? n.right : n.left);
        stack.push_back(near <= nearRight ? n.left : n.right);
      } else if (left || right) {
        stack.push_back(left ? n.left : n.right);
      }
    }
  }
  return cost / double(origins.size());
}

// 20,000 rays from a sphere around the set towards points in its box.
struct Rays {
  std::vector<glm::vec3> origins, directions;
};
Rays measurementRays(const PrimitiveSet& set) {
  Aabb bounds;
  for (const Aabb& b : set.boxes) bounds.grow(b);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Rays rays;
  const glm::vec3 centre = 0.5f * (bounds.min + bounds.max);
  const float radius = glm::length(bounds.max - bounds.min);
  while (rays.origins.size() < 20000) {
    const glm::vec3 w = draw3<glm::vec3>(u, rng) * 2.0f - 1.0f;
    if (glm::length(w) > 1.0f || glm::length(w) < 1e-3f) continue;  // uniform directions, none near 0
    const glm::vec3 from = centre + radius * glm::normalize(w);
    const glm::vec3 to = bounds.min + draw3<glm::vec3>(u, rng) * (bounds.max - bounds.min);
    rays.origins.push_back(from);
    rays.directions.push_back(glm::normalize(to - from));
  }
  return rays;
}

// One table row: the builder with these options (one thread), 5 builds: SAH, ray cost, build CPU ms
// median [min-max]; the SAH also as a multiple of `referenceSah` when that is given.
double measureRow(const std::string& mesh, const PrimitiveSet& set, const Rays& rays, const std::string& builder,
                  const std::string& setting, const BuildOptions& options, double referenceSah = 0.0) {
  std::vector<double> ms;
  Bvh bvh;
  for (int k = 0; k < 5; ++k) {
    const double c0 = threadCpuMs();
    bvh = buildBvh(builder, set.input(), options);
    ms.push_back(threadCpuMs() - c0);
  }
  std::sort(ms.begin(), ms.end());
  const double sah = sahCost(bvh, options.cost);
  std::printf("| %s | %s | %s | %.3f (%.3fx) | %.2f | %.1f [%.1f-%.1f] |\n", mesh.c_str(), builder.c_str(),
              setting.c_str(), sah, referenceSah > 0.0 ? sah / referenceSah : 1.0,
              rayCost(bvh, set, rays.origins, rays.directions), ms[2], ms[0], ms[4]);
  std::fflush(stdout);
  return sah;
}

TEST(PlocMeasure, DISABLED_RadiusCurve) {
  const char* only = std::getenv("PLOC_MESH");
  const std::filesystem::path dir = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes";
  for (const std::string mesh : {"bunny00", "refined_elephant", "armadillo"}) {
    if (only && mesh != only) continue;
    const PrimitiveSet set = testing::loadTriangles(dir / (mesh + ".off"));
    if (set.size() == 0) continue;
    const Rays rays = measurementRays(set);
    const double reference = measureRow(mesh, set, rays, "sah-binned", "-", withRadius(16, 1));
    for (uint32_t r : {1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u, 256u})
      measureRow(mesh, set, rays, "ploc", "radius " + std::to_string(r), withRadius(r, 1), reference);
  }
}

// ./tests/test_ploc --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_SizeBitsCurve'
// prints docs/builders.md's Morton size bits table: per mesh (PLOC_MESH as above; PLOC_LARGE=1 adds
// makeLargeMesh(1M)), sah-binned, then ploc (radius 16) and lbvh with BuildOptions::mortonSizeBits
// 0, 3, 6 and 9; leaf 4, one thread, as DISABLED_RadiusCurve.
TEST(PlocMeasure, DISABLED_SizeBitsCurve) {
  const char* only = std::getenv("PLOC_MESH");
  const char* large = std::getenv("PLOC_LARGE");
  const std::filesystem::path dir = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes";
  std::vector<std::string> meshes{"bunny00", "refined_elephant", "armadillo"};
  if (large && std::string(large) == "1") meshes.push_back("large1M");
  for (const std::string& mesh : meshes) {
    if (only && mesh != only) continue;
    PrimitiveSet set;
    if (mesh == "large1M") {
      const Mesh m = makeLargeMesh(1000000);
      for (const glm::uvec3& t : m.triangles) set.addTriangle(m.positions[t.x], m.positions[t.y], m.positions[t.z]);
    } else {
      set = testing::loadTriangles(dir / (mesh + ".off"));
    }
    if (set.size() == 0) continue;
    const Rays rays = measurementRays(set);
    const double reference = measureRow(mesh, set, rays, "sah-binned", "-", withRadius(16, 1));
    for (const std::string builder : {"ploc", "lbvh"})
      for (uint32_t sizeBits : {0u, 3u, 6u, 9u}) {
        BuildOptions options = withRadius(16, 1);
        options.mortonSizeBits = sizeBits;
        measureRow(mesh, set, rays, builder, "size bits " + std::to_string(sizeBits), options, reference);
      }
  }
}

}  // namespace
}  // namespace bvhlab
