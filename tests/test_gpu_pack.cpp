// The GPU pack (builders/gpu/gpu_pack.hpp, gpu_pack_wide.hpp) on llvmpipe: lbvh-gpu's and ploc-gpu's
// trees packed on the GPU into v1, bvh2-cb and cwbvh give the streams the CPU packs from the downloaded
// tree, texel for texel, on
// the bunny, synthetic meshes, a deep tree and a root that is one leaf, at several leaf sizes; one
// primitive packed on the CPU; other layouts, mismatched soups and sizes past the GL limits refused;
// the `pack` phase timed; `build --json` saying which layout it packed.
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "builders/builder.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_lbvh.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_pack_wide.hpp"
#include "builders/gpu/gpu_ploc.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "gl_compute.hpp"
#include "layout/layout.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "layout/layout_cwbvh.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"
#include "shaders/assemble.hpp"
#include "traversal_test_util.hpp"

namespace bvhlab {
namespace {

namespace fs = std::filesystem;
using gpubuild::GpuPackRequest;

class GpuPack : public ::testing::Test {
 public:
  static void SetUpTestSuite() {
    registerGpuBuilders();
    context_ = createContext(Backend::OSMesa);
    lbvh_ = std::make_unique<gpubuild::GpuLbvh>();
    ploc_ = std::make_unique<gpubuild::GpuPloc>();
  }
  static void TearDownTestSuite() {
    lbvh_.reset();
    ploc_.reset();
    context_.reset();
  }
  // Builds with `builder` packing into `layout` on the GPU; returns the tree, the GPU's streams in *out.
  static Bvh build(const std::string& builder, const TriangleSoup& soup, const std::string& layout,
                   const BuildOptions& options, PackedBvh* out) {
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(soup);
    const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
    const GpuPackRequest request{layout, &soup, out};
    return builder == "ploc-gpu" ? ploc_->build(input, options, nullptr, &request)
                                 : lbvh_->build(input, options, nullptr, &request);
  }

