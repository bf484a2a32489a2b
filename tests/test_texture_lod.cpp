// Texture level of detail by ray cones (shaders/texture_lod.glsl, --texture-lod): the default leaves
// the tracer as it was, the C++ mirror picks the GLSL's level per pixel, the cone widens at a curved
// mirror by the amount the curvature predicts, bad option values are refused.
#include <cmath>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "cli_run.hpp"
#include "render/render_cli.hpp"
#include "render/smaa.hpp"
#include "render_fixture.hpp"
#include "shaders/texture_mips.hpp"

namespace bvhlab::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

// Every textured primitive kind, a mirror and a glass sphere, a world map: all builtin (no datasets).
const char* kTexturedScene = R"(
[camera]
eye = [0, 2.5, 7]
target = [0, 0.8, 0]
fov = 45
[render]
max_depth = 4
[world]
kind = "map"
map = "builtin:checker"
[[light]]
kind = "point"
position = [4, 6, 4]
intensity = 0.9
[[material]]
name = "checker"
texture = "builtin:checker"
uv_scale = [6, 6]
[[material]]
name = "logo"
texture = "builtin:logo"
[[material]]
name = "mirror"
color = [0.9, 0.9, 0.9]
reflectivity = 0.9
[[material]]
name = "glass"
transparency = 1.0
ior = 1.5
[[object]]
kind = "plane"
material = "checker"
scale = 8
[[object]]
kind = "sphere"
material = "mirror"
translate = [-3, 1, 0]
[[object]]
kind = "box"
material = "logo"
translate = [-0.8, 0.8, 0]
rotate = [0, 25, 0]
scale = 0.8
[[object]]
kind = "cylinder"
material = "logo"
translate = [1.3, 0.9, 0]
scale = [0.7, 0.9, 0.7]
[[object]]
kind = "cone"
material = "logo"
translate = [3.2, 0.9, 0]
scale = [0.7, 0.9, 0.7]
[[object]]
kind = "torus"
material = "checker"
major_radius = 0.8
minor_radius = 0.3
translate = [0, 0.3, 2]
[[object]]
kind = "sphere"
material = "glass"
translate = [1.5, 0.6, 2.5]
scale = 0.6
)";

// A mirror sphere of radius `radius` at the origin, seen head-on from z = 5, reflecting a world map.
std::string mirrorSphereScene(float radius) {
  return R"(
[camera]
eye = [0, 0, 5]
target = [0, 0, 0]
fov = 45
[render]
max_depth = 2
[world]
kind = "map"
map = "builtin:checker"
[[material]]
name = "mirror"
color = [0, 0, 0]
reflectivity = 1.0
[[object]]
kind = "sphere"
material = "mirror"
scale = )" + std::to_string(radius) + "\n";
}

// main.glsl's LOD_VIEW encoding: red = round(16 lambda + 1), 0 where the path looked nothing up.
float decodeLevel(uint8_t red) { return red == 0 ? -1.0f : (float(red) - 1.0f) / 16.0f; }

ShaderOptions lodView(const PreparedScene& p, TextureLod mode) {
  ShaderOptions o = tracerOptions(p);
  o.textureLod = mode;
  o.lodView = true;
  return o;
}

TEST(TextureLod, DefaultIsNoneAndCompilesNoConeCode) {
  EXPECT_EQ(ShaderOptions{}.textureLod, TextureLod::None);
  EXPECT_EQ(parseRenderArgs({"scene.toml"}).textureLod, "none");
  EXPECT_EQ(parseTextureLod("cones-aniso"), TextureLod::ConesAniso);
  auto p = prepareToml(kTexturedScene);
  const SceneFeatures f = analyzeScene(p->scene);
  ShaderOptions o = tracerOptions(*p);
  const AssembledShader none = assembleTracer(f, o);
  EXPECT_FALSE(none.hasModule("texture_lod.glsl"));
  EXPECT_EQ(none.source.find("TEXTURE_LOD 1"), std::string::npos);
  o.textureLod = TextureLod::Cones;
  const AssembledShader cones = assembleTracer(f, o);
  EXPECT_TRUE(cones.hasModule("texture_lod.glsl"));
  EXPECT_NE(cones.source.find("#define TEXTURE_LOD 1\n"), std::string::npos);
}

