// Morton codes with size bits (builders/morton.hpp, BuildOptions::mortonSizeBits) and lbvh with them.
// ploc with size bits: tests/test_ploc.cpp (its reference implementation builds the extended codes too).
#include <algorithm>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/morton.hpp"
#include "builders/test_inputs.hpp"
#include "builder_test_util.hpp"
#include "datasets/random_draws.hpp"

namespace bvhlab {
namespace {

using detail::MortonEncoder;
using testing::PrimitiveSet;

// The plain code, written out bit by bit: x, y, z from the top, 21 bits each.
uint64_t plainCode(uint32_t x, uint32_t y, uint32_t z) {
  uint64_t code = 0;
  for (int b = 20; b >= 0; --b) code = code << 3 | uint64_t((x >> b) & 1) << 2 | ((y >> b) & 1) << 1 | ((z >> b) & 1);
  return code;
}

Aabb cube(const glm::vec3& centre, float half) { return {centre - glm::vec3(half), centre + glm::vec3(half)}; }

// Points of one size on the 2^21 grid: centroid bounds [0, 2^21] on every axis make the scale exactly 1,
// so a centroid at integer coordinates below 2^21 lands in that cell (2^21 itself is clamped to the top).
PrimitiveSet gridPoints(const std::vector<glm::uvec3>& cells, float half = 0.25f) {
  PrimitiveSet set;
  const float top = float(1 << 21);
  for (const glm::vec3 c : {glm::vec3(0.0f), glm::vec3(top)}) set.addBox(cube(c, half), c);  // the bounds
  for (const glm::uvec3& cell : cells) set.addBox(cube(glm::vec3(cell), half), glm::vec3(cell));
  return set;
}

TEST(MortonCodes, NoSizeBitsAreThePlainCodes) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<uint32_t> coordinate(0, (1u << 21) - 1);
  std::vector<glm::uvec3> cells(2000);
  for (glm::uvec3& c : cells) c = {coordinate(rng), coordinate(rng), coordinate(rng)};
  const PrimitiveSet set = gridPoints(cells);
  const MortonEncoder encoder(set.input(), 0, MortonGrid::Cube);
  for (size_t i = 0; i < cells.size(); ++i)
    ASSERT_EQ(encoder.code(uint32_t(i + 2)), plainCode(cells[i].x, cells[i].y, cells[i].z)) << i;
}

TEST(MortonCodes, CubeGridGivesEveryAxisTheCellsOfTheLongestExtent) {
  // Centroid bounds [0, 2^21] x [0, 2^18] x [0, 2^20]: the cube grid's cell is 1 on every axis, the
  // per-axis grid's is 1, 1/8 and 1/2 (powers of two, so both codes are exact).
  const float top = float(1 << 21);
  const glm::vec3 corner(top, top / 8.0f, top / 2.0f);
  std::mt19937 rng(6);
  std::uniform_int_distribution<uint32_t> coordinate(0, (1u << 21) - 1);
  PrimitiveSet set;
  for (const glm::vec3 c : {glm::vec3(0.0f), corner}) set.addBox(cube(c, 0.25f), c);
  std::vector<glm::uvec3> cells(2000);
  for (glm::uvec3& c : cells) {
    c = {coordinate(rng), coordinate(rng) / 8u, coordinate(rng) / 2u};
    set.addBox(cube(glm::vec3(c), 0.25f), glm::vec3(c));
  }
  const MortonEncoder cubeGrid(set.input(), 0, MortonGrid::Cube), axesGrid(set.input(), 0, MortonGrid::Axes);
  for (size_t i = 0; i < cells.size(); ++i) {
    const glm::uvec3 c = cells[i];
    ASSERT_EQ(cubeGrid.code(uint32_t(i + 2)), plainCode(c.x, c.y, c.z)) << i;
    ASSERT_EQ(axesGrid.code(uint32_t(i + 2)), plainCode(c.x, c.y * 8u, c.z * 2u)) << i;
  }
  // The corner: the longest axis's top cell is clamped on both grids, the short axes reach it only on Axes.
  const uint32_t last = (1u << 21) - 1;
  EXPECT_EQ(cubeGrid.code(1), plainCode(last, 1u << 18, 1u << 20));
  EXPECT_EQ(axesGrid.code(1), plainCode(last, last, last));
}

TEST(MortonCodes, TheGridIsAnOptionOfLbvhAndPlocOnly) {
  PrimitiveSet flat;  // a long, flat strip of triangles: the two grids order it differently
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 4000; ++i) {
    const glm::vec3 p = glm::vec3(100.0f, 0.5f, 10.0f) * draw3<glm::vec3>(u, rng);
    flat.addTriangle(p, p + glm::vec3(0.3f, 0.01f, 0.0f), p + glm::vec3(0.0f, 0.02f, 0.3f));
  }
  BuildOptions axes;
  axes.mortonGrid = MortonGrid::Axes;
  for (const char* builder : {"lbvh", "ploc"}) {
    EXPECT_FALSE(testing::identical(buildBvh(builder, flat.input(), BuildOptions{}), buildBvh(builder, flat.input(), axes)))
        << builder;  // the option is not ignored
    EXPECT_TRUE(reviewBuildOptions(builder, axes).warnings.empty()) << builder;
  }
  const OptionReview binned = reviewBuildOptions("sah-binned", axes);
  ASSERT_EQ(binned.warnings.size(), 1u);
  EXPECT_NE(binned.warnings[0].find("ignores --morton-grid"), std::string::npos) << binned.warnings[0];
  EXPECT_EQ(parseMortonGrid("cube"), MortonGrid::Cube);
  EXPECT_EQ(parseMortonGrid("axes"), MortonGrid::Axes);
  EXPECT_EQ(mortonGridName(MortonGrid::Axes), "axes");
  EXPECT_THROW(parseMortonGrid("square"), std::invalid_argument);
}

