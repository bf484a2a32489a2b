// hploc-gpu (builders/gpu/gpu_hploc.hpp; gpubuild_hploc.glsl) on llvmpipe: hploc's tree node for node
// on the bunny, synthetic inputs (ties, runs of equal codes, signed zeros), radii inside and past one
// workgroup, and 1 to 33 primitives; its packs on the GPU equal the CPU's; the limits and options it
// refuses; a GL error named; every kernel on its trees against brute force; `builders` and
// `build --json`.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "builder_test_util.hpp"
#include "builders/builder.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_hploc.hpp"
#include "builders/hploc.hpp"
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
using testing::withRadius;
[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

class GpuHploc : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    registerGpuBuilders();
    context_ = createContext(Backend::OSMesa);
  }
  static void TearDownTestSuite() { context_.reset(); }
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> GpuHploc::context_;

// hploc and hploc-gpu through the registry (validation included): the same tree, and a valid one.
void expectSameAsHploc(const BuildInput& input, const BuildOptions& options = {}) {
  const Bvh cpu = buildBvh("hploc", input, options);
  const Bvh gpu = buildBvh("hploc-gpu", input, options);
  testing::expectValidTree(gpu, input, options.maxLeafSize);
  EXPECT_TRUE(testing::identical(gpu, cpu)) << "hploc-gpu's tree differs from hploc's";
  EXPECT_EQ(sahCost(gpu, options.cost), sahCost(cpu, options.cost));
}

TEST_F(GpuHploc, TheBunnyGivesHplocsTree) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  const TriangleSoup soup = gatherTriangles(loadInput(path));
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  for (uint32_t radius : {1u, 16u}) {
    SCOPED_TRACE(radius);
    expectSameAsHploc(BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, withRadius(radius));
  }
}

// Many workgroups; a flat grid (the tie key decides); runs of equal codes (the radix tree's own
// nodes, balanced by position); -0 beside +0; radii within a list and past it; leaf size 1.
TEST_F(GpuHploc, SyntheticInputsGiveHplocsTree) {
  PrimitiveSet equalCodes = testing::randomSoup(3000, 8);
  for (int i = 0; i < 900; ++i) equalCodes.addBox(equalCodes.boxes[i % 5], equalCodes.centroids[i % 5]);
  PrimitiveSet zeros;
  for (int i = 0; i < 2000; ++i) {
    const float z = i % 3 ? 0.0f : -0.0f, t = float(i % 40);
    zeros.addBox({glm::vec3(z, t, z), glm::vec3(z, t, i % 7 ? z : 1.0f)}, glm::vec3(z, t, z));
  }
  const PrimitiveSet soup = testing::randomSoup(6000, 3), grid = testing::gridSoup(60, 40);
  for (uint32_t radius : {1u, 4u, 31u}) {
    SCOPED_TRACE(radius);
    expectSameAsHploc(soup.input(), withRadius(radius));
    expectSameAsHploc(grid.input(), withRadius(radius));
  }
  expectSameAsHploc(equalCodes.input());
  expectSameAsHploc(zeros.input());
  PrimitiveSet nested;  // one centroid, nested boxes: one code, so the radix tree's nodes (balanced)
  for (int i = 0; i < 3000; ++i) {
    const float s = 0.001f * float(1 + i % 17);
    nested.addBox({glm::vec3(-s), glm::vec3(s)}, glm::vec3(0.0f));
  }
  expectSameAsHploc(nested.input());
  EXPECT_LE(computeStats(buildBvh("hploc-gpu", nested.input(), {}), CostModel{}).depth, 14u);
  BuildOptions leaf1;
  leaf1.maxLeafSize = 1;
  expectSameAsHploc(soup.input(), leaf1);
  expectSameAsHploc(testing::randomSoup(700, 5).input(), withRadius(kMaxPlocRadius));
}

// 1 primitive (one leaf, nothing on the GPU), 2, a list that fills a group exactly (kGroup), one past
// it, and every count up to kKeep + 2 (the first subtree that is clustered).
TEST_F(GpuHploc, OneToThirtyThreePrimitives) {
  for (size_t n : {size_t(1), size_t(2), size_t(3), size_t(detail::hploc::kKeep), size_t(detail::hploc::kKeep + 1),
                   size_t(detail::hploc::kKeep + 2), size_t(detail::hploc::kGroup), size_t(detail::hploc::kGroup + 1)}) {
    SCOPED_TRACE(n);
    expectSameAsHploc(testing::randomSoup(n, uint32_t(n)).input());
  }
}

