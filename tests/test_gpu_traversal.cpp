// Every builder x every kernel through the real GLSL: per-pixel primary hit ids equal the C++
// mirror's, and so do the in-shader counters of every pixel (node visits, triangle tests, mesh rays, box
// tests), in the primid view and in the shaded view with its secondary rays. Measured on the bunny at
// 96x54: 0 pixels differ in any of the 30 combinations (the earlier check compared only the frame's
// totals, within 0.5 %), so a single ray walked differently by the GLSL fails.
#include "layout/layouts.hpp"
#include "render_fixture.hpp"

namespace bvhlab::test {
namespace {

struct Combo {
  std::string builder, kernel;
  Storage storage;
};

std::vector<Combo> combos() {
  std::vector<Combo> out;
  for (const BuilderInfo& b : builders())
    for (const KernelInfo& k : kernels()) out.push_back({b.name, k.name, Storage::Tbo});
  for (const KernelInfo& k : kernels()) out.push_back({"sah-binned", k.name, Storage::Tex2D});
  for (const KernelInfo& k : kernels()) out.push_back({"sah-binned", k.name, Storage::Ssbo});
  return out;
}

class GpuTraversal : public ::testing::TestWithParam<Combo> {};

const PreparedScene& bunny(const std::string& builder) {
  static std::map<std::string, std::unique_ptr<PreparedScene>> cache;
  auto& p = cache[builder];
  if (!p) p = prepareScene(loadMeshScene(sourceDir() / "datasets/cache/meshes/bunny00.off"), builder, BuildOptions{});
  return *p;
}

TEST_P(GpuTraversal, HitIdsAndCountsEqualTheMirror) {
  BVHLAB_REQUIRE_DATASETS();
  const Combo& c = GetParam();
  const PreparedScene& p = bunny(c.builder);
  ShaderOptions o;
  o.kernel = c.kernel;
  o.storage = c.storage;
  o.bvhStackSize = stackSizeFor(p.packed.depth);
  o.countStats = true;
  FrameOptions f = smallFrame(p.scene, 96, 54);
  for (View view : {View::PrimId, View::Shaded}) {
    o.view = view;
    Rendered gpu = renderGpu(p, o, f);
    ReferenceImage cpu = renderReference(p.scene, p.data, p.packed, o, f);
    ASSERT_EQ(gpu.stats.size(), cpu.stats.size());
    ASSERT_EQ(gpu.boxTests.size(), cpu.boxTests.size());
    size_t idMismatch = 0, hits = 0, countsDiffer = 0, overflow = 0;
    for (size_t i = 0; i < gpu.stats.size(); ++i) {
      idMismatch += gpu.stats[i].w != cpu.stats[i].w;
      hits += gpu.stats[i].w != 0;
      const bool differs = gpu.stats[i].x != cpu.stats[i].x || gpu.stats[i].y != cpu.stats[i].y ||
                           gpu.stats[i].z != cpu.stats[i].z || gpu.boxTests[i] != cpu.boxTests[i];
      countsDiffer += differs;
      overflow += gpu.stats[i].z >> 31;
      if (differs && countsDiffer <= 3)
        ADD_FAILURE() << viewName(view) << " pixel " << i << ": GLSL visits/tests/rays/boxes " << gpu.stats[i].x << "/"
                      << gpu.stats[i].y << "/" << gpu.stats[i].z << "/" << gpu.boxTests[i] << ", mirror "
                      << cpu.stats[i].x << "/" << cpu.stats[i].y << "/" << cpu.stats[i].z << "/" << cpu.boxTests[i];
    }
    std::printf("[ measured ] %s: %zu of %zu pixels' counters differ from the mirror's\n", viewName(view), countsDiffer,
                gpu.stats.size());
    EXPECT_EQ(overflow, 0u) << "stack overflow";
    if (view == View::PrimId) {
      EXPECT_GT(hits, gpu.stats.size() / 10) << "the bunny should fill part of the view";
      EXPECT_EQ(idMismatch, 0u);
    }
    EXPECT_EQ(countsDiffer, 0u) << viewName(view);
  }
}

// Box tests per pixel (main.glsl's o_boxTests, render --json's box_tests_per_ray) on every layout's
// kernels: the GLSL frame's counts equal the mirror's pixel for pixel in the primid view (no
// secondary rays, so no offset rounding to tell the two apart), and a wide node's visit tests several
// boxes (cwbvh, bvh4, bvh8: box tests > visits, where v1 tests at most one box per visit).
TEST(GpuLayouts, BoxTestsPerPixelEqualTheMirrorOnEveryLayout) {
  BVHLAB_REQUIRE_DATASETS();
  Scene scene = loadMeshScene(sourceDir() / "datasets/cache/meshes/bunny00.off");
  for (const LayoutInfo& l : layouts()) {
    const std::unique_ptr<PreparedScene> p = prepareScene(Scene(scene), "sah-binned", BuildOptions{}, l.name);
    for (const KernelInfo& k : kernelsFor(l.name)) {  // every kernel of the layout
      SCOPED_TRACE(l.name + " / " + k.name);
      ShaderOptions o;
      o.layout = l.name;
      o.kernel = k.name;
      o.bvhStackSize = stackSizeFor(p->packed);
      o.countStats = true;
      o.view = View::PrimId;
      const FrameOptions f = smallFrame(p->scene, 64, 36);
      const Rendered gpu = renderGpu(*p, o, f);
      const ReferenceImage cpu = renderReference(p->scene, p->data, p->packed, o, f);
      ASSERT_EQ(gpu.boxTests.size(), cpu.boxTests.size());
      size_t differ = 0;
      uint64_t boxes = 0, visits = 0;
      for (size_t i = 0; i < gpu.boxTests.size(); ++i) {
        differ += gpu.boxTests[i] != cpu.boxTests[i];
        boxes += gpu.boxTests[i];
        visits += gpu.stats[i].x;
      }
      EXPECT_EQ(differ, 0u);
      EXPECT_GT(boxes, 0u);
      if (l.name == "bvh4" || l.name == "bvh8" || l.name == "cwbvh") {
        EXPECT_GT(boxes, 2 * visits);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllCombos, GpuTraversal, ::testing::ValuesIn(combos()), [](const auto& info) {
  std::string s = info.param.builder + "_" + info.param.kernel + "_" + storageName(info.param.storage);
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
});

}  // namespace
}  // namespace bvhlab::test
