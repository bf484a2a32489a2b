// sah-binned against a textbook binned SAH build written out here: the fast builder (one-pass
// binning of three axes with stored bin indices, two-sided in-place partition, subset and sorted
// paths for tiny nodes, three axes swept in SIMD lanes) must build the same tree: the same boxes,
// the same leaves with the same primitives, the same inner structure; for every bin count, leaf size
// and cost model, and for any thread count.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using testing::PrimitiveSet;

// The textbook build (Wald 2007): per node, centroids binned on each axis over the node's centroid
// bounds (bin = min((c - lo) * (bins / extent), bins - 1), truncated; an axis with zero extent, or
// one so thin that bins / extent overflows, is not binned), the SAH Ci * (A_L N_L + A_R N_R)
// evaluated in double from float half areas after every occupied bin but the last, the first
// minimum over axes x, y, z and bins in order; a leaf when that does not beat Ci * A * N (and the
// node fits in a leaf); otherwise, without a winning split, the object median on the longest
// centroid axis by (centroid, index). A straightforward recursive implementation.
struct Textbook {
  struct Node {
    Aabb box;
    int left = -1, right = -1;
    std::vector<uint32_t> prims;  // leaves: sorted
  };
  const PrimitiveSet& set;
  BuildOptions options;
  uint32_t bins;
  std::vector<uint32_t> ids;
  std::vector<Node> nodes;

  Textbook(const PrimitiveSet& s, const BuildOptions& o) : set(s), options(o), bins(o.bins ? o.bins : 64) {
    ids.resize(set.size());
    for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
    Aabb box;
    for (const Aabb& b : set.boxes) box.grow(b);
    build(0, uint32_t(ids.size()), box);
  }

  int build(uint32_t begin, uint32_t end, const Aabb& box) {
    const int index = int(nodes.size());
    nodes.emplace_back();
    nodes.back().box = box;
    const uint32_t n = end - begin;
    auto leaf = [&] {
      std::vector<uint32_t> prims(ids.begin() + begin, ids.begin() + end);
      std::sort(prims.begin(), prims.end());
      nodes[index].prims = prims;
      return index;
    };
    if (n == 1) return leaf();
    Aabb centroids;
    for (uint32_t i = begin; i < end; ++i) centroids.grow(set.centroids[ids[i]]);

    // Best binned split.
    int bestAxis = -1;
    uint32_t bestBin = 0;
    double bestCost = std::numeric_limits<double>::infinity();
    const double ci = options.cost.intersectionCost;
    auto binOf = [&](uint32_t prim, int axis, float scale) {
      const float v = std::min((set.centroids[prim][axis] - centroids.min[axis]) * scale, float(bins - 1));
      return uint32_t(v);
    };
    for (int axis = 0; axis < 3; ++axis) {
      const float extent = centroids.max[axis] - centroids.min[axis];
      const float scale = float(bins) / extent;
      if (!(extent > 0.0f) || !std::isfinite(scale)) continue;
      std::vector<Aabb> binBox(bins);
      std::vector<uint32_t> binCount(bins, 0);
      for (uint32_t i = begin; i < end; ++i) {
        const uint32_t b = binOf(ids[i], axis, scale);
        binBox[b].grow(set.boxes[ids[i]]);
        ++binCount[b];
      }
      std::vector<uint32_t> occupied;
      for (uint32_t b = 0; b < bins; ++b)
        if (binCount[b]) occupied.push_back(b);
      for (size_t k = 0; k + 1 < occupied.size(); ++k) {
        Aabb left, right;
        uint32_t nl = 0, nr = 0;
        for (size_t j = 0; j <= k; ++j) left.grow(binBox[occupied[j]]), nl += binCount[occupied[j]];
        for (size_t j = k + 1; j < occupied.size(); ++j) right.grow(binBox[occupied[j]]), nr += binCount[occupied[j]];
        const double rightCost = double(right.halfArea()) * nr;
        const double cost = ci * (double(left.halfArea()) * nl + rightCost);
        if (cost < bestCost) bestCost = cost, bestAxis = axis, bestBin = occupied[k];
      }
    }

    const CostModel& c = options.cost;
    const double area = box.halfArea();
    const bool splitWins = bestAxis >= 0 && c.traversalCost * area + bestCost < c.intersectionCost * area * n;
    if (!splitWins && n <= options.maxLeafSize) return leaf();
    uint32_t mid;
    if (splitWins) {
      const float scale = float(bins) / (centroids.max[bestAxis] - centroids.min[bestAxis]);
      mid = uint32_t(std::partition(ids.begin() + begin, ids.begin() + end,
                                    [&](uint32_t p) { return binOf(p, bestAxis, scale) <= bestBin; }) -
                     ids.begin());
    } else {
      const glm::vec3 e = centroids.max - centroids.min;
      const int axis = e.y > e.x ? (e.z > e.y ? 2 : 1) : (e.z > e.x ? 2 : 0);
      mid = begin + n / 2;
      std::nth_element(ids.begin() + begin, ids.begin() + mid, ids.begin() + end, [&](uint32_t a, uint32_t b) {
        const float ca = set.centroids[a][axis], cb = set.centroids[b][axis];
        return ca < cb || (ca == cb && a < b);
      });
    }
    Aabb leftBox, rightBox;
    for (uint32_t i = begin; i < mid; ++i) leftBox.grow(set.boxes[ids[i]]);
    for (uint32_t i = mid; i < end; ++i) rightBox.grow(set.boxes[ids[i]]);
    const int left = build(begin, mid, leftBox);
    const int right = build(mid, end, rightBox);
    nodes[index].left = left, nodes[index].right = right;
    return index;
  }
};

bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

// Walks both trees from the root; returns "" or where they first differ.
std::string compare(const Bvh& bvh, const Textbook& book) {
  std::vector<std::pair<uint32_t, int>> stack{{0u, 0}};
  size_t visited = 0;
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    ++visited;
    const BvhNode& a = bvh.nodes[i];
    const Textbook::Node& b = book.nodes[size_t(j)];
    const std::string where = "node " + std::to_string(i) + " (textbook " + std::to_string(j) + ")";
    if (!sameBox(a.bounds, b.box)) return where + ": boxes differ";
    if (a.isLeaf() != (b.left < 0)) return where + ": leaf in one tree only";
    if (a.isLeaf()) {
      std::vector<uint32_t> prims(bvh.primIndices.begin() + a.first, bvh.primIndices.begin() + a.first + a.count);
      std::sort(prims.begin(), prims.end());
      if (prims != b.prims) return where + ": leaves hold different primitives";
    } else {
      stack.push_back({a.right, b.right});
      stack.push_back({a.left, b.left});
    }
  }
  if (visited != bvh.nodes.size() || visited != book.nodes.size()) return "node counts differ";
  return "";
}

std::vector<PrimitiveSet> inputs() {
  std::vector<PrimitiveSet> sets = {testing::randomSoup(3000, 11), testing::gridSoup(40, 30), testing::sphereSoup(50, 40, 0.2f),
                                    testing::thinTriangles(2000), testing::planeSoup(3000)};
  PrimitiveSet equal;  // one common centroid: the median fallback
  equal.name = "equal";
  for (int i = 0; i < 500; ++i) {
    const float s = 0.001f * float(1 + i % 17);
    equal.addBox({glm::vec3(-s), glm::vec3(s)}, glm::vec3(0.0f));
  }
  sets.push_back(equal);
  PrimitiveSet ladder;  // exponentially spaced: deep, and centroids that share bins at every level
  ladder.name = "ladder";
  for (int i = 0; i < 800; ++i) {
    const float x = std::pow(1.02f, float(i));
    ladder.addBox({glm::vec3(x, 0, 0), glm::vec3(x + 0.01f, 0.01f, 0.01f)}, glm::vec3(x + 0.005f, 0.005f, 0.005f));
  }
  sets.push_back(ladder);
  PrimitiveSet duplicates;  // the same triangle several times among others: ties everywhere
  duplicates.name = "duplicates";
  for (int i = 0; i < 600; ++i) {
    const float x = float(i % 7);
    duplicates.addTriangle({x, 0, 0}, {x + 1, 0, 0}, {x, 1, float(i % 3)});
  }
  sets.push_back(duplicates);
  return sets;
}

