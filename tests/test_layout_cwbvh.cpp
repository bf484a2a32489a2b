// Layout cwbvh (the compressed 8-wide node of Ylitie, Karras & Laine 2017; layout/layout_cwbvh.hpp):
// the packer's invariants on every builder's tree and on hard inputs (a flat axis, coordinates 1e6
// from the origin, tiny triangles a few ulps wide, tiny and huge scales, sbvh's duplicates, a one-leaf
// tree) - above all that every decoded child box CONTAINS its exact child box -, the leaf limit, 80
// bytes a node, every builder x robustness pair against brute force, the hard-case suite, and the GLSL
// kernel against its C++ mirror per ray (answer, visits, triangle tests, box tests).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "datasets/random_draws.hpp"
#include "layout/collapse_v1.hpp"
#include "layout/layout_cwbvh.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "gl_compute.hpp"
#include "layout_test_util.hpp"
#include "shaders/assemble.hpp"
#include "traversal/kernel_cwbvh_groups.hpp"
#include "traversal/kernels.hpp"
#include "traversal/layout_cwbvh.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using namespace layouttest;

// A soup moved and scaled vertex by vertex (normals and uvs kept): v -> v * scale + offset.
TriangleSoup transformed(TriangleSoup s, float scale, glm::vec3 offset) {
  for (auto* v : {&s.v0, &s.v1, &s.v2})
    for (glm::vec3& p : *v) p = p * scale + offset;
  return s;
}

// n x n quads on the plane z = 0.25: every box is flat in z.
TriangleSoup flatGrid(int n) {
  Mesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.positions.push_back({float(x) / float(n), float(y) / float(n), 0.25f});
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  MeshSceneOptions mo;
  mo.groundPlane = false;
  return gatherTriangles(makeMeshScene(m, mo));
}

// Triangles a few ulps wide scattered in [0.5, 1)^3: child boxes narrower than the grid's finest step
// at p, where several q decode to the same float.
TriangleSoup tinyTriangles(size_t n) {
  TriangleSoup s = firstTriangles(testMeshes()[1].soup, n);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.5f, 0.999f);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 c = draw3<glm::vec3>(u, rng);
    s.v0[i] = c;
    s.v1[i] = {std::nextafter(c.x, 2.0f), c.y, std::nextafter(std::nextafter(c.z, 2.0f), 2.0f)};
    s.v2[i] = {c.x, std::nextafter(c.y, 2.0f), std::nextafter(c.z, 0.0f)};
  }
  return s;
}

struct HardInput {
  std::string name;
  TriangleSoup soup;
  bool fewHits;  // rays at random points of the box rarely meet these triangles
};

const std::vector<HardInput>& hardInputs() {
  static const std::vector<HardInput> inputs = [] {
    const TriangleSoup& soup = testMeshes()[1].soup;
    std::vector<HardInput> h;
    h.push_back({"flat-z", flatGrid(12), false});
    h.push_back({"far-1e6", transformed(soup, 1.0f, glm::vec3(1e6f, -1e6f, 1e6f)), false});
    h.push_back({"tiny-triangles", tinyTriangles(300), true});
    // Scales the triangle tests still handle in float (their products of three coordinates stay normal).
    h.push_back({"scale-1e-10", transformed(soup, 1e-10f, glm::vec3(0.0f)), false});
    h.push_back({"scale-1e10", transformed(soup, 1e10f, glm::vec3(0.0f)), false});
    return h;
  }();
  return inputs;
}

bool containsBox(glm::vec3 outerMin, glm::vec3 outerMax, const Aabb& inner) {
  return glm::all(glm::lessThanEqual(outerMin, inner.min)) && glm::all(glm::greaterThanEqual(outerMax, inner.max));
}

