// The GLSL tracer: specialisation is invisible in the image, unused modules are absent from the
// source, the GLSL image matches the C++ mirror, cwbvh's image is v1's, and shader errors name module
// and line.
#include <cstdio>
#include <cstring>
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

// GLSL vs the C++ mirror, at 128x72 (llvmpipe, Mesa 22.3.6). Pixels may differ where float results differ
// in the last bits (transcendentals, FMA contraction) and round a shading value the other way. Measured:
// every shipped scene but worldmap differs in at most 77 of 9216 pixels, each by one step, mean <= 0.0029
// steps (report 0.00279, report-nomesh 0.00286, textures 0.00033, most 0.00007 or 0). Bounds ~10x:
// mean <= kMirrorMean and every pixel within kMirrorMax steps. The report scene also keeps the README's
// figure, mean <= 0.003 steps (0.003/255). A radiance scaled by 1.002 in main.glsl measures 0.10 (report)
// to 0.18 (sphere) steps: it fails these bounds and passed the former ones (mean 0.5, 99 % within 3).
// worldmap (measured mean 0.088, 1134 pixels differ, 36 by more than 3, max 13): the map is sampled by
// GL's bilinear filter in GLSL and by the mirror's own bilinear() in C++, at a direction from each side's
// atan/asin; where these round differently on the high-contrast HDR map a pixel moves by several steps
// (the cause was not narrowed further). Its bounds are ~2x what is measured.
constexpr double kMirrorMean = 0.03;  // steps; measured <= 0.00286
constexpr int kMirrorMax = 3;         // steps; measured 1
constexpr double kReportMean = 0.003;  // the README's "<= 0.003/255"; measured 0.00279
constexpr double kWorldMapMean = 0.2, kWorldMapWithin3 = 0.99;  // measured 0.088, 0.9961
constexpr int kWorldMapMax = 32;                                  // measured 13
TEST_P(SceneTest, GlslImageMatchesCppMirror) {
  if (needsData(GetParam())) BVHLAB_REQUIRE_DATASETS();
  auto p = prepare(GetParam());
  ShaderOptions o = optionsFor(*p);
  FrameOptions f = smallFrame(p->scene, kW, kH);
  Rendered gpu = renderGpu(*p, o, f);
  ReferenceImage cpu = renderReference(p->scene, p->data, p->packed, o, f);
  ImageDiff d = compareRgba(gpu.rgba, cpu.rgba);
  size_t differing = 0;
  for (size_t i = 0; i < gpu.rgba.size(); i += 4)
    differing += gpu.rgba[i] != cpu.rgba[i] || gpu.rgba[i + 1] != cpu.rgba[i + 1] || gpu.rgba[i + 2] != cpu.rgba[i + 2];
  std::printf("[ measured ] %-14s GLSL vs mirror: mean %.5f steps, within 3 %.5f, max %d, %zu of %d pixels differ\n",
              GetParam().stem().c_str(), d.meanAbs, d.within3, d.maxDiff, differing, kW * kH);
  const std::string name = GetParam().stem().string();
  if (name == "worldmap") {
    EXPECT_LE(d.meanAbs, kWorldMapMean) << GetParam();
    EXPECT_GE(d.within3, kWorldMapWithin3) << GetParam();
    EXPECT_LE(d.maxDiff, kWorldMapMax) << GetParam();
    return;
  }
  EXPECT_LE(d.meanAbs, kMirrorMean) << GetParam();
  EXPECT_LE(d.maxDiff, kMirrorMax) << GetParam();
  if (name == "report") {
    EXPECT_LE(d.meanAbs, kReportMean) << "the README quotes mean |diff| <= 0.003/255 on the report scene";
  }
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
  const ImageDiff m = compareRgba(report.rgba, cpu.rgba);
  std::printf("[ measured ] report branching, GLSL vs mirror: mean %.5f steps, max %d\n", m.meanAbs, m.maxDiff);
  EXPECT_LE(m.meanAbs, 0.0005);  // measured 0.00004 (one step in one channel of 9216 pixels)
  EXPECT_LE(m.maxDiff, kMirrorMax);
}

