// ploc-gpu (builders/gpu/gpu_ploc.hpp) on llvmpipe: ploc's tree node for node (so the same tree_hash)
// on the bunny, the armadillo and synthetic inputs at radii 1, 4 and 16, on runs of equal Morton codes
// and with other leaf sizes, cost models and grids; 0 and 1 primitives as the CPU builders; options
// it does not implement and sizes past the GL limits refused before any work; a GL error naming the
// step; its phases in `build --json`; every traversal kernel on its trees against brute force.
#include <algorithm>
#include <filesystem>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glad/gl.h>

#include <nlohmann/json.hpp>

#include "builder_test_util.hpp"
#include "cli_run.hpp"
#include "datasets/random_draws.hpp"
#include "gpu_builder_test_util.hpp"
#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_ploc.hpp"
#include "layout/layout.hpp"
#include "layout/layouts.hpp"
#include "layout/tree_hash.hpp"
#include "layout/triangle_formats.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"
#include "traversal_test_util.hpp"

namespace bvhlab {
namespace {

using testing::PrimitiveSet;

class GpuPloc : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    registerGpuBuilders();
    context_ = createContext(Backend::OSMesa);
  }
  static void TearDownTestSuite() { context_.reset(); }
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> GpuPloc::context_;

using testing::withRadius;
void expectSameAsPloc(const BuildInput& input, const BuildOptions& options = {}) {
  testing::expectSameAsPloc("ploc-gpu", input, options);
}

// The scanned meshes at radii 1, 4 and 16; on the bunny the packed tree_hash too (as `build --json`
// reports it).
TEST_F(GpuPloc, BunnyAndArmadilloGivePlocsTreeAtRadii1To16) {
  const std::filesystem::path dir = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes";
  for (const char* mesh : {"bunny00.off", "armadillo.off"}) {
    const std::filesystem::path path = dir / mesh;
    if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
    const TriangleSoup soup = gatherTriangles(loadInput(path));
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(soup);
    const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
    for (uint32_t radius : {1u, 4u, 16u}) {
      SCOPED_TRACE(std::string(mesh) + ", radius " + std::to_string(radius));
      expectSameAsPloc(input, withRadius(radius));
    }
    if (std::string(mesh) != "bunny00.off") continue;
    auto hash = [&](const std::string& builder) {
      PackedBvh packed = findLayout(kDefaultLayout).pack(buildBvh(builder, input, withRadius(4)), soup);
      packTriangles(packed, soup, kDefaultTriangleFormat);
      return packedTreeHash(packed);
    };
    EXPECT_EQ(hash("ploc-gpu"), hash("ploc"));
  }
}

// A random soup over several workgroups of clusters and a flat grid (many equal merged areas: the
// tie key decides), at radii 1, 4 and 16; then other leaf sizes, a cost model, the axes grid and the
// largest radius.
TEST_F(GpuPloc, SyntheticInputsGivePlocsTree) {
  const PrimitiveSet soup = testing::randomSoup(6000, 3), grid = testing::gridSoup(60, 40);
  for (uint32_t radius : {1u, 4u, 16u}) {
    SCOPED_TRACE(radius);
    expectSameAsPloc(soup.input(), withRadius(radius));
    expectSameAsPloc(grid.input(), withRadius(radius));
  }
  for (uint32_t leaf : {1u, 8u}) {
    BuildOptions o;
    o.maxLeafSize = leaf;
    SCOPED_TRACE(leaf);
    expectSameAsPloc(soup.input(), o);
  }
  BuildOptions costly;
  costly.cost.traversalCost = 3.0f, costly.cost.intersectionCost = 0.5f;
  expectSameAsPloc(soup.input(), costly);
  BuildOptions axes;
  axes.mortonGrid = MortonGrid::Axes;
  expectSameAsPloc(grid.input(), axes);
  expectSameAsPloc(testing::randomSoup(700, 5).input(), withRadius(kMaxPlocRadius));
}

// Runs of equal Morton codes of every length 1..64 (shuffled): each starts as one cluster, a balanced
// tree over the run, as ploc builds it; and every code equal (one run: no clustering pass at all).
TEST_F(GpuPloc, EqualMortonCodesStartAsPlocsBalancedRuns) {
  PrimitiveSet set;
  std::mt19937 rng(5);
  std::vector<glm::vec3> centres;
  for (uint32_t run = 1; run <= 64; ++run)
    for (uint32_t k = 0; k < run; ++k) centres.push_back(glm::vec3(float(run % 8), float(run / 8), float(run % 3)));
  std::shuffle(centres.begin(), centres.end(), rng);
  std::uniform_real_distribution<float> tiny(-1e-3f, 1e-3f);
  for (const glm::vec3& c : centres) {
    const glm::vec3 d = draw3<glm::vec3>(tiny, rng);
    set.addTriangle(c + d, c - d, c + glm::vec3(d.y, d.z, d.x));
  }
  for (size_t i = 0; i < set.size(); ++i) set.centroids[i] = centres[i];  // the codes collide
  BuildOptions one = withRadius(4);
  one.maxLeafSize = 1;
  expectSameAsPloc(set.input());
  expectSameAsPloc(set.input(), one);
  PrimitiveSet same;
  for (int i = 0; i < 1000; ++i) same.addTriangle(glm::vec3(i, 0, 0), glm::vec3(i, 1, 0), glm::vec3(i, 0, 1));
  for (glm::vec3& c : same.centroids) c = glm::vec3(0.5f);
  expectSameAsPloc(same.input(), one);
  expectSameAsPloc(same.input());
}

TEST_F(GpuPloc, ZeroOneAndTwoPrimitivesAsTheCpuBuilder) {
  PrimitiveSet empty;
  EXPECT_THROW(buildBvh("ploc-gpu", empty.input(), {}), InputError);
  EXPECT_THROW(buildBvh("ploc", empty.input(), {}), InputError);
  PrimitiveSet one;
  one.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  expectSameAsPloc(one.input());
  PrimitiveSet two;
  two.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  two.addTriangle(glm::vec3(2, 0, 0), glm::vec3(3, 0, 0), glm::vec3(2, 1, 0));
  BuildOptions leaf1;
  leaf1.maxLeafSize = 1;
  expectSameAsPloc(two.input(), leaf1);
  expectSameAsPloc(two.input());
}

// Refused (before any GL work: build() checks first) with a message naming the limit, a radius
// outside 1..kMaxPlocRadius, or the CPU ploc's option the GPU passes do not implement.
TEST_F(GpuPloc, SizesPastTheGlLimitsAndUnsupportedOptionsAreRefused) {
  const PrimitiveSet set = testing::randomSoup(5000, 2);
  const gpubuild::GpuLimits real = gpubuild::queryGpuLimits();
  auto expectRefusal = [&](const gpubuild::GpuLimits& limits, const BuildOptions& options, const std::string& names) {
    const gpubuild::GpuPloc ploc(limits);
    try {
      ploc.build(set.input(), options);
      ADD_FAILURE() << "no error for " << names;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  // The cluster array needs n * 28 bytes, the node boxes (2n - 1) * 24.
  expectRefusal({5000 * 28, real.maxWorkGroupsX}, {}, "GL_MAX_SHADER_STORAGE_BLOCK_SIZE");
  expectRefusal({real.maxStorageBlockBytes, 19}, {}, "GL_MAX_COMPUTE_WORK_GROUP_COUNT");  // 20 workgroups of 256
  EXPECT_NO_THROW(gpubuild::GpuPloc(gpubuild::GpuLimits{real.maxStorageBlockBytes, 20}).build(set.input(), {}));
  BuildOptions sized, topDown;
  sized.mortonSizeBits = 3;
  topDown.plocTopDown = 4;
  expectRefusal(real, sized, "--morton-size-bits");
  expectRefusal(real, topDown, "--ploc-top-down");
  expectRefusal(real, withRadius(0), "plocRadius 0");
  expectRefusal(real, withRadius(kMaxPlocRadius + 1), "plocRadius 1025");
  EXPECT_THROW(buildBvh("ploc-gpu", set.input(), sized), std::invalid_argument);
}

// A GL error surfaces as an exception naming the step it was found in (here one left pending before
// the build, found by the first check, after the upload), and the next build is right again.
TEST_F(GpuPloc, AGlErrorNamesTheStep) {
  const PrimitiveSet set = testing::randomSoup(100, 8);
  const gpubuild::GpuPloc ploc;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 987654321u);  // never generated: GL_INVALID_OPERATION in a core profile
  try {
    ploc.build(set.input(), {});
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("GL_INVALID_OPERATION in ploc-gpu: uploading the input"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(testing::identical(ploc.build(set.input(), {}), buildBvh("ploc", set.input(), {})));
}

TEST_F(GpuPloc, RegisteredAsAGpuBuilderAndTimedPerPhase) {
  EXPECT_TRUE(findBuilder("ploc-gpu").gpu);
  EXPECT_TRUE(findBuilder("ploc-gpu").usesPlocRadius);
  const PrimitiveSet set = testing::randomSoup(3000, 4);
  const GpuBuildTiming t = timeGpuBuild("ploc-gpu", set.input(), withRadius(4), 6);
  ASSERT_TRUE(t.totalMs.has_value());
  EXPECT_LE(t.totalMs->low, t.totalMs->estimate);
  EXPECT_LE(t.totalMs->estimate, t.totalMs->high);
  std::vector<std::string> names;
  for (const auto& [phase, ms] : t.phaseMedianMs) {
    names.push_back(phase);
    EXPECT_GE(ms, 0.0) << phase;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"morton", "sort", "clusters", "nn", "merge", "readback", "collapse"}));
  EXPECT_GT(t.medianMs, 0.0);
  // The passes follow one another on the GPU: the CPU reads their state once per batch, not per pass.
  EXPECT_GT(t.passes, 5u);
  EXPECT_GE(t.passesIssued, t.passes);
  EXPECT_GE(t.readbacks, 1u);
  EXPECT_LT(t.readbacks, t.passes);
}

// Builder x kernel against brute force for ploc-gpu's trees (as test_gpu_builders does for lbvh-gpu):
// every kernel's closest and any hit on a sphere and a random soup equal brute force's.
TEST_F(GpuPloc, EveryKernelOnPlocGpuTreesFindsTheBruteForceHits) {
  using namespace traversaltest;
  for (const TriangleSoup& soup : {soupOf({sphereMesh(16, 32, 1.0f)}), soupOf({randomSoupMesh(600, 4)})}) {
    const std::vector<RayQuery> rays = mixedRays(soup, 300, 1);
    std::vector<BruteHit> truth;
    size_t hits = 0;
    for (const RayQuery& q : rays) {
      truth.push_back(bruteForce(soup, q));
      hits += truth.back().found;
    }
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(soup);
    const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
    checkTree(soup, {"ploc-gpu", packBvh(buildBvh("ploc-gpu", input, withRadius(4)), soup)}, rays, truth);
    EXPECT_GT(hits, rays.size() / 10);
    EXPECT_LT(hits, rays.size());
  }
}

// The command line: `builders` marks ploc-gpu as a GPU builder; `build --json` at a radius reports its
// GL-timed median, phases and pass counts and ploc's tree_hash at that radius; --ploc-top-down is a usage error.
TEST(GpuPlocCli, BuildJsonHasGpuTimesAndPlocsHash) {
  std::string obj;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) obj += "v " + std::to_string(i) + " " + std::to_string((i * j) % 7) + " " + std::to_string(j) + "\n";
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      const int a = i * 21 + j + 1, b = a + 1, c = a + 21, d = c + 1;
      obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + "\n";
      obj += "f " + std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(c) + "\n";
    }
  const std::string mesh = clitest::writeTemp("ploc_grid.obj", obj).string();
  const clitest::Result list = clitest::run("builders");
  ASSERT_EQ(list.code, 0) << list.err;
  EXPECT_NE(list.out.find("ploc-gpu     gpu"), std::string::npos) << list.out;
  const clitest::Result gpu = clitest::run("build --mesh " + mesh + " --builder ploc-gpu --ploc-radius 4 --json --gpu-builds 6");
  const clitest::Result cpu = clitest::run("build --mesh " + mesh + " --builder ploc --ploc-radius 4 --json");
  const clitest::Result cpu16 = clitest::run("build --mesh " + mesh + " --builder ploc --json");
  ASSERT_EQ(gpu.code, 0) << gpu.err;
  ASSERT_EQ(cpu.code, 0) << cpu.err;
  ASSERT_EQ(cpu16.code, 0) << cpu16.err;
  const nlohmann::json g = nlohmann::json::parse(gpu.out), c = nlohmann::json::parse(cpu.out),
                       c16 = nlohmann::json::parse(cpu16.out);
  EXPECT_EQ(g["primitives"], 800);
  EXPECT_EQ(g["tree_hash"], c["tree_hash"]);
  EXPECT_NE(c16["tree_hash"], c["tree_hash"]) << "the radius changes nothing here: the hash check proves less";
  const nlohmann::json& t = g["gpu_build_ms"];
  EXPECT_EQ(t["builds"], 6);
  EXPECT_LE(t["low"].get<double>(), t["median"].get<double>());
  EXPECT_LE(t["median"].get<double>(), t["high"].get<double>());
  for (const char* phase : {"morton", "sort", "clusters", "nn", "merge", "readback", "collapse"})
    EXPECT_TRUE(g["gpu_phases_ms"].contains(phase)) << phase;
  EXPECT_GT(g["gpu_passes"].get<int>(), 0);
  EXPECT_GE(g["gpu_passes_issued"].get<int>(), g["gpu_passes"].get<int>());
  EXPECT_GE(g["gpu_readbacks"].get<int>(), 1);
  const clitest::Result topDown = clitest::run("build --mesh " + mesh + " --builder ploc-gpu --ploc-top-down 4");
  EXPECT_EQ(topDown.code, 2);
  EXPECT_NE(topDown.err.find("--ploc-top-down"), std::string::npos) << topDown.err;
}

}  // namespace
}  // namespace bvhlab