// The packed tree against the collapse it was written from, walked in parallel from the root: node
// shapes, metas, links (inner children consecutive, leaf triangles consecutive in slot order and equal
// to v1's texel for texel), every decoded child box containing the exact (float) box of its binary
// node, inside its node's grid, on the finest grid that reaches, with the tightest q either way; and
// nodes reached once, 80 bytes each, the triangle stream covered once, references as often as in the
// builder's tree, depth and stack bound.
void checkPacked(const Bvh& bvh, const TriangleSoup& soup) {
  const PackedBvh p = packCwbvh(bvh, soup);
  const CollapsedV1 c = collapseThroughV1(bvh, soup, kCwbvhWidth);
  ASSERT_EQ(p.layout, kLayoutCwbvh);
  const std::vector<WideNode> single{WideNode{0, {WideChild{0, true, 0}}}};
  const std::vector<WideNode>& wide = c.wide.nodes.empty() ? single : c.wide.nodes;
  const uint32_t nodes = cwbvhNodeCount(p);
  EXPECT_EQ(p.nodes.size() * 16, 80 * wide.size()) << "80 bytes a node, one node per wide node";
  ASSERT_EQ(nodes, wide.size());
  ASSERT_EQ(p.triangles.size(), c.v1.triangles.size());
  ASSERT_EQ(p.attributes.size(), c.v1.attributes.size());
  const uint32_t triangles = uint32_t(p.triangles.size() / kTriangleTexels);
  std::vector<int> covered(triangles, 0), reached(nodes, 0);
  const glsl::Storage storage(p);
  struct Item {
    uint32_t node, wide, depth;
  };
  std::vector<Item> stack{{0u, 0u, 1u}};
  uint32_t maxDepth = 1;
  int failures = 0;
  while (!stack.empty() && failures < 5) {
    const Item it = stack.back();
    stack.pop_back();
    ASSERT_LT(it.node, nodes);
    ASSERT_EQ(reached[it.node]++, 0) << "node " << it.node << " reached twice";
    const CwbvhNode n = unpackCwbvhNode(p, it.node);
    const WideNode& w = wide[it.wide];
    ASSERT_EQ(n.children, w.children.size());
    // The mirror decodes the same boxes as the tools' decoder.
    const glsl::CwNode mirror = glsl::loadCwNode(storage, it.node);
    glsl::vec3 gridMin, gridMax;  // the box the kernel tests for the root: the node's whole grid
    glsl::cwbvhGridBox(storage, it.node, gridMin, gridMax);
    Aabb frame;
    for (const WideChild& ch : w.children) frame.grow(c.binary.nodes[ch.binaryNode].bounds);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(n.origin[a], frame.min[a]);
      ASSERT_GE(n.exponent[a], 1u);
      ASSERT_LE(n.exponent[a], 254u);
      EXPECT_GE(cwbvhDecode(n.origin[a], 255, n.scale[a]), frame.max[a]) << "the grid reaches the node's max";
      EXPECT_EQ(gridMin[a], n.origin[a]);
      EXPECT_EQ(gridMax[a], cwbvhDecode(n.origin[a], 255, n.scale[a]));
      if (n.exponent[a] > 1) {
        EXPECT_LT(cwbvhDecode(n.origin[a], 255, n.scale[a] * 0.5f), frame.max[a]) << "a finer grid would have done";
      }
    }
    // Slots by octant: the packer's assignment of these children (cwbvhAssignSlots), each child once;
    // an empty slot holds meta 0 and q bytes 0.
    std::vector<glm::vec3> centroids;
    for (const WideChild& ch : w.children) centroids.push_back(c.binary.nodes[ch.binaryNode].bounds.center());
    const std::array<int, 8> childOf = cwbvhAssignSlots(centroids, frame.center());
    std::vector<int> slotted(w.children.size(), 0);
    uint32_t rank = 0, offset = 0;
    for (uint32_t s = 0; s < 8; ++s) {
      if (childOf[s] < 0) {
        EXPECT_EQ(n.meta[s], 0u) << "an empty slot holds meta 0";
        EXPECT_EQ(n.qlo[s], glm::uvec3(0u));
        EXPECT_EQ(n.qhi[s], glm::uvec3(0u));
        continue;
      }
      ASSERT_LT(size_t(childOf[s]), w.children.size());
      slotted[size_t(childOf[s])]++;
      const WideChild& ch = w.children[size_t(childOf[s])];
      const Aabb& exact = c.binary.nodes[ch.binaryNode].bounds;
      glsl::vec3 mirrorMin, mirrorMax;
      glsl::cwbvhChildBox(mirror, s, mirrorMin, mirrorMax);
      EXPECT_EQ(mirrorMin, n.bmin[s]);
      EXPECT_EQ(mirrorMax, n.bmax[s]);
      if (!containsBox(n.bmin[s], n.bmax[s], exact)) {
        ++failures;
        ADD_FAILURE() << "node " << it.node << " slot " << s << ": decoded box does not contain the child's box";
      }
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(n.bmin[s][a], n.origin[a]);
        EXPECT_LE(n.bmax[s][a], cwbvhDecode(n.origin[a], 255, n.scale[a])) << "inside the node's grid";
        EXPECT_LE(n.qlo[s][a], n.qhi[s][a]);
        // Tightest: one step more inward would no longer contain the child.
        if (n.qlo[s][a] < n.qhi[s][a]) {
          EXPECT_GT(cwbvhDecode(n.origin[a], n.qlo[s][a] + 1, n.scale[a]), exact.min[a]);
          EXPECT_LT(cwbvhDecode(n.origin[a], n.qhi[s][a] - 1, n.scale[a]), exact.max[a]);
        }
      }
      EXPECT_EQ(n.link(s), n.isInner(s) ? n.childBase + rank : n.triBase + offset);
      if (ch.leaf) {
        ASSERT_FALSE(n.isInner(s));
        ASSERT_EQ(n.meta[s], c.refs[ch.binaryNode]);
        ASSERT_GE(n.meta[s], 1u);
        const uint32_t first = n.link(s), v1First = c.first[ch.binaryNode];
        ASSERT_LE(uint64_t(first) + n.meta[s], triangles);
        for (uint32_t t = 0; t < n.meta[s]; ++t) {
          covered[first + t]++;
          for (uint32_t k = 0; k < kTriangleTexels; ++k)
            ASSERT_EQ(p.triangles[kTriangleTexels * (first + t) + k], c.v1.triangles[kTriangleTexels * (v1First + t) + k]);
          for (uint32_t k = 0; k < kAttributeTexels; ++k)
            ASSERT_EQ(p.attributes[kAttributeTexels * (first + t) + k],
                      c.v1.attributes[kAttributeTexels * (v1First + t) + k]);
        }
        offset += n.meta[s];
      } else {
        ASSERT_TRUE(n.isInner(s));
        stack.push_back({n.childBase + rank, ch.wideNode, it.depth + 1});
        ++rank;
      }
      maxDepth = std::max(maxDepth, it.depth + 1);
    }
    EXPECT_EQ(std::count(slotted.begin(), slotted.end(), 1), long(w.children.size())) << "every child in one slot";
  }
  ASSERT_EQ(failures, 0);
  EXPECT_EQ(std::count(reached.begin(), reached.end(), 1), long(nodes)) << "every node reached once";
  EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), long(triangles)) << "leaves cover the stream once";
  EXPECT_EQ(p.depth, maxDepth);
  EXPECT_EQ(stackSizeFor(p), int(std::max(1u, 7 * (p.depth - 1))));
  std::map<uint32_t, int> binaryRefs, packedRefs;
  for (uint32_t prim : bvh.primIndices) binaryRefs[prim]++;
  for (uint32_t t = 0; t < triangles; ++t) packedRefs[p.triangles[kTriangleTexels * t].w]++;
  EXPECT_EQ(binaryRefs, packedRefs) << "every reference as often as in the builder's tree";
}