TEST(MortonCodes, SizeBitsGoAfterEverySixPositionBits) {
  const uint64_t all = (uint64_t(1) << 63) - 1;
  for (uint32_t s = 1; s <= kMaxMortonSizeBits; ++s) {
    uint64_t sizeMask = 0;  // size bit k (from the top) at code bit 62 - (7k + 6)
    for (uint32_t k = 0; k < s; ++k) sizeMask |= uint64_t(1) << (62 - (7 * k + 6));
    const uint32_t classes = (1u << s) - 1;
    EXPECT_EQ(detail::insertSizeBits(all, 0, s), all & ~sizeMask) << s;
    EXPECT_EQ(detail::insertSizeBits(0, classes, s), sizeMask) << s;
    // The lowest s position bits are the ones dropped: the top position bit stays on top.
    EXPECT_EQ(detail::insertSizeBits(uint64_t(1) << 62, 0, s), uint64_t(1) << 62) << s;
    EXPECT_EQ(detail::insertSizeBits((uint64_t(1) << s) - 1, 0, s), 0u) << s;
    // The most significant size bit comes first.
    EXPECT_EQ(detail::insertSizeBits(0, 1u << (s - 1), s), uint64_t(1) << 56) << s;
  }
  EXPECT_EQ(detail::insertSizeBits(0x123456789abcdefULL, 0, 0), 0x123456789abcdefULL);
}

TEST(MortonCodes, MonotoneInPositionForEqualSizes) {
  // Equal boxes: the size class is the same, so the codes must order as the plain codes with their
  // lowest s bits dropped, along every axis and for random pairs.
  std::mt19937 rng(9);
  std::uniform_int_distribution<uint32_t> coordinate(0, (1u << 21) - 1);
  std::vector<glm::uvec3> cells;
  for (int a = 0; a < 3; ++a) {  // a walk along each axis from a random start, the other axes fixed
    glm::uvec3 c = draw3<glm::uvec3>(coordinate, rng);
    for (uint32_t step = 0, start = coordinate(rng) / 2; step < 300; ++step) {
      c[a] = start + step * 997;
      cells.push_back(c);
    }
  }
  for (int k = 0; k < 1000; ++k) cells.push_back({coordinate(rng), coordinate(rng), coordinate(rng)});
  PrimitiveSet set = gridPoints(cells);
  set.addBox(cube(glm::vec3(5.0f), 100.0f), glm::vec3(5.0f));  // a larger box: the classes span a range
  for (uint32_t s : {1u, 3u, 6u, 9u}) {
    SCOPED_TRACE("size bits " + std::to_string(s));
    const MortonEncoder encoder(set.input(), s, MortonGrid::Cube);
    auto code = [&](size_t i) { return encoder.code(uint32_t(i + 2)); };
    auto plain = [&](size_t i) { return plainCode(cells[i].x, cells[i].y, cells[i].z) >> s; };
    for (size_t i = 1; i < 900; ++i) {
      if (i % 300 == 0) continue;  // a new walk
      ASSERT_LE(code(i - 1), code(i)) << i;
    }
    for (size_t i = 0; i + 1 < cells.size(); ++i) ASSERT_EQ(code(i) < code(i + 1), plain(i) < plain(i + 1)) << i;
  }
}

