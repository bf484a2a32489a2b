// Layouts as an axis: the registry, the bvh2-cb packer's invariants, every builder x layout
// x kernel of that layout against brute force, the bvh2-cb GLSL kernel against its C++ mirror per ray
// (answer and counters), and the refusal of a kernel that walks another layout.
#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "builders/builder.hpp"
#include "cli_run.hpp"
#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "layout/layouts.hpp"
#include "layout_test_util.hpp"
#include "render/gl_context.hpp"
#include "render/prepared_scene.hpp"
#include "render/ray_tracer_gl.hpp"
#include "shaders/assemble.hpp"
#include "traversal/intersectors.hpp"
#include "traversal/kernels.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

using namespace layouttest;

TEST(Layouts, RegistryNamesV1FirstAndEveryKernelWalksItsLayout) {
  ASSERT_GE(layouts().size(), 2u);
  EXPECT_EQ(layouts().front().name, kDefaultLayout);
  for (const LayoutInfo& l : layouts()) {
    EXPECT_EQ(&findLayout(l.name), &l);
    EXPECT_FALSE(kernelsFor(l.name).empty()) << l.name;
    EXPECT_EQ(findKernel(l.name, "").name, l.defaultKernel);
    for (const KernelInfo& k : kernelsFor(l.name)) EXPECT_EQ(k.layout, l.name) << k.name;
  }
  EXPECT_EQ(&kernelsFor("v1"), &kernels());  // v1's table is the one every v1 test iterates
  size_t total = 0;
  for (const LayoutInfo& l : layouts()) total += kernelsFor(l.name).size();
  EXPECT_EQ(allKernels().size(), total);
}

TEST(Layouts, MismatchedLayoutAndKernelAreRefusedNamingTheValidKernels) {
  const auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  std::string m = message([] { findKernel("bvh2-cb", "stack-ordered"); });
  EXPECT_NE(m.find("bvh2cb-stack-ordered"), std::string::npos) << m;
  EXPECT_NE(m.find("walks layout v1"), std::string::npos) << m;
  m = message([] { findKernel("v1", "bvh2cb-stack-ordered"); });
  for (const KernelInfo& k : kernels()) EXPECT_NE(m.find(k.name), std::string::npos) << m;
  m = message([] { findKernel("bvh2-cb", "nope"); });
  EXPECT_NE(m.find("bvh2cb-stack-ordered"), std::string::npos) << m;
  m = message([] { findLayout("bvh9"); });
  for (const LayoutInfo& l : layouts()) EXPECT_NE(m.find(l.name), std::string::npos) << m;
  m = message([] { assembleRayTracer("stackless", Storage::Tbo, Robustness::Watertight, 8, false, false, "bvh2-cb"); });
  EXPECT_NE(m.find("bvh2cb-stack-ordered"), std::string::npos) << m;
  ShaderOptions so;
  so.layout = "bvh2-cb";  // kernel stays stack-ordered (v1's)
  SceneFeatures f;
  f.mesh = true;
  m = message([&] { assembleTracer(f, so); });
  EXPECT_NE(m.find("bvh2cb-stack-ordered"), std::string::npos) << m;
}

// Boxes contain their children, every record is reached once, leaf ranges lie in the triangle stream
// and cover it exactly once, every input triangle is referenced, and the triangle streams are v1's.
void checkBvh2cb(const PackedBvh& p, const PackedBvh& v1, const TriangleSoup& soup) {
  ASSERT_EQ(p.layout, "bvh2-cb");
  EXPECT_EQ(p.triangles, v1.triangles);
  EXPECT_EQ(p.attributes, v1.attributes);
  EXPECT_EQ(p.depth, v1.depth);
  const uint32_t records = bvh2cbRecordCount(p), triangles = uint32_t(p.triangles.size() / kTriangleTexels);
  ASSERT_GE(records, 1u);
  std::vector<int> reached(records, 0), covered(triangles, 0);
  std::set<uint32_t> prims;
  // A reference-splitting builder (sbvh) gives a straddling triangle several leaves, each box bounding
  // only the triangle's part on its side: there the bounds of all its leaves must contain it.
  std::vector<Aabb> leafUnion(soup.size());
  uint32_t maxDepth = 0;
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};  // (record, depth of its node)
  reached[0] = 1;
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    const Bvh2cbRecord r = unpackBvh2cbRecord(p, index);
    for (int c = 0; c < 2; ++c) {
      const Bvh2cbSlot& s = r.child[c];
      const Aabb box{s.bmin, s.bmax};
      if (s.isInner()) {
        ASSERT_LT(s.link, records);
        if (c == 0) {
          EXPECT_EQ(s.link, index + 1) << "child A's record follows its parent's";
        }
        ASSERT_EQ(reached[s.link]++, 0) << "record " << s.link << " reached twice";
        const Bvh2cbRecord child = unpackBvh2cbRecord(p, s.link);
        for (const Bvh2cbSlot& g : child.child) EXPECT_TRUE(box.contains(Aabb{g.bmin, g.bmax})) << "record " << s.link;
        stack.push_back({s.link, depth + 1});
        continue;
      }
      maxDepth = std::max(maxDepth, depth + 1);
      ASSERT_LE(s.count, kMaxLeafSize);
      ASSERT_LE(uint64_t(s.link) + s.count, triangles);
      if (s.count == 0) {
        EXPECT_TRUE(index == 0 && c == 1 && records == 1) << "an empty slot only in a single-leaf tree";
        continue;
      }
      for (uint32_t k = 0; k < s.count; ++k) {
        const uint32_t tri = s.link + k;
        covered[tri]++;
        const uint32_t prim = p.triangles[3 * tri].w;
        ASSERT_LT(prim, soup.size());
        prims.insert(prim);
        leafUnion[prim].grow(box);
      }
    }
  }
  EXPECT_EQ(std::count(reached.begin(), reached.end(), 1), long(records)) << "unreachable records";
  EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), long(triangles)) << "leaf ranges must cover the stream once";
  EXPECT_EQ(prims.size(), soup.size()) << "every input triangle reachable";
  const std::vector<Aabb> triBoxes = triangleBoxes(soup);
  for (uint32_t t = 0; t < soup.size(); ++t)
    EXPECT_TRUE(leafUnion[t].contains(triBoxes[t])) << "triangle " << t << " outside its leaves' boxes";
  if (records > 1) {
    EXPECT_EQ(maxDepth, p.depth);
  }
  EXPECT_EQ(p.nodes.size(), size_t(kBvh2cbRecordTexels) * records);
}