TEST(CwbvhPacker, EveryBuildersTreeKeepsTheInvariants) {
  for (const TestMesh& m : testMeshes())
    for (const BuilderInfo& b : builders()) {
      SCOPED_TRACE(m.name + " / " + b.name);
      checkPacked(build(b.name, m.soup), m.soup);
    }
}

TEST(CwbvhPacker, HardInputsKeepTheInvariants) {
  std::vector<HardInput> inputs = hardInputs();
  // Packing only (the triangle tests' products under- or overflow there): exponents far from 127.
  inputs.push_back({"scale-1e-30", transformed(testMeshes()[1].soup, 1e-30f, glm::vec3(0.0f)), true});
  inputs.push_back({"scale-1e18", transformed(testMeshes()[1].soup, 1e18f, glm::vec3(0.0f)), true});
  for (const HardInput& h : inputs)
    for (const char* builder : {"sah-binned", "sbvh", "lbvh"}) {
      SCOPED_TRACE(h.name + " / " + builder);
      checkPacked(build(builder, h.soup), h.soup);
    }
  // sbvh's duplicated references: the point of the sbvh case is that there are some.
  const TestMesh& m = testMeshes()[1];
  const Bvh split = build("sbvh", m.soup);
  ASSERT_GT(split.primIndices.size(), m.soup.size()) << "this sbvh tree has no duplicates to test";
  // A tree that is one leaf: one node, one leaf child.
  const TriangleSoup few = firstTriangles(m.soup, 5);
  const Bvh leaf = singleLeaf(few);
  checkPacked(leaf, few);
  const PackedBvh p = packCwbvh(leaf, few);
  EXPECT_EQ(cwbvhNodeCount(p), 1u);
  EXPECT_EQ(unpackCwbvhNode(p, 0).children, 1u);
  EXPECT_EQ(unpackCwbvhNode(p, 0).meta[0], 5u);
  EXPECT_EQ(p.depth, 2u);
  EXPECT_THROW(unpackCwbvhNode(packBvh(leaf, few), 0), std::invalid_argument);
  EXPECT_THROW(unpackCwbvhNode(p, 1), std::out_of_range);
}