 protected:
  static std::unique_ptr<GlContext> context_;
  static std::unique_ptr<gpubuild::GpuLbvh> lbvh_;
  static std::unique_ptr<gpubuild::GpuPloc> ploc_;
};
std::unique_ptr<GlContext> GpuPack::context_;
std::unique_ptr<gpubuild::GpuLbvh> GpuPack::lbvh_;
std::unique_ptr<gpubuild::GpuPloc> GpuPack::ploc_;

PackedBvh cpuPack(const Bvh& bvh, const TriangleSoup& soup, const std::string& layout) {
  return layout == "v1" ? packBvh(bvh, soup) : layout == kLayoutBvh2cb ? packBvh2cb(bvh, soup) : packCwbvh(bvh, soup);
}

constexpr const char* kPackedLayouts[] = {"v1", kLayoutBvh2cb, kLayoutCwbvh};

void expectSameStreams(const PackedBvh& gpu, const PackedBvh& cpu) {
  EXPECT_EQ(gpu.layout, cpu.layout);
  EXPECT_EQ(gpu.depth, cpu.depth);
  ASSERT_EQ(gpu.nodes.size(), cpu.nodes.size());
  ASSERT_EQ(gpu.triangles.size(), cpu.triangles.size());
  ASSERT_EQ(gpu.attributes.size(), cpu.attributes.size());
  for (size_t i = 0; i < gpu.nodes.size(); ++i) ASSERT_EQ(gpu.nodes[i], cpu.nodes[i]) << "node texel " << i;
  for (size_t i = 0; i < gpu.triangles.size(); ++i) ASSERT_EQ(gpu.triangles[i], cpu.triangles[i]) << "triangle texel " << i;
  for (size_t i = 0; i < gpu.attributes.size(); ++i)
    ASSERT_EQ(gpu.attributes[i], cpu.attributes[i]) << "attribute texel " << i;
}

// Every builder x layout x leaf size on `soup`: the GPU's streams are the CPU's pack of the tree.
void expectCpuStreams(const TriangleSoup& soup, const std::string& what) {
  for (const char* builder : {"lbvh-gpu", "ploc-gpu"})
    for (const char* layout : kPackedLayouts)
      for (uint32_t leaf : {1u, 4u, 8u}) {
        SCOPED_TRACE(what + ", " + builder + ", " + layout + ", leaf size " + std::to_string(leaf));
        BuildOptions options;
        options.maxLeafSize = leaf;
        PackedBvh gpu;
        const Bvh bvh = GpuPack::build(builder, soup, layout, options, &gpu);
        expectSameStreams(gpu, cpuPack(bvh, soup, layout));
      }
}

// One small triangle per Morton bit: triangle k sits at 2^(k / 3) grid cells along axis k % 3 (0 on the
// others), so its code has bit k alone, every code a different highest bit, and lbvh's radix tree is a
// chain about 60 deep (many pointer-jumping rounds). Corners at the grid's ends fix its bounds.
Mesh mortonChain() {
  Mesh m;
  auto add = [&](glm::vec3 p) {
    const uint32_t v = uint32_t(m.positions.size());
    m.positions.push_back(p);
    m.positions.push_back(p + glm::vec3(0.25f, 0.0f, 0.0f));
    m.positions.push_back(p + glm::vec3(0.0f, 0.25f, 0.0f));
    m.triangles.push_back({v, v + 1, v + 2});
  };
  add(glm::vec3(0.0f));
  add(glm::vec3(float(1 << 21)));
  for (int k = 0; k < 63; ++k) {
    glm::vec3 p(0.0f);
    p[k % 3] = float(1 << (k / 3));
    add(p);
  }
  return m;
}

TEST_F(GpuPack, SyntheticMeshesGiveTheCpuStreams) {
  using namespace traversaltest;
  expectCpuStreams(soupOf({sphereMesh(12, 24, 1.0f), randomSoupMesh(700, 4)}), "sphere and random soup");
  // Equal triangles on a grid: equal areas make equal costs, where the wide collapse's and the slot
  // assignment's tie-breaks decide.
  expectCpuStreams(soupOf({gridMesh(24)}), "a grid");
  // Boxes of zero area (triangles along the x axis, some of them points) beside ordinary ones, and
  // a whole scene of one point (a root of zero area: every relative area 0).
  Mesh lines = randomSoupMesh(200, 9), point;
  for (int k = 0; k < 60; ++k) {
    const uint32_t v = uint32_t(lines.positions.size());
    const float x = float(k % 7) * 0.25f;
    lines.positions.insert(lines.positions.end(), {{x, 0.5f, 0.5f}, {x + float(k % 3) * 0.1f, 0.5f, 0.5f}, {x, 0.5f, 0.5f}});
    lines.triangles.push_back({v, v + 1, v + 2});
  }
  point.positions = {{1, 2, 3}};
  for (int k = 0; k < 40; ++k) point.triangles.push_back({0, 0, 0});
  expectCpuStreams(soupOf({lines}), "boxes of zero area");
  // Grids near the ends of float's range: coordinates of 1e18 (boxes whose half areas near 1e37, grid
  // steps up at 2^60) and of 1e-36 (steps down at the smallest normal, 2^-126).
  for (const float scale : {1e18f, 1e-36f}) {
    Mesh far = randomSoupMesh(300, 11);
    for (glm::vec3& p : far.positions) p *= scale;
    expectCpuStreams(soupOf({far}), "coordinates of magnitude " + std::to_string(scale));
  }
  // Past them, a root whose half area overflows a float: the CPU's collapse refuses it, and so does the
  // GPU's, instead of letting an infinity into its program.
  Mesh huge = randomSoupMesh(300, 11);
  for (glm::vec3& p : huge.positions) p *= 1e20f;
  const TriangleSoup hugeSoup = soupOf({huge});
  PackedBvh v1, wide;
  EXPECT_THROW(packCwbvh(build("lbvh-gpu", hugeSoup, "v1", BuildOptions{}, &v1), hugeSoup), std::runtime_error);
  try {
    build("lbvh-gpu", hugeSoup, kLayoutCwbvh, BuildOptions{}, &wide);
    ADD_FAILURE() << "a root of infinite area was packed into cwbvh on the GPU";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("overflows a float"), std::string::npos) << e.what();
  }
  expectCpuStreams(soupOf({point}), "one point");
  const TriangleSoup deep = soupOf({mortonChain()});
  expectCpuStreams(deep, "a chain of Morton bits");
  PackedBvh gpu;
  BuildOptions leaf1;
  leaf1.maxLeafSize = 1;
  build("lbvh-gpu", deep, "v1", leaf1, &gpu);
  EXPECT_GT(gpu.depth, 32u) << "the deep input is not deep: fewer jumping rounds than meant";
  build("lbvh-gpu", deep, kLayoutCwbvh, leaf1, &gpu);
  EXPECT_GE(gpu.depth, 10u) << "the deep input's wide tree is not deep: few level dispatches did any work";
}

TEST_F(GpuPack, TheBunnyGivesTheCpuStreams) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  expectCpuStreams(gatherTriangles(loadInput(path)), "bunny");
}

