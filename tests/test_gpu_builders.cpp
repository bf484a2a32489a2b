// The GPU builders (builders/gpu/) on llvmpipe: lbvh-gpu builds lbvh's tree node for node (so the same
// tree_hash) on the bunny, on inputs full of equal Morton codes and on a 100k-triangle bench mesh; its
// radix sort alone against std::stable_sort; 0 and 1 primitives as the CPU builders; sizes past the
// GL limits refused before any work; registration.
#include <algorithm>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <glad/gl.h>

#include <nlohmann/json.hpp>

#include "builder_test_util.hpp"
#include "datasets/random_draws.hpp"
#include "gpu_builder_test_util.hpp"
#include "cli_run.hpp"
#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/bench_generators.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_lbvh.hpp"
#include "builders/gpu/gpu_radix_sort.hpp"
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

class GpuBuilders : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    registerGpuBuilders();
    context_ = createContext(Backend::OSMesa);
  }
  static void TearDownTestSuite() { context_.reset(); }
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> GpuBuilders::context_;

using testing::expectValidTree;
using testing::fromMesh;

// lbvh and lbvh-gpu through the registry (validation included): the same tree, and a valid one.
void expectSameAsLbvh(const BuildInput& input, const BuildOptions& options = {}) {
  const Bvh cpu = buildBvh("lbvh", input, options);
  const Bvh gpu = buildBvh("lbvh-gpu", input, options);
  expectValidTree(gpu, input, options.maxLeafSize);
  EXPECT_EQ(gpu.nodes.size(), cpu.nodes.size());
  EXPECT_TRUE(testing::identical(gpu, cpu)) << "lbvh-gpu's tree differs from lbvh's";
  EXPECT_EQ(sahCost(gpu, options.cost), sahCost(cpu, options.cost));
}

TEST_F(GpuBuilders, BunnyGivesLbvhsTreeAndTreeHash) {
  const std::filesystem::path path = testing::bunnyPath();
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  const TriangleSoup soup = gatherTriangles(loadInput(path));
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  expectSameAsLbvh(input);
  auto hash = [&](const std::string& builder) {
    PackedBvh packed = findLayout(kDefaultLayout).pack(buildBvh(builder, input, BuildOptions{}), soup);
    packTriangles(packed, soup, kDefaultTriangleFormat);
    return packedTreeHash(packed);
  };
  EXPECT_EQ(hash("lbvh-gpu"), hash("lbvh"));
}

TEST_F(GpuBuilders, OptionsAndGridsGiveLbvhsTree) {
  const PrimitiveSet set = testing::randomSoup(20000, 3);
  for (uint32_t leaf : {1u, 2u, 8u, 32u}) {
    BuildOptions o;
    o.maxLeafSize = leaf;
    SCOPED_TRACE(leaf);
    expectSameAsLbvh(set.input(), o);
  }
  BuildOptions axes;
  axes.mortonGrid = MortonGrid::Axes;
  expectSameAsLbvh(testing::gridSoup(120, 40).input(), axes);  // a flat scene: the axes grid differs from the cube
  // Centroids spread 1e-33 on x (2^21 / 1e-33 overflows a float: the CPU's scale is 0 there), 1e-30
  // on y (a finite scale near 2^21 / 1e-30) and 1 on z; with the axes grid each axis over its own.
  PrimitiveSet tiny;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 3000; ++i) {
    const glm::vec3 c = glm::vec3(1e-33f, 1e-30f, 1.0f) * draw3<glm::vec3>(u, rng);
    tiny.addTriangle(c, c + glm::vec3(0.0f, 0.0f, 1e-3f), c + glm::vec3(0.0f, 1e-31f, 0.0f));
  }
  expectSameAsLbvh(tiny.input(), axes);
  expectSameAsLbvh(tiny.input());
  BuildOptions costly;
  costly.cost.traversalCost = 3.0f, costly.cost.intersectionCost = 0.5f;
  expectSameAsLbvh(set.input(), costly);
}

// Runs of equal Morton codes of every length 1..64 (several primitives per grid cell, shuffled):
// Karras's tree splits them where lbvh splits them, in the middle.
TEST_F(GpuBuilders, EqualMortonCodesSplitInTheMiddleAsLbvh) {
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
  // Every primitive of a run gets the run's centroid (builders take the caller's centroids), so the
  // codes collide; the boxes differ, so the collapse still has choices to make.
  for (size_t i = 0; i < set.size(); ++i) set.centroids[i] = centres[i];
  expectSameAsLbvh(set.input());
  BuildOptions one;
  one.maxLeafSize = 1;
  expectSameAsLbvh(set.input(), one);

  PrimitiveSet same;  // every code equal: a tree of middle splits alone
  for (int i = 0; i < 1000; ++i) same.addTriangle(glm::vec3(i, 0, 0), glm::vec3(i, 1, 0), glm::vec3(i, 0, 1));
  for (glm::vec3& c : same.centroids) c = glm::vec3(0.5f);
  expectSameAsLbvh(same.input(), one);
  expectSameAsLbvh(same.input());
}