TEST(Bvh2cbPacker, EveryBuildersTreeKeepsTheInvariants) {
  for (const TestMesh& m : testMeshes())
    for (const BuilderInfo& b : builders()) {
      SCOPED_TRACE(m.name + " / " + b.name);
      const Bvh bvh = build(b.name, m.soup);
      const PackedBvh v1 = packBvh(bvh, m.soup);
      const PackedBvh cb = packBvh2cb(bvh, m.soup);
      checkBvh2cb(cb, v1, m.soup);
      // Same bytes of nodes less one v1 node: 64 (L - 1) against 32 (2L - 1).
      EXPECT_EQ(cb.nodes.size() * 16 + 32, v1.nodes.size() * 16);
    }
  const TriangleSoup few = firstTriangles(testMeshes()[1].soup, 5);
  const PackedBvh cb = packBvh2cb(singleLeaf(few), few);
  checkBvh2cb(cb, packBvh(singleLeaf(few), few), few);
  EXPECT_EQ(bvh2cbRecordCount(cb), 1u);
  EXPECT_THROW(unpackNode(cb, 0), std::invalid_argument);
  EXPECT_THROW(unpackBvh2cbRecord(cb, 1), std::out_of_range);
}

// Every builder x layout x kernel of that layout (watertight tests) finds brute force's closest hit
// (the same t; another triangle only at the same t) and its any-hit answer, on every ray; PLOC with
// an SAH top (--ploc-top-down 4) as one more builder.
TEST(LayoutKernels, EveryBuilderLayoutAndKernelFindTheBruteForceHits) {
  for (const TestMesh& m : testMeshes()) {
    const std::vector<BatchRay> rays = testRays(m.soup, 600, 5);
    std::vector<BatchHit> expected;
    for (const BatchRay& r : rays) expected.push_back(bruteForce(m.soup, r));
    size_t hits = 0;
    for (const BatchHit& h : expected) hits += h.hit;
    EXPECT_GT(hits, rays.size() / 5) << m.name;
    std::vector<std::pair<std::string, Bvh>> trees;
    for (const BuilderInfo& b : builders()) trees.emplace_back(b.name, build(b.name, m.soup));
    BuildOptions topDown;
    topDown.plocTopDown = 4;
    trees.emplace_back("ploc[top-down=4]", build("ploc", m.soup, topDown));
    for (const auto& [builder, bvh] : trees)
      for (const LayoutInfo& l : layouts()) {
        const PackedBvh packed = l.pack(bvh, m.soup);
        for (const KernelInfo& k : kernelsFor(l.name)) {
          SCOPED_TRACE(m.name + " / " + builder + " / " + l.name + " / " + k.name);
          expectBruteForceHits(packed, k, Robustness::Watertight, rays, expected);
        }
      }
  }
}

// The hard-case suite in watertight mode on bvh2-cb: no ray that must hit leaks, and every ray is
// answered as v1's stack-ordered answers it on the same tree (expectHardCasesAnsweredAsV1,
// layout_test_util.hpp; the wide layouts and cwbvh have the same test beside their packers).
TEST(LayoutKernels, Bvh2cbHardCasesLeakNothingInWatertightMode) {
  EXPECT_GT(expectHardCasesAnsweredAsV1("bvh2-cb"), 100u);
}

