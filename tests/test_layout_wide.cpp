// Wide layouts bvh4 / bvh8: the SAH-optimal collapse (coverage, widths, leaf cap, cost equal
// to the emitted tree's SAH and never above a greedy collapse's), the packer's invariants, every builder
// x wide layout x kernel against brute force, the stack bound, and the GLSL kernels against their C++
// mirror per ray (answer, visits, triangle tests, box tests; v1's and bvh2-cb's box counters too).
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "layout/collapse_wide.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "layout/layout_wide.hpp"
#include "layout/layouts.hpp"
#include "layout_test_util.hpp"
#include "shaders/assemble.hpp"
#include "traversal/kernels.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using namespace layouttest;

std::vector<uint32_t> parents(const Bvh& bvh) {
  std::vector<uint32_t> p(bvh.nodes.size(), UINT32_MAX);
  for (uint32_t i = 0; i < bvh.nodes.size(); ++i)
    if (!bvh.nodes[i].isLeaf()) p[bvh.nodes[i].left] = i, p[bvh.nodes[i].right] = i;
  return p;
}

bool isDescendant(const std::vector<uint32_t>& parent, uint32_t node, uint32_t ancestor) {
  for (uint32_t n = parent[node]; n != UINT32_MAX; n = parent[n])
    if (n == ancestor) return true;
  return false;
}