// A leaf over the 7-bit count is refused, naming the limit and the way out.
TEST(CwbvhPacker, RefusesALeafOfMoreThan127Triangles) {
  const TriangleSoup many = firstTriangles(testMeshes()[1].soup, 200);
  std::string msg = "no exception";
  try {
    packCwbvh(singleLeaf(many), many);
  } catch (const std::runtime_error& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("leaf of 200 triangles"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at most 127"), std::string::npos) << msg;
  EXPECT_NE(msg.find("--leaf-size"), std::string::npos) << msg;
  const TriangleSoup enough = firstTriangles(testMeshes()[1].soup, 127);
  EXPECT_NO_THROW(packCwbvh(singleLeaf(enough), enough));
}

// 80 bytes a node: fewer node bytes than bvh8's 32-byte slots for the same collapse, and the triangle
// formats apply to the re-ordered streams (the node stream stays the same).
TEST(CwbvhPacker, EightyBytesANodeAndEveryTriangleFormat) {
  const TestMesh& m = testMeshes()[0];
  const Bvh bvh = build("sah-binned", m.soup);
  const PackedBvh cw = packCwbvh(bvh, m.soup), b8 = findLayout("bvh8").pack(bvh, m.soup);
  const CollapsedV1 c = collapseThroughV1(bvh, m.soup, 8);
  EXPECT_EQ(16 * cw.nodes.size(), 80 * c.wide.nodes.size());
  EXPECT_LT(cw.nodes.size(), b8.nodes.size());
  for (const TriangleFormatInfo& f : triangleFormats()) {
    PackedBvh q = cw;
    packTriangles(q, m.soup, f.name);
    EXPECT_EQ(q.nodes, cw.nodes) << f.name;
    EXPECT_EQ(q.layout, kLayoutCwbvh);
  }
}

// Brute force with one triangle test: the closest t over all triangles.
template <TriangleTest T>
BatchHit bruteForceWith(const TriangleSoup& s, const BatchRay& r) {
  using Tests = glsl::Tests<T, BoxTest::Slab>;
  BatchHit best;
  best.t = r.tMax;
  for (uint32_t i = 0; i < s.size(); ++i) {
    float t;
    glsl::vec2 bary;
    if (Tests::intersectTriangle(glsl::Ray{r.origin, r.dir}, s.v0[i], s.v1[i], s.v2[i], r.tMin, best.t, t, bary))
      best = BatchHit{true, i, t};
  }
  return best;
}

// Every builder's tree (and the hard inputs') x every (triangle test, box test) pair: the kernel
// finds brute force's closest t with the same triangle test and its any-hit answer on every ray,
// within the stack bound. Except the slab box test 1e6 from the origin: there it misses boxes that a
// hit lies in, in every layout (measured: v1's stack-ordered lost 36 hits of these rays, bvh8 12,
// cwbvh 12 with Moller-Trumbore; the robust box test, Ize 2013, loses none), so the slab pairs are not
// held to brute force on that input.
TEST(CwbvhKernels, EveryBuilderFindsTheBruteForceHits) {
  std::vector<std::pair<std::string, const TriangleSoup*>> soups;
  for (const TestMesh& m : testMeshes()) soups.push_back({m.name, &m.soup});
  for (const HardInput& h : hardInputs()) soups.push_back({h.name, &h.soup});
  const std::vector<Robustness> pairs = {
      {TriangleTest::MollerTrumbore, BoxTest::Slab}, {TriangleTest::MollerTrumbore, BoxTest::Robust},
      {TriangleTest::Watertight, BoxTest::Slab}, {TriangleTest::Watertight, BoxTest::Robust}};
  for (const auto& [name, soup] : soups) {
    const std::vector<BatchRay> rays = testRays(*soup, 300, 7);
    std::vector<BatchHit> expectedMt, expectedWt;
    for (const BatchRay& r : rays) {
      expectedMt.push_back(bruteForceWith<TriangleTest::MollerTrumbore>(*soup, r));
      expectedWt.push_back(bruteForceWith<TriangleTest::Watertight>(*soup, r));
    }
    for (const BuilderInfo& b : builders()) {
      const PackedBvh packed = packCwbvh(build(b.name, *soup), *soup);
      for (const KernelInfo& k : kernelsFor(kLayoutCwbvh))
        for (const Robustness& robust : pairs) {
          if (robust.box == BoxTest::Slab && name == "far-1e6") continue;
          SCOPED_TRACE(name + " / " + b.name + " / " + k.name + " / " + robustnessName(robust));
          expectBruteForceHits(packed, k, robust, rays,
                               robust.triangle == TriangleTest::Watertight ? expectedWt : expectedMt);
        }
    }
  }
}

// Nearest first: on the cube grid the ordered kernel tests fewer triangles for closest hits than v1's
// stack-unordered walk of the same tree.
TEST(CwbvhKernels, NearestFirstCutsTheWork) {
  const TestMesh& m = testMeshes()[2];
  const Bvh bvh = build("sah-binned", m.soup);
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 3);
  EXPECT_LT(double(closestTriangleTests(packCwbvh(bvh, m.soup), "", rays)),
            0.8 * double(closestTriangleTests(packBvh(bvh, m.soup), "stack-unordered", rays)));
}

// The hard-case suite in watertight mode, every cwbvh kernel: no ray that must hit leaks, and every ray
// is answered as v1's stack-ordered answers it on the same tree (expectHardCasesAnsweredAsV1,
// layout_test_util.hpp).
TEST(CwbvhKernels, HardCasesLeakNothingInWatertightMode) {
  for (const KernelInfo& k : kernelsFor(kLayoutCwbvh)) EXPECT_GT(expectHardCasesAnsweredAsV1(kLayoutCwbvh, k.name), 100u);
}

// The GLSL kernel gives its C++ mirror's answer and counters per ray (visits, triangle tests, box
// tests, no overflow), closest and any hit, watertight and fast, on a builder's tree, an sbvh tree,
// the hard inputs, indexed triangles, 2D-texture storage and a single-leaf tree.
TEST(CwbvhKernelsGlsl, EqualTheMirrorPerRay) {
  auto ctx = contextOrNull();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const TestMesh& m = testMeshes()[1];
  const TriangleSoup few = firstTriangles(m.soup, 7);
  struct Case {
    std::string name;
    PackedBvh packed;
    std::vector<BatchRay> rays;
    bool fastToo;
    Storage storage;
    bool fewHits = false;
  };
  std::vector<Case> cases;
  const Bvh tree = build("sah-binned", m.soup);
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 11);
  cases.push_back({"soup", packCwbvh(tree, m.soup), rays, true, Storage::Tbo});
  cases.push_back({"soup-sbvh", packCwbvh(build("sbvh", m.soup), m.soup), rays, false, Storage::Tbo});
  cases.push_back({"soup-tex2d", packCwbvh(tree, m.soup), rays, false, Storage::Tex2D});
  PackedBvh indexed = packCwbvh(tree, m.soup);
  packTriangles(indexed, m.soup, "indexed");
  cases.push_back({"soup-indexed", indexed, rays, false, Storage::Tbo});
  cases.push_back({"soup-indexed-ssbo", indexed, rays, false, Storage::Ssbo});  // all four streams as storage buffers
  for (const HardInput& h : hardInputs())
    cases.push_back({h.name, packCwbvh(build("sah-binned", h.soup), h.soup), testRays(h.soup, 400, 13), false, Storage::Tbo,
                     h.fewHits});
  cases.push_back({"single-leaf", packCwbvh(singleLeaf(few), few), testRays(few, 300, 12), false, Storage::Tbo});
  for (const Case& cs : cases)
    for (const KernelInfo& k : kernelsFor(cs.packed.layout))
      for (bool anyHit : {false, true})
        for (Robustness robust : {Robustness::Watertight, Robustness::Fast}) {
          if (robust == Robustness::Fast && !cs.fastToo) continue;
          SCOPED_TRACE(cs.name + " / " + k.name + (anyHit ? " any" : " closest") + " / " + robustnessName(robust));
          const size_t found = expectGlslEqualsMirror(cs.packed, k, cs.rays, anyHit, robust, cs.storage);
          if (!cs.fewHits) {
            EXPECT_GT(found, cs.rays.size() / 10) << "too few hits for the comparison to mean much";
          }
        }
}

