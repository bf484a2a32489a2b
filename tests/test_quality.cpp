// Clock-independent tree-quality measures: End-Point Overlap (builders/epo.hpp), checked against
// closed forms and a brute-force definition for every builder, and the packed-tree hash
// (layout/tree_hash.hpp).
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/epo.hpp"
#include "datasets/procedural.hpp"
#include "datasets/random_draws.hpp"
#include "layout/layout.hpp"
#include "layout/tree_hash.hpp"

namespace bvhlab {
namespace {

// ---- triangles with what a builder sees ---------------------------------------------------------

struct Triangles {
  std::vector<glm::vec3> v0, v1, v2;
  std::vector<Aabb> boxes;
  std::vector<glm::vec3> centroids;

  void add(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    v0.push_back(a), v1.push_back(b), v2.push_back(c);
    Aabb box;
    box.grow(a), box.grow(b), box.grow(c);
    boxes.push_back(box);
    centroids.push_back((a + b + c) / 3.0f);
  }
  size_t size() const { return v0.size(); }
  // With the vertices: a builder that splits primitives (sbvh) clips the triangles themselves.
  BuildInput input() const { return {boxes, centroids, v0, v1, v2}; }
  double epo(const Bvh& bvh, const CostModel& cost = {}, unsigned threads = 0) const {
    return endPointOverlap(bvh, v0, v1, v2, cost, threads);
  }
};

// Random orientation, centres in the unit cube, sizes log-uniform over [minSize, maxSize]: the boxes
// overlap one another (and the big triangles reach across many nodes).
Triangles randomTriangles(size_t count, uint32_t seed, float minSize = 0.01f, float maxSize = 0.3f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
  Triangles t;
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c = draw3<glm::vec3>(unit, rng);
    const float size = minSize * std::pow(maxSize / minSize, unit(rng));
    auto corner = [&] { return c + size * draw3<glm::vec3>(signedUnit, rng); };
    const glm::vec3 a = corner(), b = corner(), d = corner();
    t.add(a, b, d);
  }
  return t;
}

Aabb boxOf(std::initializer_list<glm::vec3> points) {
  Aabb box;
  for (const glm::vec3& p : points) box.grow(p);
  return box;
}

std::vector<std::string> builderNames() {
  std::vector<std::string> names;
  for (const BuilderInfo& info : builders()) names.push_back(info.name);
  return names;
}

std::string testName(std::string name) {
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

// ---- the definition, brute force ----------------------------------------------------------------

// EPO straight from the paper's sum: for every node (recursively from the root), every triangle that
// is not in its subtree, clipped to its box; weighted by Ct (inner) or Ci * count (leaf); over the
// total area. O(nodes x triangles), no pruning, no shortcuts: what the fast query must reproduce.
double bruteForceEpo(const Bvh& bvh, const Triangles& tris, const CostModel& cost) {
  double total = 0.0;
  for (size_t t = 0; t < tris.size(); ++t) total += triangleArea(tris.v0[t], tris.v1[t], tris.v2[t]);
  double sum = 0.0;
  std::function<std::vector<uint32_t>(uint32_t)> visit = [&](uint32_t index) {
    const BvhNode& node = bvh.nodes[index];
    std::vector<uint32_t> subtree;
    if (node.isLeaf()) {
      subtree.assign(bvh.primIndices.begin() + node.first, bvh.primIndices.begin() + node.first + node.count);
    } else {
      subtree = visit(node.left);
      const std::vector<uint32_t> right = visit(node.right);
      subtree.insert(subtree.end(), right.begin(), right.end());
    }
    std::vector<bool> inside(tris.size(), false);
    for (uint32_t t : subtree) inside[t] = true;
    double area = 0.0;
    for (size_t t = 0; t < tris.size(); ++t)
      if (!inside[t]) area += clippedTriangleArea(tris.v0[t], tris.v1[t], tris.v2[t], node.bounds);
    sum += (node.isLeaf() ? double(cost.intersectionCost) * node.count : double(cost.traversalCost)) * area;
    return subtree;
  };
  visit(0);
  return total > 0.0 ? sum / total : 0.0;
}

// ---- clipping -----------------------------------------------------------------------------------

// The right triangle (0,0,0), (2,0,0), (0,2,0): area 2, hypotenuse x + y = 2, in the plane z = 0.
const glm::dvec3 kA(0, 0, 0), kB(2, 0, 0), kC(0, 2, 0);

TEST(Clip, TriangleFullyInsideKeepsItsArea) {
  EXPECT_DOUBLE_EQ(triangleArea(kA, kB, kC), 2.0);
  EXPECT_DOUBLE_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{-1, -1, -1}, {3, 3, 1}})), 2.0);
  // The triangle's own box is flat in z: the box is closed, so the triangle lies inside it.
  EXPECT_DOUBLE_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{0, 0, 0}, {2, 2, 0}})), 2.0);
}