// The primitive ids of a binary subtree's leaves, sorted (duplicates kept).
std::vector<uint32_t> subtreePrims(const Bvh& bvh, uint32_t node) {
  std::vector<uint32_t> out, stack{node};
  while (!stack.empty()) {
    const BvhNode& n = bvh.nodes[stack.back()];
    stack.pop_back();
    if (n.isLeaf()) out.insert(out.end(), bvh.primIndices.begin() + n.first, bvh.primIndices.begin() + n.first + n.count);
    else stack.push_back(n.left), stack.push_back(n.right);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// A greedy collapse for comparison: a wide node opens its largest-area inner child until it has W
// children or only leaves; binary leaves stay leaves. One of the trees the program chooses among.
WideTree greedyCollapse(const Bvh& bvh, uint32_t width) {
  WideTree out;
  out.width = width;
  if (bvh.nodes[0].isLeaf()) return out;
  std::function<uint32_t(uint32_t)> emit = [&](uint32_t n) {
    const uint32_t index = uint32_t(out.nodes.size());
    out.nodes.push_back({n, {}});
    std::vector<uint32_t> kids{bvh.nodes[n].left, bvh.nodes[n].right};
    while (kids.size() < width) {
      int best = -1;
      for (size_t i = 0; i < kids.size(); ++i)
        if (!bvh.nodes[kids[i]].isLeaf() &&
            (best < 0 || bvh.nodes[kids[i]].bounds.halfArea() > bvh.nodes[kids[size_t(best)]].bounds.halfArea()))
          best = int(i);
      if (best < 0) break;
      const BvhNode& open = bvh.nodes[kids[size_t(best)]];
      kids[size_t(best)] = open.left;
      kids.insert(kids.begin() + best + 1, open.right);
    }
    for (uint32_t k : kids) {
      if (bvh.nodes[k].isLeaf()) {
        out.nodes[index].children.push_back({k, true, 0u});
      } else {
        const uint32_t child = emit(k);
        out.nodes[index].children.push_back({k, false, child});
      }
    }
    return index;
  };
  emit(0);
  return out;
}

// The collapse's invariants on one tree.
void checkCollapse(const Bvh& bvh, uint32_t width, uint32_t cap) {
  const WideTree wide = collapseWide(bvh, width, CostModel{}, cap);
  const std::vector<uint32_t> parent = parents(bvh), refs = subtreeReferences(bvh);
  ASSERT_EQ(wide.width, width);
  const double cost = wideSahCost(bvh, wide, CostModel{});
  EXPECT_NEAR(wide.cost, cost, 1e-9 * std::max(1.0, cost)) << "the program's cost is the emitted tree's SAH";
  const double greedy = wideSahCost(bvh, greedyCollapse(bvh, width), CostModel{});
  EXPECT_LE(wide.cost, greedy * (1.0 + 1e-12)) << "the optimum is never above a greedy collapse";
  if (bvh.nodes[0].isLeaf()) {
    EXPECT_TRUE(wide.nodes.empty());
    return;
  }
  ASSERT_FALSE(wide.nodes.empty());
  EXPECT_EQ(wide.nodes[0].binaryNode, 0u);
  // Which wide node stands for each binary node (inner wide nodes only), and the references under each.
  std::map<uint32_t, uint32_t> wideOf;
  for (uint32_t i = 0; i < wide.nodes.size(); ++i) wideOf[wide.nodes[i].binaryNode] = i;
  std::vector<int> reached(wide.nodes.size(), 0);
  reached[0] = 1;
  for (uint32_t i = 0; i < wide.nodes.size(); ++i) {
    const WideNode& n = wide.nodes[i];
    ASSERT_GE(n.children.size(), 2u);
    ASSERT_LE(n.children.size(), width);
    uint64_t sum = 0;
    for (size_t a = 0; a < n.children.size(); ++a) {
      const WideChild& c = n.children[a];
      ASSERT_TRUE(isDescendant(parent, c.binaryNode, n.binaryNode)) << "a wide child lies under its node";
      EXPECT_TRUE(bvh.nodes[n.binaryNode].bounds.contains(bvh.nodes[c.binaryNode].bounds));
      for (size_t b = 0; b < a; ++b)
        ASSERT_FALSE(isDescendant(parent, c.binaryNode, n.children[b].binaryNode) ||
                     isDescendant(parent, n.children[b].binaryNode, c.binaryNode))
            << "two children of one wide node overlap";
      sum += refs[c.binaryNode];
      if (c.leaf) {
        if (!bvh.nodes[c.binaryNode].isLeaf()) {
          EXPECT_LE(refs[c.binaryNode], cap) << "merged leaf over the cap";
        }
      } else {
        ASSERT_LT(c.wideNode, wide.nodes.size());
        EXPECT_GT(c.wideNode, i) << "pre-order";
        EXPECT_EQ(wide.nodes[c.wideNode].binaryNode, c.binaryNode);
        ASSERT_EQ(reached[c.wideNode]++, 0);
      }
    }
    // Disjoint subtrees under n whose references add up to n's: they cover n's references exactly once.
    EXPECT_EQ(sum, refs[n.binaryNode]);
  }
  EXPECT_EQ(std::count(reached.begin(), reached.end(), 1), long(wide.nodes.size()));
  // Every binary node's primitives are under the wide node covering it (its nearest ancestor-or-self
  // that is a wide node).
  std::vector<std::vector<uint32_t>> under(wide.nodes.size());
  for (uint32_t i = 0; i < wide.nodes.size(); ++i) under[i] = subtreePrims(bvh, wide.nodes[i].binaryNode);
  for (uint32_t b = 0; b < bvh.nodes.size(); ++b) {
    uint32_t a = b;
    while (!wideOf.count(a)) a = parent[a];
    std::vector<uint32_t> mine = subtreePrims(bvh, b);
    const std::vector<uint32_t>& theirs = under[wideOf[a]];
    ASSERT_TRUE(std::includes(theirs.begin(), theirs.end(), mine.begin(), mine.end())) << "binary node " << b;
  }
}

TEST(CollapseWide, EveryBuildersTreeKeepsTheInvariants) {
  for (const TestMesh& m : testMeshes())
    for (const BuilderInfo& b : builders()) {
      const Bvh bvh = build(b.name, m.soup);
      for (uint32_t width : {4u, 8u})
        for (uint32_t cap : {1u, 4u, 16u}) {
          SCOPED_TRACE(m.name + " / " + b.name + " / W " + std::to_string(width) + " / cap " + std::to_string(cap));
          checkCollapse(bvh, width, cap);
        }
    }
  const TriangleSoup few = firstTriangles(testMeshes()[1].soup, 5);
  checkCollapse(singleLeaf(few), 4, 4);
  EXPECT_THROW(collapseWide(singleLeaf(few), 1, CostModel{}, 4), std::invalid_argument);
  EXPECT_THROW(collapseWide(Bvh{}, 4, CostModel{}, 4), std::invalid_argument);
}

// A wide tree has fewer levels and fewer nodes than the binary one, and more of the merging pays when
// a leaf test is cheap: the program reacts to the cost model.
TEST(CollapseWide, CostModelSteersLeafMerging) {
  const TestMesh& m = testMeshes()[0];
  const Bvh bvh = build("sah-binned", m.soup);
  const WideTree cheapLeaves = collapseWide(bvh, 4, CostModel{1.0f, 0.05f}, 64);
  const WideTree dearLeaves = collapseWide(bvh, 4, CostModel{1.0f, 20.0f}, 64);
  EXPECT_LT(cheapLeaves.nodes.size(), dearLeaves.nodes.size());
  EXPECT_LT(dearLeaves.nodes.size(), bvh.nodes.size() / 2);
}

// The packed streams: slot boxes contain their children's, records reached once, leaf ranges cover
// the TRIANGLE stream once (so every reference appears as often as in the binary tree), the triangle
// streams are v1's, depth is the wide tree's, and no record is wider than W.
void checkPacked(const PackedBvh& p, const PackedBvh& v1, const Bvh& bvh, uint32_t width) {
  ASSERT_EQ(wideWidth(p.layout), width);
  EXPECT_EQ(p.triangles, v1.triangles);
  EXPECT_EQ(p.attributes, v1.attributes);
  const uint32_t triangles = uint32_t(p.triangles.size() / kTriangleTexels);
  std::vector<int> covered(triangles, 0);
  size_t texels = kWideSlotTexels;
  uint32_t maxDepth = 1;
  struct Item {
    uint32_t texel, depth;
  };
  std::vector<Item> stack{{0u, 1u}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const WideSlot s = unpackWideSlot(p, it.texel);
    maxDepth = std::max(maxDepth, it.depth);
    if (!s.isInner()) {
      ASSERT_GE(s.count, 1u);
      ASSERT_LE(uint64_t(s.link) + s.count, triangles);
      for (uint32_t k = 0; k < s.count; ++k) covered[s.link + k]++;
      continue;
    }
    ASSERT_GE(s.children(), 2u);
    ASSERT_LE(s.children(), width);
    texels += kWideSlotTexels * s.children();
    for (uint32_t c = 0; c < s.children(); ++c) {
      const WideSlot child = unpackWideSlot(p, s.link + kWideSlotTexels * c);
      EXPECT_TRUE((Aabb{s.bmin, s.bmax}.contains(Aabb{child.bmin, child.bmax}))) << "slot at texel " << s.link;
      stack.push_back({s.link + kWideSlotTexels * c, it.depth + 1});
    }
  }
  EXPECT_EQ(texels, p.nodes.size()) << "records reached once, no unreachable texels";
  EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), long(triangles)) << "leaf ranges cover the stream once";
  EXPECT_EQ(p.depth, maxDepth);
  std::map<uint32_t, int> binaryRefs, packedRefs;
  for (uint32_t prim : bvh.primIndices) binaryRefs[prim]++;
  for (uint32_t t = 0; t < triangles; ++t) packedRefs[p.triangles[3 * t].w]++;
  EXPECT_EQ(binaryRefs, packedRefs) << "every reference as often as in the binary tree";
}