// A bench scene of 120k triangles (a terrain: many nearly equal codes along its flat regions).
TEST_F(GpuBuilders, BenchMeshOf120kTrianglesGivesLbvhsTree) {
  const PrimitiveSet set = fromMesh(generateBenchMesh("terrain", 120000, 1));
  ASSERT_GE(set.size(), 100000u);
  expectSameAsLbvh(set.input());
}

TEST_F(GpuBuilders, ZeroAndOnePrimitivesAsTheCpuBuilders) {
  PrimitiveSet empty;
  EXPECT_THROW(buildBvh("lbvh-gpu", empty.input(), {}), InputError);
  PrimitiveSet one;
  one.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  expectSameAsLbvh(one.input());
  PrimitiveSet two;
  two.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  two.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  BuildOptions leaf1;
  leaf1.maxLeafSize = 1;
  expectSameAsLbvh(two.input(), leaf1);
}

// The radix sort alone: random 63-bit codes drawn from few values in both halves (many duplicates,
// digits varying in every pass), against std::stable_sort by code. 257 x 4096 + 1 keys are 258 blocks:
// the per-digit scan's second chunk of 256 blocks, with the running total of the first.
TEST_F(GpuBuilders, RadixSortIsStdStableSort) {
  for (uint32_t n : {1u, 5u, 4096u, 4097u, 30000u, 257u * 4096u + 1u}) {
    SCOPED_TRACE(n);
    std::mt19937_64 rng(n);
    std::vector<uint64_t> values(37);
    for (uint64_t& v : values) v = rng() >> 1;
    std::vector<gpubuild::GpuKey> keys(n);
    for (uint32_t i = 0; i < n; ++i) {
      const uint64_t code = values[rng() % values.size()];
      keys[i] = {uint32_t(code >> 32), uint32_t(code), i};
    }
    const gpubuild::GpuRadixSort sort;
    GLuint buffers[3];
    buffers[0] = gpubuild::makeStorageBuffer(uint64_t(n) * 12, keys.data());
    buffers[1] = gpubuild::makeStorageBuffer(uint64_t(n) * 12);
    buffers[2] = gpubuild::makeStorageBuffer(gpubuild::GpuRadixSort::countBytes(n));
    sort.sort(buffers[0], buffers[1], buffers[2], n);
    std::vector<gpubuild::GpuKey> sorted(n);
    glGetNamedBufferSubData(buffers[0], 0, GLsizeiptr(n * 12), sorted.data());
    for (GLuint slot = 0; slot < 3; ++slot) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot, 0);
    glDeleteBuffers(3, buffers);
    checkGl("reading the sorted keys");
    auto code = [](const gpubuild::GpuKey& k) { return uint64_t(k.hi) << 32 | k.lo; };
    std::stable_sort(keys.begin(), keys.end(), [&](const auto& a, const auto& b) { return code(a) < code(b); });
    size_t differ = 0;
    for (uint32_t i = 0; i < n; ++i) differ += sorted[i].hi != keys[i].hi || sorted[i].lo != keys[i].lo || sorted[i].id != keys[i].id;
    EXPECT_EQ(differ, 0u);
  }
}

