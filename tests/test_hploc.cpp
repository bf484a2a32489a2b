// hploc (builders/hploc.cpp) against its definition (builders/hploc.hpp) written the other way round:
// the radix tree found top-down (each range split where its keys' highest differing bit flips) and
// walked depth-first, where the builder climbs it bottom-up; and its quality, options and edge cases.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builder_test_util.hpp"
#include "builders/builder.hpp"
#include "builders/collapse.hpp"
#include "builders/hploc.hpp"
#include "builders/morton.hpp"
#include "builders/morton_sort.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "gpu_builder_test_util.hpp"
#include "layout/layout.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using detail::hploc::kGroup;
using detail::hploc::kKeep;
using testing::PrimitiveSet;
using testing::withRadius;

// The definition, plainly: sorted keys (code, position); a range [l, r] splits after the position s
// whose pair (s, s + 1) differs in the highest bit, (code XOR, position XOR) compared code first;
// children first, left first; a range of one Morton code is one node over its children; another
// range's list is the left child's then the right's, clustered by ploc's passes (referencePlocPass,
// without the builders' key code) down to kKeep clusters above kKeep primitives and to one at the root.
Bvh referenceHploc(const PrimitiveSet& set, const BuildOptions& options) {
  const BuildInput input = set.input();
  const uint32_t n = uint32_t(set.boxes.size());
  const detail::MortonEncoder encoder(input, options.mortonSizeBits, options.mortonGrid);
  detail::ScratchVector<detail::Keyed> keys(n);
  for (uint32_t i = 0; i < n; ++i) keys[i] = {encoder.code(i), i};
  detail::sortMortonKeys(keys, 1);
  std::vector<BvhNode> full(2 * size_t(n) - 1);
  for (uint32_t k = 0; k < n; ++k) full[n - 1 + k] = {set.boxes[keys[k].id], 0, 0, keys[k].id, 1};
  uint32_t next = n - 1;
  auto merge = [&](uint32_t l, uint32_t r) {
    BvhNode& node = full[--next];
    node.bounds = full[l].bounds;
    node.bounds.grow(full[r].bounds);
    node.left = l, node.right = r;
    return next;
  };
  auto differs = [&](uint32_t i) {  // the XOR of the keys at i and i + 1, as (code, position)
    return std::pair{keys[i].code ^ keys[i + 1].code, i ^ (i + 1)};
  };
  std::function<std::vector<uint32_t>(uint32_t, uint32_t)> listOf = [&](uint32_t l, uint32_t r) {
    if (l == r) return std::vector<uint32_t>{n - 1 + l};
    uint32_t s = l;
    for (uint32_t i = l + 1; i < r; ++i)
      if (differs(i) > differs(s)) s = i;
    std::vector<uint32_t> list = listOf(l, s);
    const std::vector<uint32_t> right = listOf(s + 1, r);
    if (keys[l].code == keys[r].code) return std::vector<uint32_t>{merge(list.at(0), right.at(0))};
    list.insert(list.end(), right.begin(), right.end());
    const bool root = l == 0 && r == n - 1;
    if (r - l + 1 <= kKeep && !root) return list;
    EXPECT_LE(list.size(), kGroup);
    while (list.size() > (root ? 1u : kKeep)) testing::referencePlocPass(full, list, options.plocRadius, merge);
    return list;
  };
  if (n > 1) listOf(0, n - 1);
  return detail::collapseLeavesBySah(full, options);
}

PrimitiveSet signedZeros() {  // coordinates of -0 and +0 side by side, flat boxes, repeated centroids
  PrimitiveSet zeros;
  for (int i = 0; i < 3000; ++i) {
    const float z = i % 3 ? 0.0f : -0.0f, t = float(i % 40);
    zeros.addBox({glm::vec3(z, t, z), glm::vec3(z, t, i % 7 ? z : 1.0f)}, glm::vec3(z, t, z));
  }
  zeros.name = "signed-zeros";
  return zeros;
}

