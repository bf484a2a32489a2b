// The GLSL tracer: specialisation is invisible in the image, unused modules are absent from the
// source, the GLSL image matches the C++ mirror, and shader errors name module and line.
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>

#include "render_fixture.hpp"

namespace bvhlab::test {
namespace {

constexpr int kW = 128, kH = 72;  // small: every shipped scene twice on llvmpipe in seconds

class SceneTest : public ::testing::TestWithParam<std::filesystem::path> {};

std::string sceneName(const ::testing::TestParamInfo<std::filesystem::path>& info) {
  std::string s = info.param.stem().string();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

std::unique_ptr<PreparedScene> prepare(const std::filesystem::path& path) {
  return prepareScene(loadScene(path), "sah-binned", BuildOptions{});
}

ShaderOptions optionsFor(const PreparedScene& p) {
  ShaderOptions o;
  o.maxDepth = p.scene.settings.maxDepth;
  o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, p.packed.depth));
  return o;
}

bool needsData(const std::filesystem::path& scene) {
  std::ifstream in(scene);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  return text.find("cache/") != std::string::npos;
}

TEST_P(SceneTest, SpecialisedImageEqualsUberImage) {
  if (needsData(GetParam())) BVHLAB_REQUIRE_DATASETS();
  auto p = prepare(GetParam());
  ShaderOptions o = optionsFor(*p);
  FrameOptions f = smallFrame(p->scene, kW, kH);
  Rendered special = renderGpu(*p, o, f);
  o.uber = true;
  Rendered uber = renderGpu(*p, o, f);
  ImageDiff d = compareRgba(special.rgba, uber.rgba);
  EXPECT_EQ(d.maxDiff, 0) << "mean " << d.meanAbs << ", within 3: " << d.within3;
}

TEST_P(SceneTest, SpecialisedSourceLacksUnusedModules) {
  if (needsData(GetParam())) BVHLAB_REQUIRE_DATASETS();
  auto p = prepare(GetParam());
  SceneFeatures f = analyzeScene(p->scene);
  AssembledShader s = assembleTracer(f, optionsFor(*p));
  const char* kindModules[6] = {"prim_sphere.glsl", "prim_box.glsl", "prim_cylinder.glsl",
                                "prim_cone.glsl", "prim_torus.glsl", "prim_plane.glsl"};
  const char* kindFunctions[6] = {"bool intersectSphere(", "bool intersectBox(", "bool intersectCylinder(",
                                  "bool intersectCone(", "bool intersectTorus(", "bool intersectPlane("};
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(s.hasModule(kindModules[k]), f.kinds[k]) << kindModules[k];
    EXPECT_EQ(s.source.find(kindFunctions[k]) != std::string::npos, f.kinds[k]) << kindFunctions[k];
  }
  const ShaderOptions used = optionsFor(*p);
  EXPECT_EQ(s.hasModule(used.robust.triangle == TriangleTest::Watertight ? "ray_triangle_watertight.glsl"
                                                                          : "ray_triangle.glsl"),
            f.mesh);
  EXPECT_FALSE(s.hasModule(used.robust.triangle == TriangleTest::Watertight ? "ray_triangle.glsl"
                                                                             : "ray_triangle_watertight.glsl"));
  EXPECT_EQ(s.source.find("bool traceClosest(") != std::string::npos, f.mesh);
  EXPECT_EQ(s.hasModule("textures.glsl"), f.textures);
  EXPECT_EQ(s.hasModule("world_map.glsl"), f.world == WorldKind::Map);
  EXPECT_EQ(s.hasModule("world_sky.glsl"), f.world == WorldKind::Sky);
  EXPECT_EQ(s.source.find("#define HAS_REFRACTION") != std::string::npos, f.refraction);
  EXPECT_EQ(s.source.find("#define HAS_SHADOWS") != std::string::npos, f.shadows);
  if (!f.reflection && !f.refraction) {
    EXPECT_NE(s.source.find("#define MAX_DEPTH 1\n"), std::string::npos);
  }
  AssembledShader uber = assembleTracer(f, [&] { ShaderOptions o = optionsFor(*p); o.uber = true; return o; }());
  EXPECT_GE(uber.source.size(), s.source.size());
}