// The short shared stack of cwbvh-groups-shared (kernel_cwbvh_groups.glsl, SHARED_STACK_ENTRIES) with
// ONE entry in shared memory, so that every push past the first spills and every pop past it restores:
// the same answers and counters as the mirror (the registered variant keeps 8, more than these trees
// need, so its spill path is checked here).
const char* const kShortStackMain = R"(
layout(local_size_x = COMPUTE_LANES) in;
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer ResultBuffer { uvec4 results[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  MeshHit hit;
  bool found = traceClosest(Ray(rays[2 * i].xyz, rays[2 * i + 1].xyz), rays[2 * i].w, rays[2 * i + 1].w, hit);
  results[2 * i] = uvec4(found ? 1u : 0u, uint(hit.tri), floatBitsToUint(hit.t), g_stackOverflow ? 1u : 0u);
  results[2 * i + 1] = uvec4(g_nodeVisits, g_triTests, g_boxTests, 0u);
}
)";

TEST(CwbvhKernelsGlsl, ShortSharedStackSpillsAndRestoresAsTheMirrorWalks) {
  auto ctx = contextOrNull();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const TestMesh& m = testMeshes()[1];
  const PackedBvh packed = packCwbvh(build("sah-binned", m.soup), m.soup);
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 11);
  const int stack = stackSizeFor(packed);
  const AssembledShader shader = assembleTraversal("cwbvh-groups", Storage::Tbo, Robustness::Fast, stack,
                                                   "#define SHARED_STACK_ENTRIES 1\n#define COMPUTE_LANES 64\n",
                                                   kLayoutCwbvh);
  GLuint program = 0;
  try {
    program = test::compileCompute(shader.source + kShortStackMain);
  } catch (const std::exception& e) {
    FAIL() << shader.mapLog(e.what());
  }
  const std::vector<glm::uvec4>* streams[3] = {&packed.nodes, &packed.triangles, &packed.attributes};
  GLuint buffers[3], textures[3];
  glCreateBuffers(3, buffers);
  glCreateTextures(GL_TEXTURE_BUFFER, 3, textures);
  for (GLuint unit = 0; unit < 3; ++unit) {
    glNamedBufferData(buffers[unit], GLsizeiptr(streams[unit]->size() * sizeof(glm::uvec4)), streams[unit]->data(),
                      GL_STATIC_DRAW);
    glTextureBuffer(textures[unit], GL_RGBA32UI, buffers[unit]);
    glBindTextureUnit(unit, textures[unit]);
  }
  glUseProgram(program);
  const char* names[3] = {"u_nodes", "u_triangles", "u_attributes"};
  for (int unit = 0; unit < 3; ++unit) glUniform1i(glGetUniformLocation(program, names[unit]), unit);
  std::vector<glm::vec4> in;
  for (const BatchRay& r : rays) {
    in.emplace_back(r.origin, r.tMin);
    in.emplace_back(r.dir, r.tMax);
  }
  const std::vector<glm::uvec4> out =
      test::dispatchCompute<glm::uvec4>(program, in, 2 * rays.size(), rays.size(), "short-stack dispatch");
  glDeleteTextures(3, textures);
  glDeleteBuffers(3, buffers);
  glDeleteProgram(program);
  const KernelInfo& k = findKernel(kLayoutCwbvh, "cwbvh-groups");
  size_t spilled = 0, hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    glsl::Counters c;
    glsl::MeshHit hit;
    const bool found = k.closest(Robustness::Fast)(packed, glsl::Ray{rays[i].origin, rays[i].dir}, rays[i].tMin,
                                                   rays[i].tMax, hit, c);
    ASSERT_EQ(out[2 * i].x != 0, found) << "ray " << i;
    ASSERT_EQ(out[2 * i].w, 0u) << "ray " << i << " overflowed";
    if (found) {
      ASSERT_EQ(int(out[2 * i].y), hit.tri) << "ray " << i;
      ASSERT_TRUE(nearlyEqual(std::bit_cast<float>(out[2 * i].z), hit.t)) << "ray " << i;  // as expectGlslEqualsMirror
    }
    ASSERT_EQ(out[2 * i + 1].x, c.nodeVisits) << "ray " << i;
    ASSERT_EQ(out[2 * i + 1].y, c.triTests) << "ray " << i;
    ASSERT_EQ(out[2 * i + 1].z, c.boxTests) << "ray " << i;
    // Each group pushed and popped is 16 stack bytes: more than one push, some entry went to the spill.
    spilled += c.stackBytes > 16u;
    hits += found;
  }
  EXPECT_GT(spilled, rays.size() / 20) << "too few rays pushed twice: the spill path is barely tested";
  EXPECT_GT(hits, rays.size() / 10);
}