TEST(Hploc, MatchesTheDefinition) {
  PrimitiveSet equalCodes = testing::randomSoup(2000, 8);  // plus runs of equal Morton codes
  for (int i = 0; i < 600; ++i) equalCodes.addBox(equalCodes.boxes[i % 7], equalCodes.centroids[i % 7]);
  equalCodes.name = "equal-codes";
  for (const PrimitiveSet& set : {testing::randomSoup(20000, 6), testing::sphereSoup(120, 90, 0.2f), signedZeros(),
                                  equalCodes, testing::gridSoup(60, 40)}) {
    for (uint32_t radius : {1u, 3u, 16u, 40u}) {
      SCOPED_TRACE(set.name + " radius " + std::to_string(radius));
      EXPECT_TRUE(testing::identical(buildBvh("hploc", set.input(), withRadius(radius)), referenceHploc(set, withRadius(radius))));
    }
    BuildOptions sized = withRadius(8);  // Morton size bits and the per-axis grid change only the codes
    sized.mortonSizeBits = 5;
    sized.mortonGrid = MortonGrid::Axes;
    sized.maxLeafSize = 1;
    SCOPED_TRACE(set.name + " size bits, axes grid, leaf 1");
    EXPECT_TRUE(testing::identical(buildBvh("hploc", set.input(), sized), referenceHploc(set, sized)));
  }
}

TEST(Hploc, ValidTreesFromOneToManyPrimitives) {
  for (size_t n : {size_t(1), size_t(2), size_t(3), size_t(kKeep), size_t(kKeep + 1), size_t(kGroup + 1), size_t(5000)}) {
    SCOPED_TRACE(n);
    const PrimitiveSet set = testing::randomSoup(n, 11);
    const Bvh bvh = buildBvh("hploc", set.input(), {});
    testing::expectValidTree(bvh, set.input(), BuildOptions{}.maxLeafSize);
  }
}

// A radius of kGroup - 1 already searches a whole list: any larger radius gives the same tree.
TEST(Hploc, ARadiusPastTheGroupSearchesTheWholeList) {
  const PrimitiveSet set = testing::randomSoup(8000, 3);
  const Bvh whole = buildBvh("hploc", set.input(), withRadius(kGroup - 1));
  EXPECT_TRUE(testing::identical(buildBvh("hploc", set.input(), withRadius(kMaxPlocRadius)), whole));
  EXPECT_FALSE(testing::identical(buildBvh("hploc", set.input(), withRadius(1)), whole));
}

TEST(Hploc, SameTreeForAnyThreadCount) {
  const PrimitiveSet set = testing::randomSoup(30000, 9);
  BuildOptions one, four;
  one.threads = 1;
  four.threads = 4;
  EXPECT_TRUE(testing::identical(buildBvh("hploc", set.input(), one), buildBvh("hploc", set.input(), four)));
}

// H-PLOC's claim is PLOC's quality at a fraction of its passes: within 3% of ploc's SAH at the same
// radius on the bunny and on a random soup (measured: 0.995x on the bunny at radius 16).
TEST(Hploc, SahWithinThreePercentOfPlocs) {
  std::vector<PrimitiveSet> sets = {testing::randomSoup(20000, 4)};
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  const TriangleSoup soup = gatherTriangles(loadInput(path));
  PrimitiveSet bunny;
  bunny.name = "bunny";
  for (size_t i = 0; i < soup.size(); ++i) bunny.addTriangle(soup.v0[i], soup.v1[i], soup.v2[i]);
  sets.push_back(bunny);
  for (const PrimitiveSet& set : sets) {
    for (uint32_t radius : {4u, 16u}) {
      const double hploc = sahCost(buildBvh("hploc", set.input(), withRadius(radius)), CostModel{});
      const double ploc = sahCost(buildBvh("ploc", set.input(), withRadius(radius)), CostModel{});
      EXPECT_LE(hploc, 1.03 * ploc) << set.name << " radius " << radius;
    }
  }
}

TEST(Hploc, BadOptionsAreInvalidArguments) {
  const PrimitiveSet set = testing::randomSoup(100, 2);
  EXPECT_THROW(buildBvh("hploc", set.input(), withRadius(0)), std::invalid_argument);
  EXPECT_THROW(buildBvh("hploc", set.input(), withRadius(kMaxPlocRadius + 1)), std::invalid_argument);
  BuildOptions topDown;
  topDown.plocTopDown = 4;
  EXPECT_THROW(buildBvh("hploc", set.input(), topDown), std::invalid_argument);
}

}  // namespace
}  // namespace bvhlab
