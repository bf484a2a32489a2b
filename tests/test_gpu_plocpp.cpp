// plocpp-gpu (builders/gpu/gpu_ploc.hpp, PlocPasses::Fused; gpubuild_ploc_fused.glsl) on llvmpipe:
// ploc's tree node for node with each clustering pass one fused kernel, at radii whose boxes fit in
// shared memory and past them, on the bunny, synthetic inputs, runs of equal codes and 1 and 2
// primitives; a pass whose look-back gives up runs again split and the tree is the same (forced in
// one pass, and as llvmpipe makes it happen with more threads than cores); every kernel on its trees
// against brute force; `builders` and `build --json`.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "builder_test_util.hpp"
#include "builders/builder.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_ploc.hpp"
#include "builders/test_inputs.hpp"
#include "cli_run.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "gpu_builder_test_util.hpp"
#include "layout/layout.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"
#include "traversal_test_util.hpp"

namespace bvhlab {
namespace {

using testing::PrimitiveSet;
[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

class GpuPlocpp : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    registerGpuBuilders();
    context_ = createContext(Backend::OSMesa);
  }
  static void TearDownTestSuite() { context_.reset(); }
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> GpuPlocpp::context_;

using testing::withRadius;
void expectSameAsPloc(const BuildInput& input, const BuildOptions& options = {}) {
  testing::expectSameAsPloc("plocpp-gpu", input, options);
}

TEST_F(GpuPlocpp, TheBunnyGivesPlocsTree) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  const TriangleSoup soup = gatherTriangles(loadInput(path));
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  for (uint32_t radius : {1u, 16u}) {
    SCOPED_TRACE(radius);
    expectSameAsPloc(BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, withRadius(radius));
  }
}

// A random soup over many workgroups and a flat grid (the tie key decides), at radii with the boxes in
// shared memory (up to 64) and read from the storage buffer (65 and the largest); other leaf sizes.
TEST_F(GpuPlocpp, SyntheticInputsGivePlocsTreeAtEveryRadius) {
  const PrimitiveSet soup = testing::randomSoup(6000, 3), grid = testing::gridSoup(60, 40);
  for (uint32_t radius : {1u, 4u, 64u, 65u}) {
    SCOPED_TRACE(radius);
    expectSameAsPloc(soup.input(), withRadius(radius));
    expectSameAsPloc(grid.input(), withRadius(radius));
  }
  BuildOptions leaf1;
  leaf1.maxLeafSize = 1;
  expectSameAsPloc(soup.input(), leaf1);
  expectSameAsPloc(testing::randomSoup(700, 5).input(), withRadius(kMaxPlocRadius));
}

TEST_F(GpuPlocpp, EqualCodesAndOneOrTwoPrimitives) {
  PrimitiveSet same;
  for (int i = 0; i < 1000; ++i) same.addTriangle(glm::vec3(i, 0, 0), glm::vec3(i, 1, 0), glm::vec3(i, 0, 1));
  for (glm::vec3& c : same.centroids) c = glm::vec3(0.5f);
  expectSameAsPloc(same.input());
  PrimitiveSet one, two;
  one.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  expectSameAsPloc(one.input());
  two.addTriangle(glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  two.addTriangle(glm::vec3(2, 0, 0), glm::vec3(3, 0, 0), glm::vec3(2, 1, 0));
  expectSameAsPloc(two.input());
}

// A look-back that gives up (forced here in one pass; llvmpipe ends long waits on its own): the pass
// runs again with the split kernels, counted, and the tree is ploc's all the same. Forced in the first
// pass and in a later one, where the input is the other cluster buffer.
TEST_F(GpuPlocpp, APassWhoseLookBackGivesUpRunsAgainSplit) {
  const PrimitiveSet set = testing::randomSoup(5000, 7);  // 20 workgroups: block 1 exists
  const Bvh cpu = buildBvh("ploc", set.input(), withRadius(4));
  gpubuild::GpuPloc fused(std::nullopt, gpubuild::PlocPasses::Fused);
  for (uint32_t pass : {0u, 1u, 2u}) {
    SCOPED_TRACE("given up in pass " + std::to_string(pass + 1));
    fused.giveUpInPass(pass);
    gpubuild::GpuPhaseTimes times;
    const Bvh gpu = fused.build(set.input(), withRadius(4), &times);
    EXPECT_TRUE(testing::identical(gpu, cpu)) << "the tree after a fallback differs from ploc's";
    EXPECT_GE(times.fusedFallbacks, 1u);
    bool split = false;
    for (const auto& [phase, ms] : times.phases) split = split || phase == "nn";
    EXPECT_TRUE(split) << "no split pass ran: the fallback was not taken";
  }
  fused.giveUpInPass(~0u);
}

TEST_F(GpuPlocpp, EveryKernelOnItsTreesFindsTheBruteForceHits) {
  using namespace traversaltest;
  const TriangleSoup soup = soupOf({sphereMesh(16, 32, 1.0f), randomSoupMesh(600, 4)});
  const std::vector<RayQuery> rays = mixedRays(soup, 300, 1);
  std::vector<BruteHit> truth;
  for (const RayQuery& q : rays) truth.push_back(bruteForce(soup, q));
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  checkTree(soup, {"plocpp-gpu", packBvh(buildBvh("plocpp-gpu", input, withRadius(4)), soup)}, rays, truth);
}

TEST_F(GpuPlocpp, RegisteredAsAGpuBuilderWithOnePhaseForThePasses) {
  EXPECT_TRUE(findBuilder("plocpp-gpu").gpu);
  EXPECT_TRUE(findBuilder("plocpp-gpu").usesPlocRadius);
  const PrimitiveSet set = testing::randomSoup(3000, 4);
  const GpuBuildTiming t = timeGpuBuild("plocpp-gpu", set.input(), withRadius(4), 6);
  ASSERT_TRUE(t.totalMs.has_value());
  std::vector<std::string> names;
  for (const auto& [phase, ms] : t.phaseMedianMs) names.push_back(phase);
  ASSERT_GE(names.size(), 4u);
  EXPECT_EQ(names[3], "passes");
  EXPECT_GT(t.passes, 5u);
  if (t.fusedFallbacks == 0)  // a fallback adds the split passes' phases
    EXPECT_EQ(names, (std::vector<std::string>{"morton", "sort", "clusters", "passes", "readback", "collapse"}));
}

// `build --json` as for ploc-gpu plus gpu_fused_fallbacks; with llvmpipe running 8 threads on this
// machine's cores (waits the OS stretches past llvmpipe's loop bound) the tree is still ploc's.
TEST(GpuPlocppCli, BuildJsonGivesPlocsHashAlsoOnAnOversubscribedLlvmpipe) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  const clitest::Result list = clitest::run("builders");
  ASSERT_EQ(list.code, 0) << list.err;
  EXPECT_NE(list.out.find("plocpp-gpu"), std::string::npos) << list.out;
  const std::string args = "build --mesh " + path.string() + " --ploc-radius 2 --json";
  const clitest::Result cpu = clitest::run(args + " --builder ploc");
  ASSERT_EQ(cpu.code, 0) << cpu.err;
  const std::string want = nlohmann::json::parse(cpu.out)["tree_hash"];
  for (const char* threads : {"", "LP_NUM_THREADS=8 "}) {
    SCOPED_TRACE(threads);
    const clitest::Result gpu = clitest::run(args + " --builder plocpp-gpu --gpu-builds 2", threads);
    ASSERT_EQ(gpu.code, 0) << gpu.err;
    const nlohmann::json g = nlohmann::json::parse(gpu.out);
    EXPECT_EQ(g["tree_hash"], want);
    EXPECT_TRUE(g["gpu_fused_fallbacks"].is_number_unsigned());
    EXPECT_TRUE(g["gpu_phases_ms"].contains("passes"));
  }
}

}  // namespace
}  // namespace bvhlab