TEST(Clip, TriangleFullyOutsideHasNoArea) {
  EXPECT_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{5, 5, 5}, {6, 6, 6}})), 0.0);
  // Inside the triangle's box, but above the hypotenuse: the box [1.5,2]^2 lies where x + y >= 3.
  EXPECT_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{1.5f, 1.5f, -1}, {2, 2, 1}})), 0.0);
  // Touching at one vertex or along one edge is a set of zero area.
  EXPECT_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{2, -1, -1}, {3, 1, 1}})), 0.0);
  EXPECT_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{-1, -1, -1}, {3, 0, 1}})), 0.0);
  // A box above the plane z = 0.
  EXPECT_EQ(clippedTriangleArea(kA, kB, kC, boxOf({{-1, -1, 0.5f}, {3, 3, 1}})), 0.0);
  EXPECT_EQ(clippedTriangleArea(kA, kB, kC, Aabb{}), 0.0);  // the empty box
}

TEST(Clip, StraddlingTriangleKeepsTheClippedPart) {
  // x <= 1: the strip 0 <= x <= 1 under y = 2 - x, area = integral_0^1 (2 - x) dx = 1.5.
  EXPECT_NEAR(clippedTriangleArea(kA, kB, kC, boxOf({{-1, -1, -1}, {1, 3, 1}})), 1.5, 1e-15);
  // The square [0.5,1.5]^2 less its corner above x + y = 2 (a right triangle of legs 1): 1 - 0.5.
  EXPECT_NEAR(clippedTriangleArea(kA, kB, kC, boxOf({{0.5f, 0.5f, -1}, {1.5f, 1.5f, 1}})), 0.5, 1e-15);
  // The unit square lies wholly under the hypotenuse: 1.
  EXPECT_NEAR(clippedTriangleArea(kA, kB, kC, boxOf({{0, 0, -1}, {1, 1, 1}})), 1.0, 1e-15);
  // Tilted out of every axis plane: (0,0,0), (2,0,2), (0,2,0) lies in z = x, its area is sqrt(2) times
  // its xy-projection's. x <= 1 keeps projected area 1.5 (as above): 1.5 sqrt(2).
  const glm::dvec3 b(2, 0, 2);
  EXPECT_NEAR(triangleArea(kA, b, kC), 2.0 * std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(clippedTriangleArea(kA, b, kC, boxOf({{-1, -1, -1}, {1, 3, 3}})), 1.5 * std::sqrt(2.0), 1e-14);
  // ... and z <= 1 is the same cut (z = x on the triangle).
  EXPECT_NEAR(clippedTriangleArea(kA, b, kC, boxOf({{-1, -1, -1}, {3, 3, 1}})), 1.5 * std::sqrt(2.0), 1e-14);
}

// Cutting a box in two along any axis plane cuts the triangle's area in two: the pieces add up to the
// whole, and a box around the triangle holds all of it. Random triangles and boxes, so every clip
// path (vertices in and out on each of the six planes) is taken.
TEST(Clip, PiecesOfASplitBoxAddUp) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), frac(0.0f, 1.0f);
  int straddling = 0;
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec3 a = draw3<glm::dvec3>(u, rng), b = draw3<glm::dvec3>(u, rng), c = draw3<glm::dvec3>(u, rng);
    Aabb box = boxOf({{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}});
    const int axis = i % 3;
    const float cut = box.min[axis] + frac(rng) * (box.max[axis] - box.min[axis]);
    Aabb low = box, high = box;
    low.max[axis] = cut, high.min[axis] = cut;
    const double whole = clippedTriangleArea(a, b, c, box);
    const double parts = clippedTriangleArea(a, b, c, low) + clippedTriangleArea(a, b, c, high);
    EXPECT_NEAR(parts, whole, 1e-12) << "triangle " << i;
    EXPECT_GE(whole, 0.0);
    EXPECT_LE(whole, triangleArea(a, b, c) * (1.0 + 1e-12));
    if (whole > 0.0 && whole < triangleArea(a, b, c) * 0.99) ++straddling;
    EXPECT_NEAR(clippedTriangleArea(a, b, c, boxOf({{-1, -1, -1}, {1, 1, 1}})), triangleArea(a, b, c), 1e-15);
  }
  EXPECT_GT(straddling, 100);  // the property was exercised on real cuts, not only on all-or-nothing
}