// A scene that samples no texture (sky, untextured materials) gets the very same shader and image with
// cones as without: the cone code is compiled in only where it has texels to filter.
TEST(TextureLod, SceneWithoutTexturesIsUntouched) {
  auto p = prepareToml(R"(
[camera]
eye = [0, 1, 4]
target = [0, 0.5, 0]
[world]
kind = "sky"
[[material]]
name = "m"
color = [0.8, 0.3, 0.2]
reflectivity = 0.5
[[object]]
kind = "sphere"
material = "m"
translate = [0, 0.5, 0]
scale = 0.5
[[object]]
kind = "plane"
material = "m"
scale = 4
)");
  const FrameOptions f = smallFrame(p->scene, 48, 32);
  ShaderOptions none = tracerOptions(*p), cones = none;
  cones.textureLod = TextureLod::Cones;
  EXPECT_FALSE(usesTextureLod(analyzeScene(p->scene), cones));
  const Rendered a = renderGpu(*p, none, f), b = renderGpu(*p, cones, f);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.rgba, b.rgba);
}

// With cones the image changes (minified texels are filtered) and stays close to the mirror's; with
// none it is the same render as before (level 0 everywhere; the GL image equals the mirror's within the
// project's GLSL-vs-mirror tolerance).
TEST(TextureLod, ConesChangeTheImageAndMatchTheMirror) {
  auto p = prepareToml(kTexturedScene);
  const FrameOptions f = smallFrame(p->scene, 96, 54);
  for (TextureLod mode : {TextureLod::None, TextureLod::Cones, TextureLod::ConesAniso}) {
    ShaderOptions o = tracerOptions(*p);
    o.textureLod = mode;
    const Rendered gl = renderGpu(*p, o, f);
    const ReferenceImage cpu = renderReference(p->scene, p->data, p->packed, o, f);
    const ImageDiff d = compareRgba(gl.rgba, cpu.rgba);
    EXPECT_GE(d.within3, 0.99) << textureLodName(mode) << ": mean |diff| " << d.meanAbs << ", max " << d.maxDiff;
    if (mode != TextureLod::None) {
      ShaderOptions n = tracerOptions(*p);
      const ImageDiff change = compareRgba(gl.rgba, renderGpu(*p, n, f).rgba);
      EXPECT_GT(change.meanAbs, 1.0) << textureLodName(mode) << " left the image as it was";
    }
  }
}

// Per pixel, the level of the first texture lookup along the path: GLSL and mirror agree to the
// view's 1/16-level step except where floating point decides (counted and printed), and to one level
// everywhere but the few pixels whose path takes another branch.
void expectLevelsAgree(const PreparedScene& p, int width, int height, TextureLod mode,
                       Branching branching = Branching::Full) {
  const FrameOptions f = smallFrame(p.scene, width, height);
  ShaderOptions o = lodView(p, mode);
  o.branching = branching;
  const Rendered gl = renderGpu(p, o, f);
  const ReferenceImage cpu = renderReference(p.scene, p.data, p.packed, o, f);
  const float step = 1.0f / 16.0f;
  int rounding = 0, withinOne = 0, beyondOne = 0, looked = 0;
  std::map<int, int> levels;  // whole levels seen (GLSL)
  for (size_t i = 0; i < size_t(width) * height; ++i) {
    const float a = decodeLevel(gl.rgba[4 * i]), b = decodeLevel(cpu.rgba[4 * i]);
    if (a >= 0.0f) ++looked, ++levels[int(a)];
    const float d = std::abs(a - b);
    if ((a < 0.0f) != (b < 0.0f) || d > 1.0f) ++beyondOne;
    else if (d > 1.5f * step) ++withinOne;
    else if (d > 0.5f * step) ++rounding;
  }
  const int pixels = width * height;
  std::printf("%s, %s branching: %d of %d pixels looked a texture up (%zu whole levels); GLSL vs mirror: one step (1/16) apart at "
              "%d, up to one level at %d, more at %d\n",
              textureLodName(mode), branchingName(branching), looked, pixels, levels.size(), rounding, withinOne, beyondOne);
  EXPECT_GT(looked, pixels / 2);
  EXPECT_GE(levels.size(), 4u) << "the view should span several levels";
  // Pixels where floating point decides: a path that takes another branch (a hit decided by one ulp)
  // may see another surface. At most 1% of the pixels off by more than a rounding step, 0.5% by more
  // than a level.
  EXPECT_LE(withinOne + beyondOne, pixels / 100);
  EXPECT_LE(beyondOne, pixels / 200);
}

TEST(TextureLod, MirrorPicksTheGlslLevel) {
  auto p = prepareToml(kTexturedScene);
  expectLevelsAgree(*p, 96, 54, TextureLod::Cones);
  expectLevelsAgree(*p, 96, 54, TextureLod::ConesAniso);
  expectLevelsAgree(*p, 96, 54, TextureLod::Cones, Branching::Report);  // trace_report.glsl's cones
}