TEST(WidePacker, EveryBuildersTreeKeepsTheInvariants) {
  for (const TestMesh& m : testMeshes())
    for (const BuilderInfo& b : builders()) {
      const Bvh bvh = build(b.name, m.soup);
      const PackedBvh v1 = packBvh(bvh, m.soup);
      for (uint32_t width : {4u, 8u}) {
        SCOPED_TRACE(m.name + " / " + b.name + " / W " + std::to_string(width));
        const PackedBvh p = packWide(bvh, m.soup, width);
        checkPacked(p, v1, bvh, width);
        EXPECT_LT(p.nodes.size(), v1.nodes.size()) << "a wide tree stores fewer slots than v1 nodes";
        EXPECT_EQ(stackSizeFor(p), int(std::max(1u, (width - 1) * (p.depth - 1))));
      }
    }
  const TriangleSoup few = firstTriangles(testMeshes()[1].soup, 5);
  const Bvh leaf = singleLeaf(few);
  const PackedBvh p = packBvh8(leaf, few);
  checkPacked(p, packBvh(leaf, few), leaf, 8);
  EXPECT_EQ(p.nodes.size(), size_t(kWideSlotTexels));
  EXPECT_EQ(p.depth, 1u);
  EXPECT_EQ(stackSizeFor(p), 1);
  EXPECT_THROW(unpackWideSlot(packBvh(leaf, few), 0), std::invalid_argument);
  EXPECT_THROW(unpackWideSlot(p, 2), std::out_of_range);
}