// ---- EPO, closed forms --------------------------------------------------------------------------

// A tree of a root and two leaves, or deeper, made by hand so that every box is known.
Bvh leafPair(const Triangles& t, uint32_t leftTriangles) {
  Bvh bvh;
  bvh.nodes.resize(3);
  bvh.nodes[0].left = 1, bvh.nodes[0].right = 2;
  bvh.nodes[1].first = 0, bvh.nodes[1].count = leftTriangles;
  bvh.nodes[2].first = leftTriangles, bvh.nodes[2].count = uint32_t(t.size()) - leftTriangles;
  for (uint32_t i = 0; i < t.size(); ++i) bvh.primIndices.push_back(i);
  for (int n : {1, 2})
    for (uint32_t k = bvh.nodes[n].first; k < bvh.nodes[n].first + bvh.nodes[n].count; ++k)
      bvh.nodes[n].bounds.grow(t.boxes[k]);
  bvh.nodes[0].bounds = bvh.nodes[1].bounds;
  bvh.nodes[0].bounds.grow(bvh.nodes[2].bounds);
  return bvh;
}

TEST(Epo, TwoSeparatedTrianglesHaveNoOverlap) {
  Triangles t;
  t.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  t.add({5, 5, 5}, {6, 5, 5}, {5, 6, 5});
  EXPECT_EQ(t.epo(leafPair(t, 1)), 0.0);
  // The same from every builder (each makes a root and two leaves); a measure that counted a node's
  // own triangles would give each leaf its triangle's area.
  BuildOptions options;
  options.maxLeafSize = 1;
  for (const std::string& name : builderNames()) {
    const Bvh bvh = buildBvh(name, t.input(), options);
    ASSERT_EQ(bvh.nodes.size(), 3u) << name;
    EXPECT_EQ(t.epo(bvh), 0.0) << name;
  }
}

// T0 = (0,0,0), (4,0,0), (0,4,0): area 8, in z = 0, under the line x + y = 4; its leaf's box is the
// flat [0,4]^2 x [0,0].
// T1 = (1,1,-1), (3,1,1), (1,3,1): its box [1,3]^2 x [-1,1]; edges (2,0,2) and (0,2,2), cross product
// (-4,-4,4), area 2 sqrt(3); it lies in z = x + y - 3, so it meets z = 0 only along a segment.
//
// Root -> leaf A {T0}, leaf B {T1}. The root holds everything (0). Leaf A's flat box meets T1 in a
// segment (0). Leaf B's box holds the part of T0 in the square [1,3]^2 under x + y = 4: the square
// (4) less the right triangle (1,3), (3,1), (3,3) above the line (2), so 2. Leaf B has one triangle:
// EPO = Ci * 1 * 2 / (8 + 2 sqrt(3)).
TEST(Epo, BigTriangleOverSiblingLeafIsTheClippedAreaTimesTheLeafCost) {
  Triangles t;
  t.add({0, 0, 0}, {4, 0, 0}, {0, 4, 0});
  t.add({1, 1, -1}, {3, 1, 1}, {1, 3, 1});
  const Bvh bvh = leafPair(t, 1);
  const double total = 8.0 + 2.0 * std::sqrt(3.0);
  EXPECT_NEAR(t.epo(bvh), 2.0 / total, 1e-14);
  CostModel cost;
  cost.traversalCost = 1.5f;  // no inner node but the root, which overlaps nothing: Ct has no say
  cost.intersectionCost = 2.0f;
  EXPECT_NEAR(t.epo(bvh, cost), 2.0 * 2.0 / total, 1e-14);
  EXPECT_NEAR(bruteForceEpo(bvh, t, cost), 2.0 * 2.0 / total, 1e-14);
}

