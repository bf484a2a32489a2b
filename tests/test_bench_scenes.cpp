// The benchmark scene suite (datasets/scenes/bench/): the generators give exactly the
// triangles asked for, deterministically; the scene format's generate key and its errors; every bench
// scene loads with the triangle count its README states and a camera that sees triangles.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "datasets/bench_generators.hpp"
#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "experiments/generated_scenes.hpp"
#include "layout/layout.hpp"
#include "render/workloads.hpp"
#include "traversal/embree_tracer.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

namespace fs = std::filesystem;
const fs::path kBench = fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes/bench";

// ---- generators ----

TEST(BenchGenerators, EveryGeneratorGivesExactlyTheRequestedTriangles) {
  // Sizes that land on and off every generator's structure (rooms, strands, grid rows, knot rings).
  for (const BenchGenerator& g : benchGenerators())
    for (uint64_t n : {uint64_t(1000), uint64_t(1001), uint64_t(4097), uint64_t(20011)}) {
      const Mesh m = generateBenchMesh(g.name, int64_t(n), 7);
      ASSERT_EQ(m.triangles.size(), n) << g.name;
      for (const glm::uvec3& t : m.triangles)
        ASSERT_TRUE(t.x < m.positions.size() && t.y < m.positions.size() && t.z < m.positions.size()) << g.name;
      for (const glm::vec3& p : m.positions)
        ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << g.name;
    }
}

// The boxes the header documents.
TEST(BenchGenerators, MeshesLieWhereTheHeaderSays) {
  auto bounds = [](const Mesh& m) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : m.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
    return std::pair{lo, hi};
  };
  auto [hlo, hhi] = bounds(makeHairball(20000, 3));
  EXPECT_LE(glm::max(glm::length(hlo), glm::length(hhi)), 1.8f);  // corners of a box inside the unit ball
  EXPECT_LE(std::max({-hlo.x, -hlo.y, -hlo.z, hhi.x, hhi.y, hhi.z}), 1.01f);
  auto [tlo, thi] = bounds(makeTerrain(20000, 3));
  EXPECT_GE(tlo.y, 0.0f);
  EXPECT_LE(thi.y, 160.0f);
  EXPECT_GT(thi.y - tlo.y, 40.0f);  // real relief, not a flat grid
  EXPECT_FLOAT_EQ(tlo.x, -500.0f);
  EXPECT_FLOAT_EQ(thi.x, 500.0f);
  // Stadium: the bowl reaches r = 1000; all but the enclosure's triangles are within 1.3 of the centre.
  const Mesh s = makeStadium(50000, 3);
  auto [slo, shi] = bounds(s);
  EXPECT_NEAR(shi.x, 1000.0f, 5.0f);
  size_t dense = 0;
  for (const glm::uvec3& t : s.triangles)
    if (glm::length(s.positions[t.x] - glm::vec3(0, 1.2f, 0)) < 1.3f) ++dense;
  EXPECT_GE(dense, s.triangles.size() - 4096);
  EXPECT_LE(dense, s.triangles.size() - 50000 / 16 + 64);  // the enclosure is really there
}

TEST(BenchGenerators, SameSeedSameMeshOtherSeedOtherMesh) {
  for (const BenchGenerator& g : benchGenerators()) {
    const uint64_t a = meshContentHash(generateBenchMesh(g.name, 5000, 1));
    EXPECT_EQ(a, meshContentHash(generateBenchMesh(g.name, 5000, 1))) << g.name;
    EXPECT_NE(a, meshContentHash(generateBenchMesh(g.name, 5000, 2))) << g.name;
  }
}

// The generated meshes are pinned by their content hash, so a generator that changes what a seed makes
// fails here, with every compiler. In particular the random draws are made in a fixed order
// (SplitMix64::uniform3, datasets/random_draws.hpp): with three draws as the arguments of one glm::vec3
// constructor, the sanitizer's clang build made other soup, large, interior, hairball and stadium
// meshes than GCC's from the same seeds. A deliberate change to a generator updates these values (and
// makes new bench results: the meshes are part of every scene that generates them).
TEST(BenchGenerators, SeedsMakeTheSameMeshesWithEveryCompiler) {
  const std::map<std::string, uint64_t> pinned = {
      {"stadium", 0x8032fc2be06c868aull}, {"interior", 0xaaccd5304c96cf11ull}, {"hairball", 0xc164c233281afa42ull},
      {"terrain", 0xab6acb56f9cada40ull}, {"scaling", 0x8884435dd4c697a5ull}};
  for (const BenchGenerator& g : benchGenerators()) {
    ASSERT_TRUE(pinned.count(g.name)) << "no pinned hash for generator " << g.name;
    const uint64_t hash = meshContentHash(generateBenchMesh(g.name, 5000, 1));
    EXPECT_EQ(hash, pinned.at(g.name)) << g.name << std::hex << " hash 0x" << hash;
  }
  const uint64_t soup = meshContentHash(makeTriangleSoup(3000, 5));
  EXPECT_EQ(soup, 0x7efd6084f7955627ull) << std::hex << "soup hash 0x" << soup;
}