// GLSL vs the C++ mirror. Tolerance: mean |diff| < 0.5/255 and >= 99% of pixels within 3/255.
// Pixels may differ where float results differ in the last bits (transcendentals, FMA contraction)
// and flip a decision: a silhouette pixel, a shadow boundary, a texture seam.
TEST_P(SceneTest, GlslImageMatchesCppMirror) {
  if (needsData(GetParam())) BVHLAB_REQUIRE_DATASETS();
  auto p = prepare(GetParam());
  ShaderOptions o = optionsFor(*p);
  FrameOptions f = smallFrame(p->scene, kW, kH);
  Rendered gpu = renderGpu(*p, o, f);
  ReferenceImage cpu = renderReference(p->scene, p->data, p->packed, o, f);
  ImageDiff d = compareRgba(gpu.rgba, cpu.rgba);
  EXPECT_LT(d.meanAbs, 0.5) << GetParam();
  EXPECT_GE(d.within3, 0.99) << GetParam() << " max diff " << d.maxDiff;
}

INSTANTIATE_TEST_SUITE_P(Shipped, SceneTest, ::testing::ValuesIn(shippedScenes()), sceneName);

// Report branching (Algorithm 1's compromise) and full branching differ only in what a path does after
// it meets a surface that both reflects and refracts. In refraction.toml those are the glass sphere and
// the glass block; the floor neither reflects nor refracts, so a pixel whose primary ray lands on the
// floor or in the sky is shaded by the same rays in both modes and must be identical. The glass mask is
// derived from the primary hit id (PrimId view's stats target) and the hit object's material.
// Dilation by one pixel: the PrimId view is a separately compiled shader, and where its primary hit
// rounds differently at a glass silhouette (FMA contraction, a different instruction order) a pixel on
// the edge could be glass in one and floor in the other; nothing else can move a difference further.
TEST(Render, ReportBranchingDiffersFromFullOnlyWhereGlassIs) {
  auto p = prepare(sourceDir() / "datasets/scenes/refraction.toml");
  ShaderOptions o = optionsFor(*p);
  FrameOptions f = smallFrame(p->scene, kW, kH);
  Rendered full = renderGpu(*p, o, f);
  ShaderOptions ro = o;
  ro.branching = Branching::Report;
  Rendered report = renderGpu(*p, ro, f);
  ShaderOptions io = o;
  io.view = View::PrimId;
  io.countStats = true;
  Rendered ids = renderGpu(*p, io, f);
  ASSERT_EQ(ids.stats.size(), size_t(kW * kH));

  std::vector<char> glass(kW * kH, 0), nearGlass(kW * kH, 0);
  for (int i = 0; i < kW * kH; ++i) {
    const uint32_t id = statsPrimaryIdPlusOne(ids.stats[i]);
    if (id == 0 || id > p->data.objects.size()) continue;  // sky (no mesh in this scene)
    const MaterialData& m = p->data.materials.at(p->data.objects[id - 1].info.y);
    glass[i] = m.optics.y > 0.0f;  // transparent: reflects and refracts
  }
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx >= 0 && xx < kW && yy >= 0 && yy < kH && glass[yy * kW + xx]) nearGlass[y * kW + x] = 1;
        }
  int glassPixels = 0, glassDiffering = 0, ringDiffering = 0, outsideDiffering = 0;
  for (int i = 0; i < kW * kH; ++i) {
    bool differs = false;
    for (int c = 0; c < 3; ++c) differs |= full.rgba[4 * i + c] != report.rgba[4 * i + c];
    glassPixels += glass[i];
    if (glass[i]) glassDiffering += differs;
    else if (nearGlass[i]) ringDiffering += differs;
    else if (differs && ++outsideDiffering <= 3)
      ADD_FAILURE() << "pixel (" << i % kW << "," << i / kW << ") differs but its primary ray misses the glass";
  }
  EXPECT_EQ(outsideDiffering, 0) << "report branching changed pixels that never meet glass";
  ASSERT_GT(glassPixels, kW * kH / 20) << "the glass must be in view";
  // Inside the glass both Fresnel branches carry weight almost everywhere; Algorithm 1 cuts the
  // reflected one after one bounce, which changes most glass pixels (measured: 1186 of 1295, 92%, at 128x72).
  EXPECT_GT(glassDiffering, glassPixels / 2) << glassDiffering << " of " << glassPixels << " glass pixels differ";
  std::printf("[ measured ] report vs full branching: %d of %d glass pixels differ, %d in the 1-pixel ring, "
              "%d elsewhere\n", glassDiffering, glassPixels, ringDiffering, outsideDiffering);
  ReferenceImage cpu = renderReference(p->scene, p->data, p->packed, ro, f);
  EXPECT_LT(compareRgba(report.rgba, cpu.rgba).meanAbs, 0.5);
}