// The case above, grown by an inner node: a third triangle in a leaf of its own, next to T1's leaf.
// T2 = (1.25,1.25,0), (1.75,1.25,0), (1.25,1.75,0): area 0.125, in z = 0 inside T0's footprint, box
// [1.25,1.75]^2 x [0,0] of area 0.25 in its plane, all of it under x + y = 4.
//
// Root -> leaf A {T0}, inner I -> (leaf B {T1}, leaf C {T2}); box I = box B = [1,3]^2 x [-1,1].
//   root  everything in its subtree                                             0
//   A     T1 meets z = 0 in a segment (0); T2 lies in A's flat box (0.125)       0.125  x Ci
//   I     T0 in [1,3]^2 (2, as above)                                           2      x Ct
//   B     T0 (2) + T2, wholly inside box B (0.125)                              2.125  x Ci
//   C     T0 over the square [1.25,1.75]^2 (0.25); T1 crosses z = 0 in a segment 0.25   x Ci
// EPO = (2.5 Ci + 2 Ct) / (8 + 2 sqrt(3) + 0.125); with Ct = 1.5, Ci = 2: 8 / (8.125 + 2 sqrt(3)).
TEST(Epo, InnerAndLeafNodesWeighTheirCosts) {
  Triangles t;
  t.add({0, 0, 0}, {4, 0, 0}, {0, 4, 0});
  t.add({1, 1, -1}, {3, 1, 1}, {1, 3, 1});
  t.add({1.25f, 1.25f, 0}, {1.75f, 1.25f, 0}, {1.25f, 1.75f, 0});
  Bvh bvh;
  bvh.nodes.resize(5);
  bvh.primIndices = {0, 1, 2};
  bvh.nodes[0].left = 1, bvh.nodes[0].right = 2;        // root
  bvh.nodes[1].first = 0, bvh.nodes[1].count = 1;       // A
  bvh.nodes[2].left = 3, bvh.nodes[2].right = 4;        // I
  bvh.nodes[3].first = 1, bvh.nodes[3].count = 1;       // B
  bvh.nodes[4].first = 2, bvh.nodes[4].count = 1;       // C
  bvh.nodes[1].bounds = t.boxes[0];
  bvh.nodes[3].bounds = t.boxes[1];
  bvh.nodes[4].bounds = t.boxes[2];
  bvh.nodes[2].bounds = t.boxes[1];
  bvh.nodes[2].bounds.grow(t.boxes[2]);
  bvh.nodes[0].bounds = bvh.nodes[1].bounds;
  bvh.nodes[0].bounds.grow(bvh.nodes[2].bounds);
  const double total = 8.125 + 2.0 * std::sqrt(3.0);
  CostModel cost;
  cost.traversalCost = 1.5f;
  cost.intersectionCost = 2.0f;
  EXPECT_NEAR(t.epo(bvh, cost), 8.0 / total, 1e-14);
  EXPECT_NEAR(t.epo(bvh), 4.5 / total, 1e-14);  // Ct = Ci = 1
  EXPECT_NEAR(bruteForceEpo(bvh, t, cost), 8.0 / total, 1e-14);
}