TEST(MortonCodes, SizeBitsSeparateABigAndASmallPrimitiveAtOneCentroid) {
  PrimitiveSet set = testing::randomSoup(1000, 4);
  const glm::vec3 centre(0.5f);
  set.addBox(cube(centre, 0.4f), centre);      // larger than any triangle of the soup
  set.addBox(cube(centre, 1e-6f), centre);     // smaller than any
  const uint32_t big = uint32_t(set.size() - 2), small = big + 1;
  EXPECT_EQ(MortonEncoder(set.input(), 0, MortonGrid::Cube).code(big), MortonEncoder(set.input(), 0, MortonGrid::Cube).code(small));
  for (uint32_t s = 1; s <= kMaxMortonSizeBits; ++s) {
    const MortonEncoder encoder(set.input(), s, MortonGrid::Cube);
    EXPECT_EQ(encoder.sizeClass(set.boxes[small]), 0u) << s;
    EXPECT_GT(encoder.code(big), encoder.code(small)) << s;
    // The big box's diagonal is over a quarter of the scene's: the top size bit (bit 56, below the 6
    // position bits the two share) alone tells them apart.
    EXPECT_GE(encoder.sizeClass(set.boxes[big]), 1u << (s - 1)) << s;
    EXPECT_GE(encoder.code(big) ^ encoder.code(small), uint64_t(1) << 56) << s;
  }
}

TEST(MortonCodes, SizeClassesAreEqualStepsOfTheSquareRootOfTheRelativeDiagonal) {
  // Flat boxes along x in a scene of diagonal 16: with 2 size bits, class c starts at a diagonal of
  // 16 (c / 4)^2 = 1, 4, 9 (exact in floating point); the scene's own diagonal is clamped to class 3.
  PrimitiveSet set;
  const struct {
    float diagonal;
    uint32_t sizeClass;
  } cases[] = {{16.0f, 3}, {0.0f, 0}, {0.9375f, 0}, {1.0f, 1}, {3.9f, 1}, {4.0f, 2}, {8.9f, 2}, {9.0f, 3}, {15.0f, 3}};
  for (const auto& c : cases) set.addBox({glm::vec3(0.0f), glm::vec3(c.diagonal, 0.0f, 0.0f)}, glm::vec3(0.0f));
  const MortonEncoder encoder(set.input(), 2, MortonGrid::Cube);
  for (size_t k = 0; k < set.size(); ++k) EXPECT_EQ(encoder.sizeClass(set.boxes[k]), cases[k].sizeClass) << k;
  EXPECT_EQ(MortonEncoder(set.input(), 0, MortonGrid::Cube).sizeClass(set.boxes[0]), 0u);  // no size bits: one class
  // A scene of one point: every box in class 0.
  PrimitiveSet point;
  for (int k = 0; k < 4; ++k) point.addBox({glm::vec3(1.0f), glm::vec3(1.0f)}, glm::vec3(1.0f));
  EXPECT_EQ(MortonEncoder(point.input(), 9, MortonGrid::Cube).sizeClass(point.boxes[0]), 0u);
}

TEST(MortonCodes, BadSizeBitsIsAnInvalidArgument) {
  const PrimitiveSet set = testing::randomSoup(100);
  BuildOptions options;
  options.mortonSizeBits = kMaxMortonSizeBits + 1;
  for (const std::string builder : {"ploc", "lbvh"}) {
    try {
      buildBvh(builder, set.input(), options);
      FAIL() << builder << " accepted mortonSizeBits 10";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("mortonSizeBits 10"), std::string::npos) << what;
      EXPECT_NE(what.find("0..9"), std::string::npos) << what;
    }
  }
  EXPECT_THROW(reviewBuildOptions("ploc", options), std::invalid_argument);
  options.mortonSizeBits = kMaxMortonSizeBits;
  EXPECT_NO_THROW(buildBvh("lbvh", set.input(), options));
  EXPECT_TRUE(reviewBuildOptions("lbvh", options).warnings.empty());
  EXPECT_EQ(reviewBuildOptions("sah-binned", options).warnings.size(), 1u);  // ignores it, says so
}

TEST(MortonCodes, LbvhWithSizeBitsIsOneTreeForAnyThreadCountAndChangesTheTree) {
  const PrimitiveSet set = testing::randomSoup(30000, 7);
  BuildOptions options;
  options.mortonSizeBits = 6;
  options.threads = 1;
  const Bvh one = buildBvh("lbvh", set.input(), options);
  EXPECT_EQ(one.primIndices.size(), set.size());
  std::vector<uint32_t> sorted = one.primIndices;
  std::sort(sorted.begin(), sorted.end());
  for (uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  for (uint32_t threads : {2u, 8u}) {
    options.threads = threads;
    EXPECT_TRUE(testing::identical(one, buildBvh("lbvh", set.input(), options))) << threads << " threads";
  }
  options.mortonSizeBits = 0;
  EXPECT_FALSE(testing::identical(one, buildBvh("lbvh", set.input(), options)));  // the option is not ignored
}

}  // namespace
}  // namespace bvhlab