// Three copies of one triangle: the collapse makes the root one leaf (3 A <= A + 2 A + A). v1 holds
// one node; bvh2-cb one record with the leaf in A and an empty slot over the same box in B; cwbvh one
// node with the leaf in one slot.
TEST_F(GpuPack, ARootThatIsOneLeaf) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 1, 2}, {0, 1, 2}};
  const TriangleSoup soup = traversaltest::soupOf({m});
  for (const char* builder : {"lbvh-gpu", "ploc-gpu"})
    for (const char* layout : kPackedLayouts) {
      SCOPED_TRACE(std::string(builder) + ", " + layout);
      PackedBvh gpu;
      const Bvh bvh = build(builder, soup, layout, BuildOptions{}, &gpu);
      ASSERT_EQ(bvh.nodes.size(), 1u) << "the root was not collapsed: this case tests nothing";
      expectSameStreams(gpu, cpuPack(bvh, soup, layout));
      EXPECT_EQ(gpu.nodes.size(), std::string(layout) == "v1" ? 2u : std::string(layout) == kLayoutCwbvh ? 5u : 4u);
    }
}

TEST_F(GpuPack, OnePrimitiveIsPackedOnTheCpu) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  const TriangleSoup soup = traversaltest::soupOf({m});
  for (const char* layout : kPackedLayouts) {
    PackedBvh gpu;
    const Bvh bvh = build("lbvh-gpu", soup, layout, BuildOptions{}, &gpu);
    expectSameStreams(gpu, cpuPack(bvh, soup, layout));
  }
}

TEST_F(GpuPack, OtherLayoutsMismatchedSoupsAndSizesPastTheLimitsAreRefused) {
  const TriangleSoup soup = traversaltest::soupOf({traversaltest::randomSoupMesh(50, 2)});
  PackedBvh out;
  try {
    build("lbvh-gpu", soup, "bvh4", BuildOptions{}, &out);
    ADD_FAILURE() << "bvh4 was packed on the GPU";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'bvh4'"), std::string::npos) << e.what();
  }
  const TriangleSoup other = traversaltest::soupOf({traversaltest::randomSoupMesh(49, 2)});
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  const GpuPackRequest mismatched{"v1", &other, &out};
  EXPECT_THROW(lbvh_->build(input, BuildOptions{}, nullptr, &mismatched), std::invalid_argument);
  // A limit the build fits in (its largest buffer, the node boxes, takes 48 bytes a primitive) but the
  // pack's soup texels (112 bytes a primitive) do not.
  const size_t n = 1000;
  const gpubuild::GpuLimits limits{60 * n, 1u << 20};
  for (const char* builder : {"lbvh-gpu", "ploc-gpu"}) {
    SCOPED_TRACE(builder);
    auto check = [&](bool pack) {
      if (std::string(builder) == "ploc-gpu")
        gpubuild::GpuPloc(limits).checkLimits(n, pack);
      else
        gpubuild::GpuLbvh(limits).checkLimits(n, pack);
    };
    EXPECT_NO_THROW(check(false));
    try {
      check(true);
      ADD_FAILURE() << "the pack's buffers were not counted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("soup texels (pack)"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << e.what();
    }
  }
}

TEST_F(GpuPack, TimedAsThePackPhase) {
  const TriangleSoup soup = traversaltest::soupOf({traversaltest::randomSoupMesh(2000, 6)});
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  for (const char* builder : {"lbvh-gpu", "ploc-gpu"}) {
    const GpuBuildTiming t = timeGpuBuild(builder, input, BuildOptions{}, 3, kLayoutBvh2cb, &soup);
    EXPECT_EQ(t.packLayout, kLayoutBvh2cb);
    ASSERT_FALSE(t.phaseMedianMs.empty());
    EXPECT_EQ(t.phaseMedianMs.back().first, "pack") << builder;
    EXPECT_GT(t.phaseMedianMs.back().second, 0.0) << builder;
    const GpuBuildTiming unpacked = timeGpuBuild(builder, input, BuildOptions{}, 3);
    EXPECT_TRUE(unpacked.packLayout.empty());
    for (const auto& [phase, ms] : unpacked.phaseMedianMs) EXPECT_NE(phase, "pack");
    // cwbvh: the binary pack's steps, then the wide collapse's three.
    const GpuBuildTiming wide = timeGpuBuild(builder, input, BuildOptions{}, 3, kLayoutCwbvh, &soup);
    EXPECT_EQ(wide.packLayout, kLayoutCwbvh);
    std::vector<std::string> tail;
    for (size_t p = wide.phaseMedianMs.size() >= 4 ? wide.phaseMedianMs.size() - 4 : 0; p < wide.phaseMedianMs.size(); ++p)
      tail.push_back(wide.phaseMedianMs[p].first);
    EXPECT_EQ(tail, (std::vector<std::string>{"pack", "wide_costs", "wide_levels", "wide_nodes"})) << builder;
  }
}