// A triangle referenced by two leaves, as a builder that splits primitives (sbvh) makes them. Q(n)
// is the set of triangles referenced in n's subtree, and a triangle counts at most once per node.
// T0 = (0,0,0), (4,0,0), (0,4,0): area 8, in z = 0, split at x = 2 into leaves A and B.
// T1 = (3,0,1), (3.5,0,1), (3,0.5,1): area 0.125, in z = 1, in leaf B.
// T2 = (1,1,0), (1.5,1,0), (1,1.5,0): area 0.125, in z = 0, in leaf C.
// root -> (I -> (A {T0}: [0,2] x [0,4] x [0,0], B {T0, T1}: [2,4] x [0,2] x [0,1]), C {T2}: T2's box)
//   root  everything                                                        0
//   I     Q = {T0, T1}: T2, inside I's box (0.125)                          0.125 x Ct
//   A     Q = {T0} (although T0 is also in B): T2 inside A's flat box        0.125 x Ci
//         (0.125), T1 off its plane (0)
//   B     Q = {T0, T1}: T2 is at x <= 1.5 (0)                               0
//   C     Q = {T2}: T0 over C's square [1,1.5]^2, ONCE although two leaves   0.25  x Ci
//         reference it (0.25); T1 off the plane (0)
// A(S) = 8 + 0.125 + 0.125 (T0 once). Counting T0 per reference would add T0's part in A's box
// (x <= 2: 6) to leaf A's term and double C's.
TEST(Epo, DuplicateReferencesCountATriangleOnce) {
  Triangles t;
  t.add({0, 0, 0}, {4, 0, 0}, {0, 4, 0});
  t.add({3, 0, 1}, {3.5f, 0, 1}, {3, 0.5f, 1});
  t.add({1, 1, 0}, {1.5f, 1, 0}, {1, 1.5f, 0});
  Bvh bvh;
  bvh.nodes.resize(5);
  bvh.primIndices = {0, 0, 1, 2};
  bvh.nodes[0].left = 1, bvh.nodes[0].right = 4;   // root
  bvh.nodes[1].left = 2, bvh.nodes[1].right = 3;   // I
  bvh.nodes[2].first = 0, bvh.nodes[2].count = 1;  // A
  bvh.nodes[3].first = 1, bvh.nodes[3].count = 2;  // B
  bvh.nodes[4].first = 3, bvh.nodes[4].count = 1;  // C
  bvh.nodes[2].bounds = {{0, 0, 0}, {2, 4, 0}};
  bvh.nodes[3].bounds = {{2, 0, 0}, {4, 2, 1}};
  bvh.nodes[4].bounds = t.boxes[2];
  bvh.nodes[1].bounds = bvh.nodes[2].bounds;
  bvh.nodes[1].bounds.grow(bvh.nodes[3].bounds);
  bvh.nodes[0].bounds = bvh.nodes[1].bounds;
  bvh.nodes[0].bounds.grow(bvh.nodes[4].bounds);
  EXPECT_NEAR(t.epo(bvh), 0.5 / 8.25, 1e-14);
  CostModel cost;
  cost.traversalCost = 1.5f;
  cost.intersectionCost = 2.0f;
  EXPECT_NEAR(t.epo(bvh, cost), (0.125 * 1.5 + 0.375 * 2.0) / 8.25, 1e-14);
  EXPECT_NEAR(bruteForceEpo(bvh, t, cost), (0.125 * 1.5 + 0.375 * 2.0) / 8.25, 1e-14);
  for (unsigned threads : {1u, 2u, 0u}) EXPECT_EQ(t.epo(bvh, cost, threads), t.epo(bvh, cost, 1)) << threads;

  // T0 in both leaves of one node: that node's term has no T0 in it.
  Triangles two;
  two.add({0, 0, 0}, {4, 0, 0}, {0, 4, 0});
  two.add({1, 1, 0}, {1.5f, 1, 0}, {1, 1.5f, 0});
  Bvh split;
  split.nodes.resize(3);
  split.primIndices = {0, 1, 0};
  split.nodes[0].left = 1, split.nodes[0].right = 2;
  split.nodes[1].first = 0, split.nodes[1].count = 2;  // {T0, T2'}: [0,2] x [0,4] x [0,0]
  split.nodes[2].first = 2, split.nodes[2].count = 1;  // {T0}: [2,4] x [0,2] x [0,0]
  split.nodes[1].bounds = {{0, 0, 0}, {2, 4, 0}};
  split.nodes[2].bounds = {{2, 0, 0}, {4, 2, 0}};
  split.nodes[0].bounds = {{0, 0, 0}, {4, 4, 0}};
  // Leaf 1 holds both triangles; leaf 2's box meets T2' (x <= 1.5) nowhere: EPO 0.
  EXPECT_EQ(two.epo(split), 0.0);
  EXPECT_EQ(bruteForceEpo(split, two, {}), 0.0);
}