TEST(Render, SsaaMatchesMirrorAndConvergesTowardsTheReference) {
  auto p = prepare(sourceDir() / "datasets/scenes/textures.toml");
  ShaderOptions o = optionsFor(*p);
  FrameOptions f = smallFrame(p->scene, kW, kH);
  Rendered none = renderGpu(*p, o, f);
  o.ssaaGrid = 2;
  Rendered ssaa4 = renderGpu(*p, o, f);
  ReferenceImage cpu4 = renderReference(p->scene, p->data, p->packed, o, f);
  o.ssaaGrid = 4;
  Rendered ssaa16 = renderGpu(*p, o, f);
  ImageDiff mirror = compareRgba(ssaa4.rgba, cpu4.rgba);
  EXPECT_LT(mirror.meanAbs, 0.5);
  EXPECT_GE(mirror.within3, 0.99);
  double errNone = compareRgba(none.rgba, ssaa16.rgba).meanAbs;
  double err4 = compareRgba(ssaa4.rgba, ssaa16.rgba).meanAbs;
  EXPECT_LT(err4, 0.7 * errNone) << "none " << errNone << " vs ssaa4 " << err4;
}

TEST(Render, DebugViewsBlackOnMissNeverBlackOnHit) {
  auto p = prepare(sourceDir() / "datasets/scenes/sphere.toml");
  ShaderOptions o = optionsFor(*p);
  FrameOptions f = smallFrame(p->scene, kW, kH);
  o.view = View::PrimId;
  o.countStats = true;
  Rendered ids = renderGpu(*p, o, f);
  for (View v : {View::Normal, View::Depth, View::PrimId}) {
    o.view = v;
    o.countStats = false;
    Rendered r = renderGpu(*p, o, f);
    size_t hits = 0;
    for (size_t i = 0; i < ids.stats.size(); ++i) {
      bool hit = ids.stats[i].w != 0;
      hits += hit;
      int sum = r.rgba[4 * i] + r.rgba[4 * i + 1] + r.rgba[4 * i + 2];
      if (hit) EXPECT_GT(sum, 0) << viewName(v) << " pixel " << i;
      else EXPECT_EQ(sum, 0) << viewName(v) << " pixel " << i;
    }
    EXPECT_GT(hits, 0u);
  }
}

TEST(Render, CompileErrorNamesModuleAndLine) {
  glContext();
  auto p = prepare(sourceDir() / "datasets/scenes/sphere.toml");
  AssembledShader s = assembleTracer(analyzeScene(p->scene), optionsFor(*p));
  // Break line 3 of shade.glsl.
  int target = 0;
  for (const ShaderModule& m : s.modules)
    if (m.name == "shade.glsl") target = m.firstLine + 2;
  ASSERT_GT(target, 0);
  std::string broken;
  std::istringstream in(s.source);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) broken += (n == target ? "this is not glsl;" : line) + "\n";
  s.source = broken;
  try {
    compileFullscreenProgram(s);
    FAIL() << "a broken shader compiled";
  } catch (const ShaderError& e) {
    EXPECT_NE(std::string(e.what()).find("shade.glsl:3"), std::string::npos) << e.what();
  }
}

TEST(Render, LogMappingHandlesMesaAndNvidiaFormats) {
  AssembledShader s;
  s.modules = {{"<defines>", 1, 3}, {"a.glsl", 4, 10}, {"b.glsl", 14, 5}};
  EXPECT_EQ(s.mapLog("0:15(7): error: bad\n"), "b.glsl:2: error: bad\n");
  EXPECT_EQ(s.mapLog("0(4) : error C0000: x\n"), "a.glsl:1: error C0000: x\n");
  EXPECT_EQ(s.mapLog("plain\n"), "plain\n");
}

}  // namespace
}  // namespace bvhlab::test