// A leaf slot of more triangles than cwbvh's 7-bit count: 300 copies of one triangle at leaf size 255
// collapse into leaves past 127. The CPU's packer refuses it, and so does the GPU's, with the same
// advice; buffers past the GL limit are refused before any work.
TEST_F(GpuPack, CwbvhRefusesLeavesPastItsCountAndBuffersPastTheLimit) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int i = 0; i < 300; ++i) m.triangles.push_back({0, 1, 2});
  const TriangleSoup soup = traversaltest::soupOf({m});
  BuildOptions big;
  big.maxLeafSize = 255;
  for (const char* builder : {"lbvh-gpu", "ploc-gpu"}) {
    SCOPED_TRACE(builder);
    PackedBvh gpu;
    try {
      const Bvh bvh = build(builder, soup, kLayoutCwbvh, big, &gpu);
      ADD_FAILURE() << "a leaf past 127 triangles was packed";
      EXPECT_THROW(packCwbvh(bvh, soup), std::runtime_error);
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("stores at most 127"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("--leaf-size 127"), std::string::npos) << e.what();
    }
    PackedBvh v1;
    const Bvh bvh = build(builder, soup, "v1", big, &v1);
    EXPECT_THROW(packCwbvh(bvh, soup), std::runtime_error) << "the CPU packs it: the case tests nothing";
  }
  const gpubuild::GpuLimits limits{60 * 1000, 1u << 20};
  try {
    gpubuild::GpuWidePack::checkLimits(1000, limits);
    ADD_FAILURE() << "the cwbvh pack's buffers were not checked";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(cwbvh pack)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(gpubuild::GpuWidePack::checkLimits(1000, gpubuild::GpuLimits{1u << 20, 1u << 20}));
}

// The wide collapse's division (gpubuild_exact_division.glsl): from either neighbour of the IEEE
// quotient, correctQuotient gives the IEEE quotient back, bit for bit, on quotients of half areas as the
// collapse makes them (doubles of floats, a child's at most its root's, over float's whole range). On
// llvmpipe the driver's own division is IEEE, so this is what exercises the correction at all.
TEST_F(GpuPack, TheWideCollapsesDivisionIsCorrectedToTheIeeeQuotient) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> exponent(-36.0, 36.0), below(-30.0, 0.0);
  std::vector<glm::uvec2> in;
  std::vector<double> quotients;
  auto add = [&](double a, double b) {
    const double q = a / b;
    for (double v : {a, b, q}) in.push_back(std::bit_cast<glm::uvec2>(v));
    quotients.push_back(q);
  };
  for (int k = 0; k < 20000; ++k) {
    const float root = float(std::pow(10.0, exponent(rng)));
    const float child = std::max(float(double(root) * std::pow(10.0, below(rng))), std::numeric_limits<float>::min());
    add(double(child), double(root));
  }
  for (float v : {1.0f, 3.0f, 1e-30f, 7e30f}) add(double(v), double(v)), add(double(v) * 0.5, double(v));
  const std::string source = std::string("#version 450\n") + glslSources().at("gpubuild_exact_division.glsl") + R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer In { uvec2 ins[]; };     // a, b, the IEEE a / b
layout(std430, binding = 1) writeonly buffer Out { uvec2 outs[]; };  // corrected from above and below
uniform int u_count;
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(u_count)) return;
  double a = packDouble2x32(ins[3u * i]), b = packDouble2x32(ins[3u * i + 1u]), q = packDouble2x32(ins[3u * i + 2u]);
  outs[2u * i] = unpackDouble2x32(correctQuotient(a, b, nextUp(q)));
  outs[2u * i + 1u] = unpackDouble2x32(correctQuotient(a, b, nextDown(q)));
}
)";
  const GLuint program = test::compileCompute(source);
  const std::vector<glm::uvec2> out =
      test::dispatchCompute<glm::uvec2>(program, in, 2 * quotients.size(), quotients.size(), "exact division");
  glDeleteProgram(program);
  size_t wrong = 0;
  for (size_t i = 0; i < quotients.size(); ++i)
    for (int side = 0; side < 2; ++side)
      if (std::bit_cast<double>(out[2 * i + size_t(side)]) != quotients[i] ||
          std::signbit(std::bit_cast<double>(out[2 * i + size_t(side)])))
        ++wrong;
  EXPECT_EQ(wrong, 0u) << "of " << 2 * quotients.size() << " corrections";
}