// Every builder's tree (sbvh: with duplicate references) against the definition, on random
// triangles: exercises the query's shortcuts (subtrees wholly inside a box) with shared triangles.
TEST(Epo, SbvhTreesMatchBruteForce) {
  for (uint32_t seed : {4u, 5u}) {
    const Triangles t = randomTriangles(400, seed, 0.05f, 0.6f);  // big triangles: many split references
    BuildOptions options;
    options.maxLeafSize = 2;
    const Bvh bvh = buildBvh("sbvh", t.input(), options);
    ASSERT_GT(bvh.primIndices.size(), t.size());
    const double reference = bruteForceEpo(bvh, t, {});
    EXPECT_GT(reference, 0.0);
    EXPECT_NEAR(t.epo(bvh), reference, 1e-10 * reference);
    EXPECT_EQ(t.epo(bvh, {}, 3), t.epo(bvh, {}, 1));
  }
}

// ---- EPO against the definition, every builder ---------------------------------------------------

class EpoEveryBuilder : public ::testing::TestWithParam<std::string> {};

TEST_P(EpoEveryBuilder, MatchesBruteForce) {
  CostModel cost;
  cost.traversalCost = 1.2f;  // unequal constants, so swapping Ct and Ci would show
  cost.intersectionCost = 0.7f;
  for (uint32_t leafSize : {1u, 4u})
    for (uint32_t seed : {1u, 2u, 3u}) {
      SCOPED_TRACE("leaf size " + std::to_string(leafSize) + " seed " + std::to_string(seed));
      const Triangles t = randomTriangles(300, seed);
      BuildOptions options;
      options.maxLeafSize = leafSize;
      options.cost = cost;
      const Bvh bvh = buildBvh(GetParam(), t.input(), options);
      const double reference = bruteForceEpo(bvh, t, cost);
      EXPECT_GT(reference, 0.0);  // overlapping input: a zero would not test anything
      EXPECT_NEAR(t.epo(bvh, cost), reference, 1e-10 * reference);
    }
  // Flat boxes: every triangle in y = 0, so every node box has zero height (the closed-box case).
  Triangles flat;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), edge(-0.05f, 0.05f);
  for (int i = 0; i < 200; ++i) {
    const glm::vec3 c = drawXZ<glm::vec3>(unit, rng);  // fixed order (random_draws.hpp): the last corner first
    const glm::vec3 v2 = c + drawXZ<glm::vec3>(edge, rng), v1 = c + drawXZ<glm::vec3>(edge, rng);
    flat.add(c + drawXZ<glm::vec3>(edge, rng), v1, v2);
  }
  const Bvh bvh = buildBvh(GetParam(), flat.input(), BuildOptions{});
  const double reference = bruteForceEpo(bvh, flat, {});
  EXPECT_GT(reference, 0.0);
  EXPECT_NEAR(flat.epo(bvh), reference, 1e-10 * reference);
}

INSTANTIATE_TEST_SUITE_P(Builders, EpoEveryBuilder, ::testing::ValuesIn(builderNames()),
                         [](const auto& info) { return testName(info.param); });