// Every builder x wide layout x kernel (watertight and fast tests) finds brute force's closest t and
// its any-hit answer on every ray, within the stack bound (no overflow at stackSizeFor).
TEST(WideKernels, EveryBuilderFindsTheBruteForceHits) {
  for (const TestMesh& m : testMeshes()) {
    const std::vector<BatchRay> rays = testRays(m.soup, 400, 7);
    std::vector<BatchHit> expected;
    for (const BatchRay& r : rays) expected.push_back(bruteForce(m.soup, r));
    for (const BuilderInfo& b : builders()) {
      const Bvh bvh = build(b.name, m.soup);
      for (const char* layout : {kLayoutBvh4, kLayoutBvh8}) {
        const PackedBvh packed = findLayout(layout).pack(bvh, m.soup);
        for (const KernelInfo& k : kernelsFor(layout)) {
          SCOPED_TRACE(m.name + " / " + b.name + " / " + layout + " / " + k.name);
          expectBruteForceHits(packed, k, Robustness::Watertight, rays, expected);
        }
      }
    }
  }
}

// Nearest first: on the cube grid (many boxes one behind another) the ordered wide kernels test fewer
// triangles for closest hits than v1's stack-unordered walk of the same tree (fixed child order); a
// sort that walked the farthest child first would test more.
TEST(WideKernels, NearestFirstCutsTheWork) {
  const TestMesh& m = testMeshes()[2];
  const Bvh bvh = build("sah-binned", m.soup);
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 3);
  const uint64_t unordered = closestTriangleTests(packBvh(bvh, m.soup), "stack-unordered", rays);
  for (const char* layout : {kLayoutBvh4, kLayoutBvh8}) {
    const uint64_t ordered = closestTriangleTests(findLayout(layout).pack(bvh, m.soup), "", rays);
    EXPECT_LT(double(ordered), 0.8 * double(unordered)) << layout;
  }
}

// The hard-case suite in watertight mode: the wide kernels leak no ray that must hit, and answer every
// ray as v1's stack-ordered does on the same tree (expectHardCasesAnsweredAsV1, layout_test_util.hpp).
TEST(WideKernels, HardCasesLeakNothingInWatertightMode) {
  for (const char* layout : {kLayoutBvh4, kLayoutBvh8}) EXPECT_GT(expectHardCasesAnsweredAsV1(layout), 100u) << layout;
}