TEST(SahBinned, SameTreeAsTheTextbookBuild) {
  for (const PrimitiveSet& set : inputs()) {
    for (uint32_t bins : {0u, 2u, 7u, 32u, 256u}) {  // 0: the default (64)
      for (uint32_t leafSize : {1u, 4u, 16u}) {
        BuildOptions options;
        options.bins = bins;
        options.maxLeafSize = leafSize;
        options.threads = 1;
        const Bvh bvh = buildBvh("sah-binned", set.input(), options);
        const Textbook book(set, options);
        EXPECT_EQ(compare(bvh, book), "") << set.name << " bins " << bins << " leaf " << leafSize;
      }
    }
  }
}

TEST(SahBinned, SameTreeAsTheTextbookBuildForOtherCostModels) {
  for (const PrimitiveSet& set : {testing::randomSoup(2000, 5), testing::sphereSoup(40, 30, 0.2f)}) {
    for (CostModel cost : {CostModel{0.5f, 2.0f}, CostModel{3.0f, 1.0f}, CostModel{1.0f, 0.3f}}) {
      BuildOptions options;
      options.cost = cost;
      options.threads = 1;
      const Bvh bvh = buildBvh("sah-binned", set.input(), options);
      EXPECT_EQ(compare(bvh, Textbook(set, options)), "") << set.name << " Ct " << cost.traversalCost << " Ci " << cost.intersectionCost;
    }
  }
}

// Large enough for the threaded driver (>= detail::kParallelMinInput primitives) and for the two bin sets (>= 1024 per node).
TEST(SahBinned, SameTreeAsTheTextbookBuildOnTheBunnyAndForAnyThreadCount) {
  PrimitiveSet bunny = testing::loadTriangles(testing::bunnyPath());
  if (bunny.size() == 0) bunny = testing::randomSoup(40000, 9);  // the data set is optional; the property is not
  BuildOptions options;
  options.threads = 1;
  const Bvh one = buildBvh("sah-binned", bunny.input(), options);
  EXPECT_EQ(compare(one, Textbook(bunny, options)), "");
  for (uint32_t threads : {2u, 3u, 8u}) {
    options.threads = threads;
    const Bvh many = buildBvh("sah-binned", bunny.input(), options);
    EXPECT_EQ(many.primIndices, one.primIndices) << threads << " threads";
    ASSERT_EQ(many.nodes.size(), one.nodes.size()) << threads << " threads";
    for (size_t i = 0; i < one.nodes.size(); ++i) {
      const BvhNode &a = one.nodes[i], &b = many.nodes[i];
      ASSERT_TRUE(sameBox(a.bounds, b.bounds) && a.count == b.count && a.first == b.first && a.left == b.left && a.right == b.right)
          << threads << " threads, node " << i;
    }
  }
}

// The SAH to keep: 34.25 at leaf 4 on the bunny with these triangle centroids (the
// renderer's scene loader frames the mesh differently and measures 33.76), within 1.01x Embree MEDIUM.
TEST(SahBinned, KeepsItsSahOnTheBunny) {
  const PrimitiveSet bunny = testing::loadTriangles(testing::bunnyPath());
  if (bunny.size() == 0) BVHLAB_SKIP_OR_FAIL(testing::bunnyPath() << " is missing: run `bash datasets/fetch.sh`");
  BuildStats binned, embree;
  buildBvh("sah-binned", bunny.input(), {}, &binned);
  buildBvh("embree", bunny.input(), {}, &embree);
  EXPECT_NEAR(binned.sahCost, 34.2543, 0.005 * 34.2543);
  EXPECT_LE(binned.sahCost, 1.01 * embree.sahCost);
}

}  // namespace
}  // namespace bvhlab