// ---- EPO, determinism and degenerate input ------------------------------------------------------

TEST(Epo, SameValueForAnyThreadCount) {
  const Triangles t = randomTriangles(5000, 9, 0.002f, 0.1f);  // thousands of nodes: dozens of chunks
  const Bvh bvh = buildBvh("sah-binned", t.input(), BuildOptions{});
  const double one = t.epo(bvh, {}, 1);
  EXPECT_GT(one, 0.0);
  for (unsigned threads : {2u, 3u, 8u, 0u}) EXPECT_EQ(t.epo(bvh, {}, threads), one) << threads << " threads";
}

TEST(Epo, DegenerateInputsGiveFiniteValues) {
  // One triangle: one leaf, whose subtree is the whole scene.
  Triangles one;
  one.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  EXPECT_EQ(one.epo(buildBvh("sah-binned", one.input(), BuildOptions{})), 0.0);

  // Only zero-area triangles (repeated points, collinear points): no surface, EPO 0 by definition.
  // Coordinates in quarters, so the collinear points are exactly collinear in float.
  Triangles degenerate;
  for (int i = 0; i < 20; ++i) {
    const float x = 0.25f * float(i);
    degenerate.add({x, 0, 0}, {x, 0, 0}, {x, 0, 0});
    degenerate.add({x, 0, 0}, {x + 0.5f, 0.5f, 0.5f}, {x + 1.0f, 1.0f, 1.0f});
  }
  BuildOptions leafOne;
  leafOne.maxLeafSize = 1;
  const Bvh flatTree = buildBvh("median", degenerate.input(), leafOne);
  EXPECT_EQ(degenerate.epo(flatTree), 0.0);
  EXPECT_EQ(bruteForceEpo(flatTree, degenerate, {}), 0.0);

  // Zero-area triangles among real ones contribute nothing, and the value stays the definition's.
  Triangles mixed = randomTriangles(200, 4);
  for (int i = 0; i < 50; ++i) {
    const glm::vec3 p = mixed.v0[size_t(i)];
    mixed.add(p, p, p);
    mixed.add(p, mixed.v1[size_t(i)], 2.0f * mixed.v1[size_t(i)] - p);  // collinear
  }
  const Bvh mixedTree = buildBvh("lbvh", mixed.input(), BuildOptions{});
  const double value = mixed.epo(mixedTree);
  EXPECT_TRUE(std::isfinite(value));
  EXPECT_NEAR(value, bruteForceEpo(mixedTree, mixed, {}), 1e-10 * value);
}

TEST(Epo, MalformedInputIsAClearError) {
  Triangles t;
  t.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  t.add({5, 5, 5}, {6, 5, 5}, {5, 6, 5});
  const Bvh bvh = leafPair(t, 1);
  const std::vector<glm::vec3> shorter(t.v1.begin(), t.v1.begin() + 1);
  EXPECT_THROW(endPointOverlap(bvh, t.v0, shorter, t.v2, {}), std::invalid_argument);
  EXPECT_THROW(endPointOverlap(Bvh{}, t.v0, t.v1, t.v2, {}), std::invalid_argument);

  Bvh outOfRange = bvh;
  outOfRange.primIndices[1] = 7;
  EXPECT_THROW(t.epo(outOfRange), std::invalid_argument);
  Bvh twice = bvh;
  twice.primIndices[1] = 0;  // triangle 0 twice, triangle 1 nowhere
  EXPECT_THROW(t.epo(twice), std::invalid_argument);
  Bvh cycle = bvh;
  cycle.nodes[0].right = 0;
  EXPECT_THROW(t.epo(cycle), std::invalid_argument);

  Triangles nan = t;
  nan.v2[1].y = std::nanf("");
  EXPECT_THROW(nan.epo(bvh), std::invalid_argument);
}

// ---- packed tree hash ---------------------------------------------------------------------------

struct Packed {
  TriangleSoup soup;
  Bvh bvh;
  PackedBvh packed;
};