// The GLSL kernels give their C++ mirror's answer and counters per ray (visits, triangle tests, box
// tests, no overflow), closest and any hit, watertight and fast, on a builder's tree, an sbvh tree and
// a single-leaf tree; every other kernel's box counter is checked against its mirror alongside.
TEST(WideKernelsGlsl, EqualTheMirrorPerRay) {
  auto ctx = contextOrNull();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const TestMesh& m = testMeshes()[1];
  const TriangleSoup few = firstTriangles(m.soup, 7);
  struct Case {
    std::string name;
    PackedBvh packed;
    std::vector<BatchRay> rays;
    bool fastToo;
  };
  std::vector<Case> cases;
  const Bvh tree = build("sah-binned", m.soup), split = build("sbvh", m.soup);
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 11);
  cases.push_back({"soup/bvh4", packBvh4(tree, m.soup), rays, true});
  cases.push_back({"soup/bvh8", packBvh8(tree, m.soup), rays, true});
  cases.push_back({"soup-sbvh/bvh8", packBvh8(split, m.soup), rays, false});
  cases.push_back({"single-leaf/bvh4", packBvh4(singleLeaf(few), few), testRays(few, 300, 12), false});
  cases.push_back({"soup/v1", packBvh(tree, m.soup), rays, false});
  cases.push_back({"soup/bvh2-cb", packBvh2cb(tree, m.soup), rays, false});
  for (const Case& cs : cases)
    for (const KernelInfo& k : kernelsFor(cs.packed.layout))
      for (bool anyHit : {false, true})
        for (Robustness robust : {Robustness::Watertight, Robustness::Fast}) {
          if (robust == Robustness::Fast && !cs.fastToo) continue;
          SCOPED_TRACE(cs.name + " / " + k.name + (anyHit ? " any" : " closest") + " / " + robustnessName(robust));
          const size_t found = expectGlslEqualsMirror(cs.packed, k, cs.rays, anyHit, robust);
          EXPECT_GT(found, cs.rays.size() / 10) << "too few hits for the comparison to mean much";
        }
}

// The fetch-whole kernels walk as the stack-ordered ones do: per ray the same hit and the same
// counters, bytes included (their mirrors; the GLSL equals each mirror above).
TEST(WideKernels, FetchWholeWalksAsStackOrdered) {
  const layouttest::TestMesh& m = layouttest::testMeshes().front();
  const Bvh tree = build("sah-binned", m.soup);
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 11);
  for (const char* layout : {"bvh4", "bvh8"}) {
    const PackedBvh packed = findLayout(layout).pack(tree, m.soup);
    const KernelInfo& plain = findKernel(layout, std::string(layout) + "-stack-ordered");
    const KernelInfo& whole = findKernel(layout, std::string(layout) + "-fetch-whole");
    size_t hits = 0;
    for (const BatchRay& r : rays) {
      glsl::Counters a, b;
      glsl::MeshHit ha, hb;
      const bool fa = plain.traceClosest(packed, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, ha, a);
      const bool fb = whole.traceClosest(packed, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, hb, b);
      ASSERT_EQ(fa, fb);
      ASSERT_EQ(ha.tri, hb.tri);
      ASSERT_EQ(ha.t, hb.t);
      ASSERT_EQ(a.nodeVisits, b.nodeVisits);
      ASSERT_EQ(a.boxTests, b.boxTests);
      ASSERT_EQ(a.triTests, b.triTests);
      ASSERT_EQ(a.nodeBytes, b.nodeBytes);
      ASSERT_EQ(a.stackBytes, b.stackBytes);
      hits += fa;
    }
    EXPECT_GT(hits, rays.size() / 10) << layout;
  }
}

// A kernel of another layout is refused, naming the wide layout's kernel.
TEST(WideKernels, MismatchedLayoutAndKernelAreRefused) {
  const auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  std::string msg = message([] { findKernel("bvh4", "bvh8-stack-ordered"); });
  EXPECT_NE(msg.find("walks layout bvh8, not bvh4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("bvh4-stack-ordered"), std::string::npos) << msg;
  msg = message([] { findKernel("bvh8", "stack-ordered"); });
  EXPECT_NE(msg.find("bvh8-stack-ordered"), std::string::npos) << msg;
  msg = message([] { assembleRayTracer("bvh4-stack-ordered", Storage::Tbo, Robustness::Watertight, 8, false, false, "v1"); });
  EXPECT_NE(msg.find("walks layout bvh4, not v1"), std::string::npos) << msg;
  EXPECT_EQ(findKernel("bvh8", "").name, "bvh8-stack-ordered");
}

}  // namespace
}  // namespace bvhlab