TEST(BenchGenerators, RequestsOutOfRangeAndUnknownNamesAreErrorsNamingTheGenerator) {
  for (const BenchGenerator& g : benchGenerators())
    for (int64_t n : {int64_t(-5), int64_t(0), int64_t(kMinBenchTriangles) - 1,
                      int64_t(kMaxProceduralTriangles) + 1, int64_t(1) << 40}) {
      try {
        generateBenchMesh(g.name, n, 1);
        ADD_FAILURE() << g.name << " accepted " << n;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("generator '" + g.name + "'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(std::to_string(n)), std::string::npos) << e.what();
      }
    }
  try {
    generateBenchMesh("teapot", 5000, 1);
    ADD_FAILURE() << "unknown generator accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("known: stadium, interior"), std::string::npos) << e.what();
  }
}

TEST(BenchGenerators, ExperimentConfigsKnowTheNewKinds) {
  const auto& kinds = generatedMeshKinds();
  for (const BenchGenerator& g : benchGenerators())
    EXPECT_NE(std::find(kinds.begin(), kinds.end(), g.name), kinds.end()) << g.name;
  const Mesh m = generateMesh(nlohmann::json{{"generate", "terrain"}, {"triangles", 3000}, {"seed", 4}});
  EXPECT_EQ(m.triangles.size(), 3000u);
  EXPECT_EQ(meshContentHash(m), meshContentHash(generateBenchMesh("terrain", 3000, 4)));
}

// ---- the scene format's generate key ----

fs::path writeScene(const std::string& name, const std::string& object) {
  const fs::path p = fs::temp_directory_path() / ("bvhlab_bench_" + name + ".toml");
  std::ofstream(p) << "[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n\n[[object]]\nkind = \"mesh\"\n" << object;
  return p;
}

std::string loadError(const fs::path& p) {
  try {
    loadScene(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(BenchSceneFormat, GenerateKeyBuildsTheMesh) {
  const Scene s = loadScene(writeScene("ok", "generate = \"hairball\"\ntriangles = 2000\nseed = 5\nfit = 2\n"));
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].triangles.size(), 2000u);
}

TEST(BenchSceneFormat, GenerateErrorsNameFileLineAndKey) {
  const fs::path unknown = writeScene("unknown", "generate = \"teapot\"\ntriangles = 2000\n");
  std::string e = loadError(unknown);
  EXPECT_NE(e.find(unknown.string() + ":7:"), std::string::npos) << e;
  EXPECT_NE(e.find(".generate: unknown generator \"teapot\""), std::string::npos) << e;
  for (const std::string& n : {std::string("10"), std::string("1099511627776"), std::string("-3")}) {
    const fs::path range = writeScene("range", "generate = \"terrain\"\ntriangles = " + n + "\n");
    e = loadError(range);
    EXPECT_NE(e.find(range.string() + ":8:"), std::string::npos) << e;
    EXPECT_NE(e.find(".triangles: generator 'terrain'"), std::string::npos) << e;
  }
  e = loadError(writeScene("missing", "generate = \"terrain\"\n"));
  EXPECT_NE(e.find("needs triangles = N"), std::string::npos) << e;
  e = loadError(writeScene("float", "generate = \"terrain\"\ntriangles = 2000.5\n"));
  EXPECT_NE(e.find(".triangles must be an integer"), std::string::npos) << e;
  e = loadError(writeScene("both", "generate = \"terrain\"\nmesh = \"x.off\"\ntriangles = 2000\n"));
  EXPECT_NE(e.find("not both"), std::string::npos) << e;
  e = loadError(writeScene("seed", "generate = \"terrain\"\ntriangles = 2000\nseed = -1\n"));
  EXPECT_NE(e.find(".seed must be a non-negative integer"), std::string::npos) << e;
  const fs::path foreign = fs::temp_directory_path() / "bvhlab_bench_foreign.toml";
  std::ofstream(foreign) << "[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n[[object]]\nkind = \"sphere\"\ntriangles = 5\n";
  e = loadError(foreign);
  EXPECT_NE(e.find("key 'triangles' is only valid with kind = \"mesh\""), std::string::npos) << e;
}

// ---- the shipped suite ----

// "| file.toml | 123,456 | ..." rows of the suite's README: the documented triangle counts.
std::map<std::string, uint64_t> documentedCounts() {
  std::ifstream in(kBench / "README.md");
  std::map<std::string, uint64_t> out;
  const std::regex row(R"(^\|\s*`?([a-z0-9_A-Z-]+\.toml)`?\s*\|\s*([0-9,]+)\s*\|)");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    std::string digits = m[2];
    digits.erase(std::remove(digits.begin(), digits.end(), ','), digits.end());
    out[m[1]] = std::stoull(digits);
  }
  return out;
}

TEST(BenchSuite, ReadmeDocumentsEverySceneFile) {
  const auto counts = documentedCounts();
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(kBench))
    if (entry.path().extension() == ".toml") {
      ++files;
      EXPECT_TRUE(counts.count(entry.path().filename().string())) << entry.path() << " missing from README.md";
    }
  EXPECT_GE(files, 8u);
  EXPECT_EQ(counts.size(), files);
}