TEST_F(GpuHploc, SizesPastTheGlLimitsAndUnsupportedOptionsAreRefused) {
  const PrimitiveSet set = testing::randomSoup(5000, 2);
  const gpubuild::GpuLimits real = gpubuild::queryGpuLimits();
  auto expectRefusal = [&](const gpubuild::GpuLimits& limits, const BuildOptions& options, const std::string& names) {
    const gpubuild::GpuHploc hploc(limits);
    try {
      hploc.build(set.input(), options);
      ADD_FAILURE() << "no error for " << names;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  // The node boxes need (2n - 1) * 24 bytes; the hierarchy 157 workgroups of 32.
  expectRefusal({(2 * 5000 - 1) * 24 - 1, real.maxWorkGroupsX}, {}, "GL_MAX_SHADER_STORAGE_BLOCK_SIZE");
  expectRefusal({real.maxStorageBlockBytes, 156}, {}, "GL_MAX_COMPUTE_WORK_GROUP_COUNT");
  EXPECT_NO_THROW(gpubuild::GpuHploc(gpubuild::GpuLimits{real.maxStorageBlockBytes, 157}).build(set.input(), {}));
  BuildOptions sized, topDown;
  sized.mortonSizeBits = 3;
  topDown.plocTopDown = 4;
  expectRefusal(real, sized, "--morton-size-bits");
  expectRefusal(real, topDown, "--ploc-top-down");
  expectRefusal(real, withRadius(0), "plocRadius 0");
  EXPECT_THROW(buildBvh("hploc-gpu", set.input(), sized), std::invalid_argument);
}

TEST_F(GpuHploc, AGlErrorNamesTheStep) {
  const PrimitiveSet set = testing::randomSoup(100, 8);
  const gpubuild::GpuHploc hploc;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 987654321u);  // never generated: GL_INVALID_OPERATION in a core profile
  try {
    hploc.build(set.input(), {});
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("GL_INVALID_OPERATION in hploc-gpu: uploading the input"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(testing::identical(hploc.build(set.input(), {}), buildBvh("hploc", set.input(), {})));
}

// Timed per phase, one dispatch for the whole hierarchy; packed on the GPU into v1, bvh2-cb and cwbvh, where
// timeGpuBuild compares every texel with the CPU's pack of the same tree (and throws at the first
// difference).
TEST_F(GpuHploc, RegisteredTimedPerPhaseAndPackedAsTheCpuPacks) {
  EXPECT_TRUE(findBuilder("hploc-gpu").gpu);
  EXPECT_TRUE(findBuilder("hploc-gpu").usesPlocRadius);
  EXPECT_FALSE(findBuilder("hploc").gpu);
  const TriangleSoup soup = traversaltest::soupOf({traversaltest::randomSoupMesh(3000, 4)});
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  const GpuBuildTiming t = timeGpuBuild("hploc-gpu", input, withRadius(4), 6);  // 6: enough for an interval
  ASSERT_TRUE(t.totalMs.has_value());
  EXPECT_LE(t.totalMs->low, t.totalMs->estimate);
  EXPECT_LE(t.totalMs->estimate, t.totalMs->high);
  std::vector<std::string> names;
  for (const auto& [phase, ms] : t.phaseMedianMs) names.push_back(phase);
  EXPECT_EQ(names, (std::vector<std::string>{"morton", "sort", "hierarchy", "collapse"}));
  EXPECT_EQ(t.readbacks, 0u);
  for (const char* layout : {"v1", "bvh2-cb", "cwbvh"}) {
    SCOPED_TRACE(layout);
    const GpuBuildTiming packed = timeGpuBuild("hploc-gpu", input, withRadius(4), 1, layout, &soup);
    EXPECT_EQ(packed.packLayout, layout);
    EXPECT_EQ(packed.phaseMedianMs.back().first, std::string(layout) == "cwbvh" ? "wide_nodes" : "pack");
  }
}

TEST_F(GpuHploc, EveryKernelOnItsTreesFindsTheBruteForceHits) {
  using namespace traversaltest;
  const TriangleSoup soup = soupOf({sphereMesh(16, 32, 1.0f), randomSoupMesh(600, 4)});
  const std::vector<RayQuery> rays = mixedRays(soup, 300, 1);
  std::vector<BruteHit> truth;
  for (const RayQuery& q : rays) truth.push_back(bruteForce(soup, q));
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  checkTree(soup, {"hploc-gpu", packBvh(buildBvh("hploc-gpu", input, withRadius(4)), soup)}, rays, truth);
}

TEST(GpuHplocCli, BuildJsonGivesHplocsHash) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " is missing: run `bash datasets/fetch.sh`");
  const clitest::Result list = clitest::run("builders");
  ASSERT_EQ(list.code, 0) << list.err;
  EXPECT_NE(list.out.find("hploc-gpu"), std::string::npos) << list.out;
  const std::string args = "build --mesh " + path.string() + " --ploc-radius 2 --json";
  const clitest::Result cpu = clitest::run(args + " --builder hploc");
  ASSERT_EQ(cpu.code, 0) << cpu.err;
  const clitest::Result gpu = clitest::run(args + " --builder hploc-gpu --gpu-builds 2");
  ASSERT_EQ(gpu.code, 0) << gpu.err;
  const nlohmann::json c = nlohmann::json::parse(cpu.out), g = nlohmann::json::parse(gpu.out);
  EXPECT_EQ(g["tree_hash"], c["tree_hash"]);
  EXPECT_EQ(g["sah_cost"], c["sah_cost"]);
  EXPECT_TRUE(g["gpu_phases_ms"].contains("hierarchy"));
  EXPECT_EQ(g["gpu_build_ms"]["builds"], 2);
}

}  // namespace
}  // namespace bvhlab