Scene sceneOf(Mesh mesh) {
  Scene scene;
  scene.materials.resize(1);
  scene.meshes.push_back(std::move(mesh));
  return scene;
}

Packed buildAndPack(const Scene& scene, const std::string& builder, uint32_t leafSize = 4) {
  Packed p;
  p.soup = gatherTriangles(scene);
  const std::vector<Aabb> boxes = triangleBoxes(p.soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(p.soup);
  BuildOptions options;
  options.maxLeafSize = leafSize;
  p.bvh = buildBvh(builder, BuildInput{boxes, centroids}, options);
  p.packed = packBvh(p.bvh, p.soup);
  return p;
}

// Known answers, computed outside this code (Python): FNV-1a 64 over
// u64le(1) u32le(1,2,3,4) u64le(0) u64le(1) u32le(0xdeadbeef,0,0,7), and over three u64le(0).
TEST(TreeHash, KnownAnswers) {
  PackedBvh p;
  EXPECT_EQ(packedTreeHash(p), "81d23fd7003c2305");
  p.nodes = {glm::uvec4(1, 2, 3, 4)};
  p.attributes = {glm::uvec4(0xdeadbeefu, 0, 0, 7)};
  EXPECT_EQ(packedTreeHash(p), "b2f0b887e038a5c0");
}

TEST(TreeHash, EqualTreesHashEqual) {
  const Scene scene = sceneOf(makeTriangleSoup(3000, 3));
  for (const std::string& name : builderNames()) {
    const Packed a = buildAndPack(scene, name), b = buildAndPack(scene, name);
    const std::string h = packedTreeHash(a.packed);
    EXPECT_EQ(h.size(), 16u);
    EXPECT_EQ(h.find_first_not_of("0123456789abcdef"), std::string::npos) << h;
    EXPECT_EQ(h, packedTreeHash(b.packed)) << name << ": the same builder run twice";
  }
  // Different builders, one tree: a single triangle is a single leaf for all of them.
  const Scene single = sceneOf(makeTriangleSoup(1, 4));
  const std::string first = packedTreeHash(buildAndPack(single, builderNames().front()).packed);
  for (const std::string& name : builderNames())
    EXPECT_EQ(packedTreeHash(buildAndPack(single, name).packed), first) << name;
}

TEST(TreeHash, ChangesWithOneNodeBoxOrOneTriangle) {
  const Packed base = buildAndPack(sceneOf(makeTriangleSoup(2000, 5)), "sah-binned");
  const std::string h = packedTreeHash(base.packed);

  PackedBvh box = base.packed;
  box.nodes[2 * 7 + 1].y ^= 1u;  // node 7's bmax.y, one ulp
  EXPECT_NE(packedTreeHash(box), h);

  PackedBvh vertex = base.packed;
  vertex.triangles[3 * 100 + 2].x ^= 1u;  // triangle 100's v2.x, one ulp
  EXPECT_NE(packedTreeHash(vertex), h);

  PackedBvh attribute = base.packed;
  attribute.attributes.back().w ^= 1u;
  EXPECT_NE(packedTreeHash(attribute), h);

  // Two triangles swapped in the stream: the same multiset of bytes, another tree.
  PackedBvh swapped = base.packed;
  for (int k = 0; k < 3; ++k) std::swap(swapped.triangles[k], swapped.triangles[3 + k]);
  EXPECT_NE(packedTreeHash(swapped), h);

  // A texel moved from one stream to the next: the concatenated bytes are equal, the counts are not.
  PackedBvh moved = base.packed;
  moved.attributes.insert(moved.attributes.begin(), moved.triangles.back());
  moved.triangles.pop_back();
  EXPECT_NE(packedTreeHash(moved), h);

  // Another builder's tree of the same triangles, where the streams differ.
  const Packed other = buildAndPack(sceneOf(makeTriangleSoup(2000, 5)), "median");
  ASSERT_NE(other.packed.nodes, base.packed.nodes);
  EXPECT_NE(packedTreeHash(other.packed), h);
}

}  // namespace
}  // namespace bvhlab