TEST(TextureLod, MirrorPicksTheGlslLevelOnTheReportScene) {
  BVHLAB_REQUIRE_DATASETS();
  auto p = prepareScene(loadScene(sourceDir() / "datasets/scenes/report.toml"), "sah-binned", BuildOptions{});
  expectLevelsAgree(*p, 96, 54, TextureLod::Cones);
}

// The centre ray hits the sphere head-on at t = 5 - r with cone width w = gamma t and reflects
// straight back: the reflected spread is gamma + 2 w / r, so the world map's level rises by
// log2(1 + 2 t / r) over a cone that keeps its spread. Fails if the curvature term is dropped, has the
// wrong sign, or ignores the object's scale.
TEST(TextureLod, ConeWidensAtACurvedMirror) {
  for (float r : {1.0f, 2.0f}) {
    auto p = prepareToml(mirrorSphereScene(r));
    const int w = 25, h = 15;  // odd: the centre pixel's ray is the axis
    const FrameOptions f = smallFrame(p->scene, w, h);
    ShaderOptions with = lodView(*p, TextureLod::Cones), without = with;
    without.coneCurvature = false;
    const size_t centre = size_t(h / 2) * w + w / 2;
    const float t = 5.0f - r;
    const float expected = std::log2(1.0f + 2.0f * t / r);
    const Rendered a = renderGpu(*p, with, f), b = renderGpu(*p, without, f);
    const float la = decodeLevel(a.rgba[4 * centre]), lb = decodeLevel(b.rgba[4 * centre]);
    ASSERT_GE(lb, 0.5f) << "the flat cone's level should be above the clamp at 0 to measure the rise";
    EXPECT_NEAR(la - lb, expected, 0.1) << "r = " << r << ": level " << la << " with curvature, " << lb << " without";
    const ReferenceImage ca = renderReference(p->scene, p->data, p->packed, with, f);
    const ReferenceImage cb = renderReference(p->scene, p->data, p->packed, without, f);
    EXPECT_NEAR(decodeLevel(ca.rgba[4 * centre]) - decodeLevel(cb.rgba[4 * centre]), expected, 0.1)
        << "mirror, r = " << r;
  }
}

// The same for a mesh: a latitude-longitude unit sphere with exact vertex normals (n = p), whose
// per-triangle estimate (n_j - n_i).(p_j - p_i) / |p_j - p_i|^2 is exactly 1 on every edge. The facets sit
// inside the sphere by at most r (1 - cos(pi / 64)) ~ 1.2e-3, so the centre ray's t differs from 4 by
// less than that; the 0.1 tolerance covers it.
TEST(TextureLod, ConeWidensAtACurvedMeshMirror) {
  std::string obj;
  const int rings = 64, segments = 128;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = M_PI * i / rings, ph = 2.0 * M_PI * j / segments;
      const double x = std::sin(th) * std::cos(ph), y = std::cos(th), z = std::sin(th) * std::sin(ph);
      obj += "v " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
      obj += "vn " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
    }
  auto at = [&](int i, int j) { return std::to_string(i * segments + (j % segments) + 1); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const std::string a = at(i, j), b = at(i, j + 1), c = at(i + 1, j), d = at(i + 1, j + 1);
      // Counter-clockwise seen from outside: the geometric normal points out, as the vertex normals do.
      obj += "f " + a + "//" + a + " " + b + "//" + b + " " + c + "//" + c + "\n";
      obj += "f " + b + "//" + b + " " + d + "//" + d + " " + c + "//" + c + "\n";
    }
  const std::filesystem::path file = clitest::writeTemp("sphere.obj", obj);
  auto p = prepareToml(R"(
[camera]
eye = [0, 0, 5]
target = [0, 0, 0]
fov = 45
[render]
max_depth = 2
[world]
kind = "map"
map = "builtin:checker"
[[material]]
name = "mirror"
color = [0, 0, 0]
reflectivity = 1.0
[[object]]
kind = "mesh"
material = "mirror"
mesh = ")" + file.string() + "\"\n");
  const int w = 25, h = 15;
  const FrameOptions f = smallFrame(p->scene, w, h);
  ShaderOptions with = lodView(*p, TextureLod::Cones), without = with;
  without.coneCurvature = false;
  const size_t centre = size_t(h / 2) * w + w / 2;
  const float expected = std::log2(1.0f + 2.0f * 4.0f / 1.0f);
  const Rendered a = renderGpu(*p, with, f), b = renderGpu(*p, without, f);
  EXPECT_NEAR(decodeLevel(a.rgba[4 * centre]) - decodeLevel(b.rgba[4 * centre]), expected, 0.1)
      << "level " << decodeLevel(a.rgba[4 * centre]) << " with curvature, " << decodeLevel(b.rgba[4 * centre])
      << " without";
  const ReferenceImage ca = renderReference(p->scene, p->data, p->packed, with, f);
  const ReferenceImage cb = renderReference(p->scene, p->data, p->packed, without, f);
  EXPECT_NEAR(decodeLevel(ca.rgba[4 * centre]) - decodeLevel(cb.rgba[4 * centre]), expected, 0.1) << "mirror";
}