// Every bvh2-cb GLSL kernel gives its C++ mirror's answer and counters (box tests too) per ray, closest and any
// hit, on a builder's tree and on a tree whose root is a leaf (bvh2cb-aila-laine through the compute path's
// persistent threads); v1's kernels alongside as a control.
TEST(LayoutKernelsGlsl, EqualTheMirrorPerRay) {
  auto ctx = contextOrNull();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const TestMesh& m = testMeshes()[1];
  const TriangleSoup few = firstTriangles(m.soup, 7);
  struct Case {
    std::string name;
    PackedBvh packed;
    std::vector<BatchRay> rays;
    Storage storage = Storage::Tbo;
  };
  std::vector<Case> cases;
  const Bvh tree = build("sah-binned", m.soup);
  cases.push_back({"soup/bvh2-cb", packBvh2cb(tree, m.soup), testRays(m.soup, 1200, 11)});
  cases.push_back({"soup/bvh2-cb/ssbo", packBvh2cb(tree, m.soup), testRays(m.soup, 1200, 11), Storage::Ssbo});
  cases.push_back({"soup/v1", packBvh(tree, m.soup), testRays(m.soup, 1200, 11)});
  cases.push_back({"single-leaf/bvh2-cb", packBvh2cb(singleLeaf(few), few), testRays(few, 400, 12)});
  for (const Case& cs : cases)
    for (bool anyHit : {false, true})
      for (Robustness robust : {Robustness::Watertight, Robustness::Fast}) {
        if (cs.packed.layout == "v1" && robust == Robustness::Fast) continue;  // test_trace covers v1
        SCOPED_TRACE(cs.name + (anyHit ? " any" : " closest") + " / " + robustnessName(robust));
        // expectGlslEqualsMirror (layout_test_util.hpp): answer, visits, triangle and box tests per ray.
        for (const KernelInfo& k : kernelsFor(cs.packed.layout)) {  // bvh2-cb: stack-ordered and aila-laine
          SCOPED_TRACE(k.name);
          const size_t found = expectGlslEqualsMirror(cs.packed, k, cs.rays, anyHit, robust, cs.storage);
          EXPECT_GT(found, cs.rays.size() / 10) << "too few hits for the comparison to mean much";
        }
      }
}

// The renderer refuses a shader assembled for another layout than the tree's, and renders a bvh2-cb
// tree through prepareScene's layout.
TEST(LayoutKernelsGlsl, PreparedSceneCarriesTheLayout) {
  MeshSceneOptions mo;
  mo.groundPlane = false;
  auto p = prepareScene(makeMeshScene(makeUvSphere(16, 8), mo), "sah-binned", BuildOptions{}, "bvh2-cb");
  EXPECT_EQ(p->packed.layout, "bvh2-cb");
  EXPECT_EQ(p->stats.bytes, p->packed.bytes());
  EXPECT_THROW(prepareScene(makeMeshScene(makeUvSphere(8, 4), mo), "sah-binned", BuildOptions{}, "v9"),
               std::invalid_argument);
}

// The command line: `layouts` lists each layout with its kernels; a kernel of another layout is refused
// before the input is read; build and render report the layout and bytes per triangle.
TEST(LayoutCli, ListsRefusesAndReports) {
  using clitest::run;
  clitest::Result r = run("layouts");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("bvh2-cb"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("bvh2cb-stack-ordered (default)"), std::string::npos) << r.out;
  r = run("render /no/such/mesh.off --layout bvh2-cb --kernel stackless");
  EXPECT_EQ(r.code, 2);  // a usage error
  EXPECT_NE(r.err.find("kernels for layout bvh2-cb: bvh2cb-stack-ordered"), std::string::npos) << r.err;
  r = run("trace /no/such/mesh.off --layout nope");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("valid layouts: v1 bvh2-cb"), std::string::npos) << r.err;

  const std::filesystem::path mesh = clitest::writeTemp("tetra.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                                        "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  nlohmann::json v1, cb;
  for (auto [layout, out] : {std::pair{"v1", &v1}, std::pair{"bvh2-cb", &cb}}) {
    r = run("build --mesh " + mesh.string() + " --layout " + layout + " --leaf-size 1 --json");
    ASSERT_EQ(r.code, 0) << r.err;
    *out = nlohmann::json::parse(r.out);
    EXPECT_EQ((*out)["layout"], layout);
    EXPECT_DOUBLE_EQ((*out)["bytes_per_triangle"].get<double>(), (*out)["bytes"].get<double>() / 4.0);
  }
  // 4 leaves: v1 stores 7 nodes of 32 bytes, bvh2-cb 3 records of 64; the triangle streams are equal.
  EXPECT_EQ(v1["bytes"].get<int>() - cb["bytes"].get<int>(), 7 * 32 - 3 * 64);
  EXPECT_NE(v1["tree_hash"], cb["tree_hash"]);
  r = run("render " + mesh.string() + " --layout bvh2-cb --leaf-size 1 --width 32 --height 18 --frames 1 --warmup 0 --json");
  if (r.code == 0) {  // needs a GL context
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["layout"], "bvh2-cb");
    EXPECT_EQ(j["kernel"], "bvh2cb-stack-ordered");
    EXPECT_EQ(j["bytes"], cb["bytes"]);
    EXPECT_GT(j["node_visits_per_ray"].get<double>(), 0.0);
  }
}

}  // namespace
}  // namespace bvhlab