// `build --json`: gpu_pack names the layout packed on the GPU (v1, bvh2-cb or cwbvh with raw triangles) and
// is null where the CPU packs (another layout or triangle format).
TEST(GpuPackCli, BuildJsonSaysWhichLayoutWasPackedOnTheGpu) {
  std::string obj;
  for (int i = 0; i < 12; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(i % 3) + " 0\nv " +
                                      std::to_string(i) + " 1 1\nv " + std::to_string(i + 1) + " 0 1\n";
  for (int i = 0; i < 12; ++i)
    obj += "f " + std::to_string(3 * i + 1) + " " + std::to_string(3 * i + 2) + " " + std::to_string(3 * i + 3) + "\n";
  const std::string mesh = clitest::writeTemp("gpu_pack.obj", obj).string();
  const std::pair<std::string, nlohmann::json> cases[] = {
      {"--layout bvh2-cb", "bvh2-cb"}, {"--layout cwbvh", "cwbvh"}, {"", "v1"}, {"--layout bvh4", nullptr},
      {"--triangles precomputed", nullptr}};
  for (const auto& [flags, expected] : cases) {
    const clitest::Result r = clitest::run("build --mesh " + mesh + " --builder ploc-gpu --json --gpu-builds 2 " + flags);
    ASSERT_EQ(r.code, 0) << flags << ": " << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["gpu_pack"], expected) << flags;
    EXPECT_EQ(j["gpu_phases_ms"].contains("pack"), !expected.is_null()) << flags;
  }
}

// A sweep with [render] gpu_builds through `bvhlab run`: the GPU builder's trace row records its
// GL-timed build (median, interval, the layout packed on the GPU), the CPU builder's row none, and the
// report's builder table shows the GPU time marked as such.
TEST(GpuPackCli, SweepRowsAndTheReportCarryTheGlTimedBuild) {
  const fs::path cfg = clitest::writeTemp("gpu-pack-run/cfg.toml", R"(
[experiment]
name = "gpu-builds-test"
description = "GL-timed GPU builds in a sweep"
[render]
frames = 3
warmup = 1
gpu_builds = 6
[measure]
max_frames = 3
[trace]
count = 2000
[axes]
scenes = { generate = "large", triangles = 3000, seed = 2, name = "cloud" }
builders = ["lbvh", "lbvh-gpu"]
rays = "primary"
)");
  const fs::path out = clitest::testDir() / "gpu-pack-run/out";
  const clitest::Result r = clitest::run("run " + cfg.string() + " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out / "results.json");
  const nlohmann::json results = nlohmann::json::parse(in);
  int gpuRows = 0, cpuRows = 0;
  for (const nlohmann::json& row : results["rows"]) {
    if (row.value("control_of", nlohmann::json()).is_string()) continue;
    ASSERT_EQ(row["status"], "ok") << row.dump();
    if (row["builder"] == "lbvh-gpu") {
      ++gpuRows;
      ASSERT_TRUE(row["gpu_build_ms"].is_number()) << row.dump();
      EXPECT_GT(row["gpu_build_ms"].get<double>(), 0.0);
      EXPECT_LE(row["gpu_build_ms_ci_low"].get<double>(), row["gpu_build_ms"].get<double>());
      EXPECT_GE(row["gpu_build_ms_ci_high"].get<double>(), row["gpu_build_ms"].get<double>());
      EXPECT_EQ(row["gpu_pack"], "v1");
    } else {
      ++cpuRows;
      EXPECT_TRUE(!row.contains("gpu_build_ms") || row["gpu_build_ms"].is_null()) << row.dump();
    }
  }
  EXPECT_EQ(gpuRows, 1);
  EXPECT_EQ(cpuRows, 1);
  std::ifstream hin(out / "report.html");
  const std::string html((std::istreambuf_iterator<char>(hin)), {});
  EXPECT_NE(html.find("on the GPU (pack into v1 included)"), std::string::npos);
}

}  // namespace
}  // namespace bvhlab