TEST_F(GpuBuilders, SizesPastTheGlLimitsAreRefusedBeforeAnyWork) {
  const PrimitiveSet set = testing::randomSoup(5000, 2);
  const gpubuild::GpuLimits real = gpubuild::queryGpuLimits();
  EXPECT_GT(real.maxStorageBlockBytes, 0u);
  EXPECT_GT(real.maxWorkGroupsX, 0u);
  try {  // the node boxes need (2n - 1) * 24 bytes
    gpubuild::GpuLbvh(gpubuild::GpuLimits{5000 * 24, real.maxWorkGroupsX}).build(set.input(), {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << e.what();
  }
  try {  // 5000 primitives are 20 workgroups of 256
    gpubuild::GpuLbvh(gpubuild::GpuLimits{real.maxStorageBlockBytes, 19}).build(set.input(), {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("GL_MAX_COMPUTE_WORK_GROUP_COUNT"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(gpubuild::GpuLbvh(gpubuild::GpuLimits{real.maxStorageBlockBytes, 20}).build(set.input(), {}));
  BuildOptions sized;
  sized.mortonSizeBits = 3;
  EXPECT_THROW(buildBvh("lbvh-gpu", set.input(), sized), std::invalid_argument);
}

// A GL error surfaces as an exception naming the step it was found in (here one left pending before
// the build, found by the first check, after the upload).
TEST_F(GpuBuilders, AGlErrorNamesTheStep) {
  const PrimitiveSet set = testing::randomSoup(100, 8);
  const gpubuild::GpuLbvh lbvh;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 987654321u);  // never generated: GL_INVALID_OPERATION in a core profile
  try {
    lbvh.build(set.input(), {});
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("GL_INVALID_OPERATION in lbvh-gpu: uploading the input"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(testing::identical(lbvh.build(set.input(), {}), buildBvh("lbvh", set.input(), {})));  // and goes on
}

TEST_F(GpuBuilders, RegisteredAsAGpuBuilderAndTimedPerPhase) {
  EXPECT_TRUE(findBuilder("lbvh-gpu").gpu);
  EXPECT_FALSE(findBuilder("lbvh").gpu);
  const PrimitiveSet set = testing::randomSoup(3000, 4);
  const GpuBuildTiming t = timeGpuBuild("lbvh-gpu", set.input(), {}, 6);
  ASSERT_TRUE(t.totalMs.has_value());
  EXPECT_LE(t.totalMs->low, t.totalMs->estimate);
  EXPECT_LE(t.totalMs->estimate, t.totalMs->high);
  ASSERT_EQ(t.phaseMedianMs.size(), 5u);
  EXPECT_EQ(t.phaseMedianMs[0].first, "morton");
  EXPECT_EQ(t.phaseMedianMs[4].first, "collapse");
  for (const auto& [phase, ms] : t.phaseMedianMs) EXPECT_GE(ms, 0.0) << phase;
  EXPECT_GT(t.medianMs, 0.0);
  EXPECT_THROW(timeGpuBuild("lbvh", set.input(), {}, 6), std::invalid_argument);
}

// Builder x kernel against brute force for lbvh-gpu's trees (test_traversal runs the CPU builders;
// its executable does not register the GPU builders): every kernel's closest and any hit on a sphere
// and a random soup equal brute force's.
TEST_F(GpuBuilders, EveryKernelOnLbvhGpuTreesFindsTheBruteForceHits) {
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
    checkTree(soup, {"lbvh-gpu", packBvh(buildBvh("lbvh-gpu", input, BuildOptions{}), soup)}, rays, truth);
    EXPECT_GT(hits, rays.size() / 10);
    EXPECT_LT(hits, rays.size());
  }
}

// Without a current context the registry's lbvh-gpu makes its own (as `bvhlab build` runs it).
TEST(GpuBuildersNoContext, BuildsInAHeadlessContextOfItsOwn) {
  registerGpuBuilders();
  const PrimitiveSet set = testing::randomSoup(2000, 6);
  EXPECT_TRUE(testing::identical(buildBvh("lbvh-gpu", set.input(), {}), buildBvh("lbvh", set.input(), {})));
}

// The command line: `builders` marks lbvh-gpu as a GPU builder; `build --json` reports its GL-timed
// median with an interval and the phases, and the same tree_hash as lbvh; size bits are a usage error.
TEST(GpuBuildersCli, BuildJsonHasGpuTimesAndLbvhsHash) {
  std::string obj;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) obj += "v " + std::to_string(i) + " " + std::to_string((i * j) % 7) + " " + std::to_string(j) + "\n";
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      const int a = i * 21 + j + 1, b = a + 1, c = a + 21, d = c + 1;
      obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + "\n";
      obj += "f " + std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(c) + "\n";
    }
  const std::string mesh = clitest::writeTemp("grid.obj", obj).string();
  const clitest::Result list = clitest::run("builders");
  ASSERT_EQ(list.code, 0) << list.err;
  EXPECT_NE(list.out.find("lbvh-gpu     gpu"), std::string::npos) << list.out;
  EXPECT_NE(list.out.find("lbvh         cpu"), std::string::npos) << list.out;
  const clitest::Result gpu = clitest::run("build --mesh " + mesh + " --builder lbvh-gpu --json --gpu-builds 6");
  const clitest::Result cpu = clitest::run("build --mesh " + mesh + " --builder lbvh --json");
  ASSERT_EQ(gpu.code, 0) << gpu.err;
  ASSERT_EQ(cpu.code, 0) << cpu.err;
  const nlohmann::json g = nlohmann::json::parse(gpu.out), c = nlohmann::json::parse(cpu.out);
  EXPECT_EQ(g["primitives"], 800);
  EXPECT_EQ(g["tree_hash"], c["tree_hash"]);
  EXPECT_FALSE(c.contains("gpu_build_ms"));
  const nlohmann::json& t = g["gpu_build_ms"];
  EXPECT_EQ(t["builds"], 6);
  EXPECT_LE(t["low"].get<double>(), t["median"].get<double>());
  EXPECT_LE(t["median"].get<double>(), t["high"].get<double>());
  EXPECT_GT(t["median"].get<double>(), 0.0);
  for (const char* phase : {"morton", "sort", "hierarchy", "fit", "collapse"})
    EXPECT_TRUE(g["gpu_phases_ms"].contains(phase)) << phase;
  const clitest::Result sized = clitest::run("build --mesh " + mesh + " --builder lbvh-gpu --morton-size-bits 2");
  EXPECT_EQ(sized.code, 2);
  EXPECT_NE(sized.err.find("--morton-size-bits"), std::string::npos) << sized.err;
}

}  // namespace
}  // namespace bvhlab