// The slot order cwbvh-groups takes a group's bits in: the slots s ^ octant for s = 0, 1, ..., 7
// (findMSB over bits slot ^ (7 - octant): traversal/kernel_cwbvh_groups.hpp's helpers).
std::vector<uint32_t> groupsSlotOrder(const std::array<int, 8>& childOf, glm::vec3 dir) {
  namespace g = glsl::cwbvh_groups;
  const uint32_t octInv = 7u - g::cwbvhOctant(glsl::rayInverseDirection(dir));
  uint32_t mask = 0;
  for (uint32_t s = 0; s < 8; ++s)
    if (childOf[s] >= 0) mask |= 1u << g::cwbvhHitBit(s, octInv);
  std::vector<uint32_t> order;
  while (mask != 0) {
    const uint32_t bit = uint32_t(glm::findMSB(mask));
    mask &= ~(1u << bit);
    order.push_back(g::cwbvhSlotOfBit(bit, octInv));
  }
  return order;
}

// Two children spread along x: every ray with +x direction (whatever its y, z signs) takes the one at
// lower x first, every ray with -x direction the other; eight children at the cube's corners: each
// octant's ray takes first the corner it meets first (the one opposite its direction).
TEST(CwbvhGroups, SlotsByOctantGiveNearToFarOrder) {
  const std::array<int, 8> pair = cwbvhAssignSlots({{-1.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}}, glm::vec3(0.0f));
  for (uint32_t o = 0; o < 8; ++o) {
    const glm::vec3 dir((o & 1) ? -1.0f : 1.0f, (o & 2) ? -0.5f : 0.5f, (o & 4) ? -0.25f : 0.25f);
    const std::vector<uint32_t> order = groupsSlotOrder(pair, dir);
    ASSERT_EQ(order.size(), 2u);
    const std::vector<int> expected = dir.x > 0.0f ? std::vector<int>{0, 1} : std::vector<int>{1, 0};
    EXPECT_EQ(pair[order[0]], expected[0]) << "octant " << o;
    EXPECT_EQ(pair[order[1]], expected[1]) << "octant " << o;
  }
  std::vector<glm::vec3> corners;
  for (int i = 0; i < 8; ++i) corners.push_back({(i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f});
  const std::array<int, 8> cube = cwbvhAssignSlots(corners, glm::vec3(0.0f));
  for (uint32_t o = 0; o < 8; ++o) {
    const glm::vec3 dir((o & 1) ? -1.0f : 1.0f, (o & 2) ? -1.0f : 1.0f, (o & 4) ? -1.0f : 1.0f);
    const glm::vec3 first = corners[size_t(cube[groupsSlotOrder(cube, dir).front()])];
    EXPECT_EQ(first, -dir) << "octant " << o;
  }
  EXPECT_THROW(cwbvhAssignSlots({}, glm::vec3(0.0f)), std::invalid_argument);
}

// Through the kernel: eight clusters of four walls along x (one leaf each, all in the root node); a
// ray along +x meets every wall, and the first leaf it takes (by octant) is the nearest, whose hit
// culls every other leaf: exactly 4 triangle tests. Along -x the same from the other end. Fast and
// watertight tests (the plane test with two axes parallel to the ray, and the decoded boxes).
TEST(CwbvhGroups, ARayAlongXTakesTheNearestLeafFirst) {
  Mesh m;
  for (int c = 0; c < 8; ++c)
    for (int w = 0; w < 4; ++w) {
      const float x = 2.0f * float(c) + 0.1f * float(w);
      const uint32_t b = uint32_t(m.positions.size());
      m.positions.push_back({x, 0.0f, 0.0f});
      m.positions.push_back({x, 1.0f, 0.0f});
      m.positions.push_back({x, 0.0f, 1.0f});
      m.triangles.push_back({b, b + 1, b + 2});
    }
  MeshSceneOptions mo;
  mo.groundPlane = false;
  const TriangleSoup soup = gatherTriangles(makeMeshScene(m, mo));
  // A balanced binary tree over the eight clusters, made by hand (a builder may split a cluster).
  Bvh bvh;
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::function<uint32_t(uint32_t, uint32_t)> make = [&](uint32_t lo, uint32_t hi) {  // clusters lo..hi-1
    const uint32_t index = uint32_t(bvh.nodes.size());
    bvh.nodes.emplace_back();
    BvhNode n;
    if (hi - lo == 1) {
      n.first = 4 * lo;
      n.count = 4;
    } else {
      n.left = make(lo, (lo + hi) / 2);
      n.right = make((lo + hi) / 2, hi);
    }
    for (uint32_t t = 4 * lo; t < 4 * hi; ++t) n.bounds.grow(boxes[t]);
    bvh.nodes[index] = n;
    return index;
  };
  for (uint32_t t = 0; t < 32; ++t) bvh.primIndices.push_back(t);
  make(0, 8);
  const PackedBvh packed = packCwbvh(bvh, soup);
  const CwbvhNode root = unpackCwbvhNode(packed, 0);
  ASSERT_EQ(root.children, 8u) << "the premise: the root holds the eight clusters";
  for (uint32_t s = 0; s < 8; ++s) ASSERT_EQ(root.meta[s], 4u) << "the premise: one leaf of four walls per slot";
  const KernelInfo& k = findKernel("cwbvh", "cwbvh-groups");
  for (Robustness robust : {Robustness::Fast, Robustness::Watertight})
    for (float sign : {1.0f, -1.0f}) {
      SCOPED_TRACE(std::string(robustnessName(robust)) + (sign > 0.0f ? " +x" : " -x"));
      const glsl::Ray ray{{sign > 0.0f ? -1.0f : 20.0f, 0.25f, 0.25f}, {sign, 0.0f, 0.0f}};
      glsl::Counters c;
      glsl::MeshHit hit;
      ASSERT_TRUE(k.closest(robust)(packed, ray, 0.0f, 1e30f, hit, c));
      EXPECT_FLOAT_EQ(hit.t, sign > 0.0f ? 1.0f : 20.0f - 14.3f);
      EXPECT_EQ(c.triTests, 4u) << "only the nearest leaf tested";
      EXPECT_EQ(c.nodeVisits, 1u);
      EXPECT_EQ(c.boxTests, 9u) << "the root grid and eight slots";
    }
}

// A kernel of another layout is refused, naming cwbvh's kernel; cwbvh's default kernel is its own.
TEST(CwbvhKernels, MismatchedLayoutAndKernelAreRefused) {
  std::string msg = "no exception";
  try {
    findKernel("cwbvh", "bvh8-stack-ordered");
  } catch (const std::invalid_argument& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("walks layout bvh8, not cwbvh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cwbvh-stack-ordered"), std::string::npos) << msg;
  EXPECT_EQ(findKernel("cwbvh", "").name, "cwbvh-stack-ordered");
  EXPECT_EQ(findKernel("cwbvh-stack-ordered").layout, "cwbvh");
}

}  // namespace
}  // namespace bvhlab