// cwbvh (8-wide compressed nodes, 8-bit conservative child boxes) and bvh2-cb (both child boxes in the
// parent) pack the same builder's tree, so the same triangles sit in their leaves as in v1's: every ray finds the same closest hit, and the images are
// byte-identical (the claim of docs/layouts.md#cwbvh). Checked on the report scene (analytic objects,
// reflection and refraction rays through the bunny) and on the bare bunny (`bvhlab render FILE`'s framing).
// Should a tie at equal distance ever resolve differently, the failure names the differing pixels.
TEST(Render, CwbvhAndBvh2cbImagesAreByteIdenticalToV1s) {
  BVHLAB_REQUIRE_DATASETS();
  for (const std::string which : {"report", "bunny"}) {
    SCOPED_TRACE(which);
    auto load = [&] {
      return which == "report" ? loadScene(sourceDir() / "datasets/scenes/report.toml")
                               : loadMeshScene(sourceDir() / "datasets/cache/meshes/bunny00.off");
    };
    const std::unique_ptr<PreparedScene> v1 = prepareScene(load(), "sah-binned", BuildOptions{}, "v1");
    const std::unique_ptr<PreparedScene> cw = prepareScene(load(), "sah-binned", BuildOptions{}, "cwbvh");
    const std::unique_ptr<PreparedScene> cb = prepareScene(load(), "sah-binned", BuildOptions{}, "bvh2-cb");
    ASSERT_EQ(cw->soup.size(), v1->soup.size());
    ASSERT_EQ(cb->soup.size(), v1->soup.size());
    ASSERT_GT(cw->soup.size(), 70000u) << "the bunny's triangles must be in the scene";
    const FrameOptions f = smallFrame(v1->scene, 160, 90);
    size_t meshPixels = 0;
    for (View view : {View::PrimId, View::Shaded}) {
      ShaderOptions o = optionsFor(*v1);
      o.view = view;
      o.countStats = view == View::PrimId;  // the primary hit ids: compared, and how much of the frame is mesh
      const Rendered a = renderGpu(*v1, o, f);
      if (o.countStats)
        for (size_t i = 0; i < a.rgba.size() / 4; ++i)
          meshPixels += statsPrimaryIdPlusOne(a.stats[i]) > v1->data.objects.size();  // ids past the analytic objects
      for (const PreparedScene* other : {cw.get(), cb.get()})
      for (const KernelInfo& cwKernel : kernelsFor(other->packed.layout)) {  // every cwbvh and bvh2-cb kernel
        SCOPED_TRACE(cwKernel.name);
        ShaderOptions oc = o;
        oc.layout = other->packed.layout;
        oc.kernel = cwKernel.name;
        oc.bvhStackSize = stackSizeFor(other->packed);
        const Rendered b = renderGpu(*other, oc, f);
        ASSERT_EQ(a.rgba.size(), b.rgba.size());
        size_t differing = 0;
        for (size_t i = 0; i < a.rgba.size() / 4; ++i) {
          bool differs = std::memcmp(&a.rgba[4 * i], &b.rgba[4 * i], 4) != 0;
          if (o.countStats) differs |= statsPrimaryIdPlusOne(a.stats[i]) != statsPrimaryIdPlusOne(b.stats[i]);
          if (differs && ++differing <= 3)
            ADD_FAILURE() << viewName(view) << " pixel (" << i % 160 << "," << i / 160 << ") differs between v1 and " << oc.layout;
        }
        std::printf("[ measured ] %s, %s view, %s, 160x90: %zu of %zu pixels differ between v1 and %s\n",
                    which.c_str(), viewName(view), cwKernel.name.c_str(), differing, a.rgba.size() / 4,
                    oc.layout.c_str());
        EXPECT_EQ(differing, 0u) << viewName(view);
      }
    }
    EXPECT_GT(meshPixels, size_t(160 * 90 / 50)) << "the bunny must be in view for the comparison to mean much";
  }
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
  std::printf("[ measured ] ssaa 2x2, GLSL vs mirror: mean %.5f steps, within 3 %.5f, max %d\n", mirror.meanAbs,
              mirror.within3, mirror.maxDiff);
  EXPECT_LE(mirror.meanAbs, 0.003);  // measured 0.00025
  EXPECT_LE(mirror.maxDiff, kMirrorMax);
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