TEST(TextureLod, MipChainAveragesEveryTexel) {
  // 3x2 -> 1x1: the odd column joins the last texel, so the 1x1 level is the mean of all six.
  std::vector<glm::vec4> t;
  for (int i = 0; i < 6; ++i) t.push_back(glm::vec4(float(i)));
  const std::vector<MipLevel> chain = buildMipChain(t, 3, 2);
  ASSERT_EQ(chain.size(), 2u);
  EXPECT_EQ(chain[1].width, 1);
  EXPECT_EQ(chain[1].height, 1);
  EXPECT_FLOAT_EQ(chain[1].texels[0].x, 2.5f);
  EXPECT_THROW(buildMipChain(t, 4, 2), std::invalid_argument);
}

// SMAA's geometry edges (--smaa-edges geometry) read the primary ray's hit id, which the shaded view
// writes from inside radiance() (both branching modes): it must equal the id the primid debug view
// computes for the same pixel. SMAA then changes only pixels within two of an id boundary (an edge lies
// between a pixel and its left or lower neighbour; the blend reads the weights of the four neighbours),
// and does change some: the checker's own edges, filtered by cones, stay as they were.
TEST(TextureLod, SmaaGeometryEdgesFollowThePrimaryIds) {
  auto p = prepareToml(kTexturedScene);
  const int w = 96, h = 54;
  const FrameOptions f = smallFrame(p->scene, w, h);
  glContext();
  for (Branching branching : {Branching::Full, Branching::Report}) {
    ShaderOptions shaded = tracerOptions(*p);
    shaded.textureLod = TextureLod::ConesAniso;
    shaded.branching = branching;
    shaded.primaryIdOut = true;
    ShaderOptions primid = shaded;
    primid.view = View::PrimId;
    primid.countStats = true;
    GpuRenderer debug(*p, primid, f);
    debug.drawFrame();
    const std::vector<uint32_t> expected = debug.readPrimaryIds();
    const std::vector<glm::uvec4> stats = debug.readStats();
    GpuRenderer gpu(*p, shaded, f);
    gpu.drawFrame();
    const std::vector<uint32_t> ids = gpu.readPrimaryIds();
    std::map<uint32_t, int> seen;
    for (size_t i = 0; i < ids.size(); ++i) {
      ASSERT_EQ(expected[i], stats[i].w & 0x7FFFFFFFu) << "pixel " << i;
      ASSERT_EQ(ids[i], expected[i]) << branchingName(branching) << ", pixel " << i;
      ++seen[ids[i]];
    }
    EXPECT_GE(seen.size(), 8u) << "the miss, the plane, five objects and the mesh-free scene's glass sphere";

    SmaaSettings settings = SmaaSettings::preset(SmaaPreset::High);
    settings.edgeMode = SmaaEdgeMode::Geometry;
    SmaaPass smaa(w, h, settings);
    smaa.apply(gpu.colorTexture(), gpu.primaryIdTexture());
    const std::vector<uint8_t> in = gpu.readColor(), out = smaa.readOutput();
    const auto id = [&](int x, int y) { return ids[size_t(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)]; };
    int changed = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        if (std::equal(in.begin() + 4 * i, in.begin() + 4 * i + 3, out.begin() + 4 * i)) continue;
        ++changed;
        bool boundary = false;
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) boundary = boundary || id(x + dx, y + dy) != id(x, y);
        EXPECT_TRUE(boundary) << "SMAA changed pixel " << x << "," << y << " far from any primitive boundary";
      }
    EXPECT_GT(changed, w) << "geometry edges blended nothing";
  }
}

TEST(TextureLod, BadOptionValueIsRefused) {
  const clitest::Result render = clitest::run("render " + clitest::scene("textures.toml").string() +
                                              " --width 8 --height 8 --texture-lod blurry");
  EXPECT_EQ(render.code, 2) << render.err;
  EXPECT_EQ(render.err.rfind("bvhlab: error:", 0), 0u) << render.err;
  EXPECT_NE(render.err.find("--texture-lod"), std::string::npos) << render.err;
  EXPECT_NE(render.err.find("cones-aniso"), std::string::npos) << render.err;
}

}  // namespace
}  // namespace bvhlab::test