// Scenes too large to build in a unit test: their count is the file's `triangles` (the generators are
// exact, tested above at small sizes), checked against the README without generating them.
const std::set<std::string> kTooLargeForATest = {"scaling_1M.toml", "scaling_10M.toml"};

class BenchScene : public ::testing::TestWithParam<std::string> {};

TEST_P(BenchScene, LoadsWithTheDocumentedCountAndItsCameraSeesTriangles) {
  const std::string file = GetParam();
  const uint64_t documented = documentedCounts().at(file);
  std::ifstream in(kBench / file);
  std::stringstream text;
  text << in.rdbuf();
  const bool generated = text.str().find("generate = ") != std::string::npos;
  if (kTooLargeForATest.count(file)) {
    EXPECT_NE(text.str().find("triangles = " + std::to_string(documented) + "\n"), std::string::npos);
    return;
  }
  Scene scene;
  try {
    scene = loadScene(kBench / file);
  } catch (const InputError& e) {
    const std::string what = e.what();
    // Only file-based scenes may be skipped, and only for data this machine has not fetched (or the AC3D
    // importer, for the ship, not being built in); under BVHLAB_REQUIRE_ALL=1 (CI) that too fails.
    if (!generated && (what.find("fetch.sh") != std::string::npos || what.find("not found") != std::string::npos ||
                       what.find("unsupported mesh format") != std::string::npos))
      BVHLAB_SKIP_OR_FAIL(file << ": " << what);
    FAIL() << what;
  }
  const TriangleSoup soup = gatherTriangles(scene);
  EXPECT_EQ(soup.size(), documented) << file;
  EmbreeTracer embree(soup, 2);
  WorkloadRequest r;
  r.workload = Workload::Primary;
  r.count = 4096;
  r.width = scene.settings.width;
  r.height = scene.settings.height;
  const RayWorkload w = generateWorkload(r, scene, soup, [&embree](const std::vector<BatchRay>& rays) {
    std::vector<BatchHit> hits;
    embree.closest(rays, hits);
    return hits;
  });
  std::vector<BatchHit> hits;
  embree.closest(w.rays, hits);
  ASSERT_EQ(hits.size(), w.rays.size());
  const auto hit = std::count_if(hits.begin(), hits.end(), [](const BatchHit& h) { return bool(h.hit); });
  // The interesting part is in view: at least a fifth of the primary grid hits triangles. The report
  // scene keeps the report's own camera, where the bunny (its only triangles) covers ~5% of the image.
  const double fraction = double(hit) / double(hits.size());
  EXPECT_GE(fraction, file == "report.toml" ? 0.03 : 0.2) << file << ": the camera sees triangles on " << fraction * 100 << "% of the image";
}

std::vector<std::string> sceneFiles() {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(kBench))
    if (entry.path().extension() == ".toml") out.push_back(entry.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

INSTANTIATE_TEST_SUITE_P(Bench, BenchScene, ::testing::ValuesIn(sceneFiles()),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string name = i.param.substr(0, i.param.size() - 5);
                           std::replace(name.begin(), name.end(), '-', '_');  // gtest names: [A-Za-z0-9_]
                           return name;
                         });

}  // namespace
}  // namespace bvhlab
