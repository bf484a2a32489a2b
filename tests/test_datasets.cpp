// datasets/: fetched data and checksums, procedural generators, image file I/O (mesh files: test_mesh_io.cpp).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <OpenImageIO/imageio.h>

#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/procedural.hpp"
#include "datasets_test_util.hpp"

using namespace bvhlab;
namespace fs = std::filesystem;

using namespace bvhlab::datasets_test;


// ---- fetched data ---------------------------------------------------------------------------------

// Skips only when nothing was fetched (a failure under BVHLAB_REQUIRE_ALL=1); a cache with some of the
// files is a fetch that stopped half-way or lost a file since, and fails naming each missing file.
TEST(FetchedData, EveryChecksummedFileIsPresentAndVerifies) {
  const std::vector<std::string> files = checksummedFiles();
  ASSERT_FALSE(files.empty()) << "datasets/checksums.sha256 lists no file";
  std::vector<std::string> missing;
  for (const std::string& f : files)
    if (!fs::exists(kCache / f)) missing.push_back(f);
  if (missing.size() == files.size())
    BVHLAB_SKIP_OR_FAIL("no fetched data in " << kCache.string() << ": run `bash datasets/fetch.sh`");
  for (const std::string& f : missing)
    ADD_FAILURE() << (kCache / f).string() << " is missing (" << missing.size() << " of " << files.size()
                  << " checksummed files): run `bash datasets/fetch.sh`";
  EXPECT_EQ(runShell("bash " + (kSource / "datasets/fetch.sh").string() + " --verify"), 0);
}

TEST(FetchedData, FetchScriptRejectsACorruptedCopy) {
  REQUIRE_CACHE();
  TempDir tmp;
  fs::copy(kCache, tmp.path(), fs::copy_options::recursive);
  std::string data = readFile(tmp / "meshes/cow.off");
  data[data.size() / 2] ^= 1;  // one flipped bit must be caught
  writeFile(tmp / "meshes/cow.off", data);
  const std::string script = (kSource / "datasets/fetch.sh").string();
  EXPECT_NE(runShell("BVHLAB_DATA_CACHE=" + tmp.path().string() + " bash " + script + " --verify"), 0);
  // A missing file with --verify is an error too (and never downloads).
  fs::copy_file(kCache / "meshes/cow.off", tmp / "meshes/cow.off", fs::copy_options::overwrite_existing);
  fs::remove(tmp / "worlds/night.exr");
  EXPECT_NE(runShell("BVHLAB_DATA_CACHE=" + tmp.path().string() + " bash " + script + " --verify"), 0);
  fs::copy_file(kCache / "worlds/night.exr", tmp / "worlds/night.exr");
  EXPECT_EQ(runShell("BVHLAB_DATA_CACHE=" + tmp.path().string() + " bash " + script + " --verify"), 0);
}

TEST(FetchedData, EveryMeshLoadsWithTheCountsItsHeaderDeclares) {
  REQUIRE_CACHE();
  for (const std::string& rel : checksummedFiles()) {
    const fs::path p = kCache / rel;
    if (!isMeshFile(p)) continue;
    SCOPED_TRACE(rel);
    const Mesh m = loadMesh(p);
    EXPECT_GT(m.triangles.size(), 0u);
    EXPECT_TRUE(allFinite(m));
    expectIndicesInRange(m);
    if (p.extension() == ".off") {  // these OFF files are all-triangle: faces == triangles
      std::istringstream header(readFile(p));
      std::string magic;
      size_t nV = 0, nF = 0;
      header >> magic >> nV >> nF;
      EXPECT_EQ(m.positions.size(), nV);
      EXPECT_EQ(m.triangles.size(), nF);
    }
  }
}

TEST(FetchedData, EveryWorldMapLoadsAsFiniteLinearHdr) {
  REQUIRE_CACHE();
  for (const std::string& rel : checksummedFiles()) {
    if (fs::path(rel).extension() != ".exr") continue;
    SCOPED_TRACE(rel);
    const Image img = loadImage(kCache / rel);
    EXPECT_EQ(img.width, 2 * img.height);  // equirectangular
    float maxValue = 0.0f;
    for (const glm::vec4& t : img.texels) maxValue = std::max({maxValue, t.r, t.g, t.b});
    EXPECT_GT(maxValue, 1.0f) << "an HDR map should hold values above 1 (sun, lamps)";
  }
}

// ---- procedural ----------------------------------------------------------------------------------

TEST(Procedural, GeneratorsAreDeterministicAndSeedsMatter) {
  EXPECT_TRUE(sameImage(makeLogoTexture(64), makeLogoTexture(64)));
  EXPECT_TRUE(sameImage(makeCheckerTexture(32, 4), makeCheckerTexture(32, 4)));
  EXPECT_TRUE(sameMesh(makeUvSphere(12, 6), makeUvSphere(12, 6)));
  EXPECT_TRUE(sameMesh(makeCube(3), makeCube(3)));
  EXPECT_TRUE(sameMesh(makeGridPlane(3, 4), makeGridPlane(3, 4)));
  EXPECT_TRUE(sameMesh(makeTriangleSoup(500, 7), makeTriangleSoup(500, 7)));
  EXPECT_FALSE(sameMesh(makeTriangleSoup(500, 7), makeTriangleSoup(500, 8)));
  EXPECT_TRUE(sameMesh(makeLargeMesh(5000, 3), makeLargeMesh(5000, 3)));
  EXPECT_FALSE(sameMesh(makeLargeMesh(5000, 3), makeLargeMesh(5000, 4)));
  SplitMix64 a(42), b(42);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next(), b.next());
}

TEST(Procedural, RandomNumbersHaveTheirStatedRanges) {
  SplitMix64 rng(1);
  double sum = 0.0, sumSq = 0.0;
  constexpr int kN = 20000;
  for (int i = 0; i < kN; ++i) {
    const float u = rng.uniform();
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    const float n = rng.normal();
    ASSERT_TRUE(std::isfinite(n));
    sum += n;
    sumSq += double(n) * n;
    ASSERT_NEAR(glm::length(rng.unitVector()), 1.0f, 1e-5f);
  }
  // Standard normal: mean 0 and variance 1 within ~5 standard errors (sd of the mean is 1/sqrt(N)).
  EXPECT_NEAR(sum / kN, 0.0, 5.0 / std::sqrt(double(kN)));
  EXPECT_NEAR(sumSq / kN, 1.0, 0.05);
}

TEST(Procedural, UvSphereIsAClosedOutwardUnitSphere) {
  const Mesh m = makeUvSphere(24, 12);
  EXPECT_EQ(m.triangles.size(), size_t(2 * 24 * (12 - 1)));
  expectIndicesInRange(m);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  ASSERT_EQ(m.uvs.size(), m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    EXPECT_NEAR(glm::length(m.positions[i]), 1.0f, 1e-6f);
    EXPECT_NEAR(glm::length(m.normals[i]), 1.0f, 1e-6f);
    EXPECT_TRUE(m.uvs[i].x >= 0.0f && m.uvs[i].x <= 1.0f && m.uvs[i].y >= 0.0f && m.uvs[i].y <= 1.0f);
  }
  EXPECT_EQ(outwardFraction(m, glm::vec3(0.0f)), 1.0);
}

TEST(Procedural, CubeIsWatertightOutwardAndFlatShaded) {
  const int n = 3;
  const Mesh m = makeCube(n);
  EXPECT_EQ(m.triangles.size(), size_t(12 * n * n));
  expectIndicesInRange(m);
  EXPECT_EQ(outwardFraction(m, glm::vec3(0.0f)), 1.0);
  // Watertight: with vertices merged by position, every undirected edge borders exactly two triangles
  // and every directed edge appears once (consistent orientation).
  std::map<std::tuple<float, float, float>, uint32_t> ids;
  auto id = [&](uint32_t v) {
    const glm::vec3 p = m.positions[v];
    return ids.emplace(std::make_tuple(p.x, p.y, p.z), uint32_t(ids.size())).first->second;
  };
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{id(t[k]), id(t[(k + 1) % 3])}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "open edge";
  }
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const glm::vec3 p = m.positions[i], nrm = m.normals[i];
    EXPECT_FLOAT_EQ(glm::dot(p, nrm), 1.0f);  // on the face its normal names
    EXPECT_LE(std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}), 1.0f);
  }
}

TEST(Procedural, GridPlaneFacesUp) {
  const Mesh m = makeGridPlane(5, 3);
  EXPECT_EQ(m.triangles.size(), size_t(2 * 5 * 3));
  expectIndicesInRange(m);
  for (const glm::uvec3& t : m.triangles) {
    const glm::vec3 a = m.positions[t.x], b = m.positions[t.y], c = m.positions[t.z];
    EXPECT_GT(glm::cross(b - a, c - a).y, 0.0f);
    EXPECT_EQ(a.y, 0.0f);
  }
}

TEST(Procedural, TriangleSoupStaysNearTheUnitCube) {
  const Mesh m = makeTriangleSoup(2000, 5, 0.01f, 0.1f);
  EXPECT_EQ(m.triangles.size(), 2000u);
  expectIndicesInRange(m);
  for (const glm::vec3& p : m.positions)
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], -0.1f);
      EXPECT_LE(p[k], 1.1f);
    }
}

TEST(Procedural, LargeMeshHasExactlyTheRequestedTrianglesAndIsFinite) {
  for (size_t n : {size_t(100), size_t(101), size_t(102), size_t(103), size_t(12345)}) {
    const Mesh m = makeLargeMesh(n, 9);
    EXPECT_EQ(m.triangles.size(), n);
    expectIndicesInRange(m);
    EXPECT_TRUE(allFinite(m));
  }
  const Mesh big = makeLargeMesh(1'000'000);
  EXPECT_EQ(big.triangles.size(), 1'000'000u);
  EXPECT_TRUE(allFinite(big));
  // Two populations by triangle: the bumpy sphere (|p| ~ 1, about 3/4) and debris further out.
  size_t inner = 0, outer = 0;
  for (const glm::uvec3& t : big.triangles) {
    const glm::vec3 c = (big.positions[t.x] + big.positions[t.y] + big.positions[t.z]) / 3.0f;
    (glm::length(c) < 1.3f ? inner : outer)++;
  }
  EXPECT_GT(inner, big.triangles.size() * 6 / 10);
  EXPECT_GT(outer, big.triangles.size() / 10);
}

TEST(Procedural, LogoIsOpaqueHighContrastAndSquare) {
  const Image logo = makeLogoTexture(128);
  EXPECT_EQ(logo.width, 128);
  EXPECT_EQ(logo.height, 128);
  ASSERT_EQ(logo.texels.size(), size_t(128 * 128));
  float lo = 1.0f, hi = 0.0f;
  std::set<std::tuple<float, float, float>> colors;
  for (const glm::vec4& t : logo.texels) {
    EXPECT_EQ(t.a, 1.0f);
    const float lum = 0.2126f * t.r + 0.7152f * t.g + 0.0722f * t.b;
    lo = std::min(lo, lum);
    hi = std::max(hi, lum);
    colors.insert({t.r, t.g, t.b});
  }
  EXPECT_LT(lo, 0.05f);  // dark tile
  EXPECT_GT(hi, 0.8f);   // white strokes
  EXPECT_GT(colors.size(), 5u);  // more than a two-tone image (orange, teal, AA edges)
  // Not symmetric top to bottom: the root is at the top (v = 1), the leaves at the bottom.
  EXPECT_FALSE(logo.texels[size_t(20) * 128 + 64] == logo.texels[size_t(107) * 128 + 64] &&
               logo.texels[size_t(30) * 128 + 30] == logo.texels[size_t(97) * 128 + 30]);
}

TEST(Procedural, CheckerAlternatesStartingWithColourA) {
  const glm::vec3 a(1.0f, 0.0f, 0.0f), b(0.0f, 0.0f, 1.0f);
  const Image img = makeCheckerTexture(16, 4, a, b);
  auto at = [&](int x, int y) { return glm::vec3(img.texels[size_t(y) * 16 + x]); };
  EXPECT_EQ(at(0, 0), a);
  EXPECT_EQ(at(4, 0), b);
  EXPECT_EQ(at(0, 4), b);
  EXPECT_EQ(at(5, 5), a);
  EXPECT_EQ(at(15, 15), a);
}

// ---- image I/O ------------------------------------------------------------------------------------

TEST(ImageIo, Rgba8PngRoundTripIsExactAndBottomUp) {
  TempDir tmp;
  const int w = 7, h = 5;
  std::vector<uint8_t> px(size_t(w) * h * 4);
  for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t((i * 37 + 11) % 256);
  const fs::path file = tmp / "nested/dirs/out.png";
  saveImageRgba8(file, w, h, px);
  ASSERT_TRUE(fs::exists(file));
  const ImageRgba8 back = loadImageRgba8(file);
  EXPECT_EQ(back.width, w);
  EXPECT_EQ(back.height, h);
  EXPECT_EQ(back.rgba, px);
  // In the file, the first scanline is the top: our last row.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // the raw stored bytes, not premultiplied
  auto in = OIIO::ImageInput::open(file.string(), &config);
  ASSERT_TRUE(in);
  std::vector<uint8_t> top(size_t(w) * 4);
  ASSERT_TRUE(in->read_scanline(0, 0, OIIO::TypeDesc::UINT8, top.data()));
  EXPECT_TRUE(std::equal(top.begin(), top.end(), px.begin() + size_t(h - 1) * w * 4));
  // No temporary files are left beside it.
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(file.parent_path())) entries += e.path().filename() == "out.png" ? 0 : 1;
  EXPECT_EQ(entries, 0u);
}

TEST(ImageIo, LoadImageDecodesSrgbButNotAlpha) {
  TempDir tmp;
  const std::vector<uint8_t> px = {0, 128, 255, 128, 10, 20, 30, 255};  // 2x1
  saveImageRgba8(tmp / "a.png", 2, 1, px);
  const Image img = loadImage(tmp / "a.png");
  ASSERT_EQ(img.texels.size(), 2u);
  EXPECT_FLOAT_EQ(img.texels[0].r, 0.0f);
  EXPECT_NEAR(img.texels[0].g, srgbToLinear(128.0f / 255.0f), 1e-6f);
  EXPECT_NEAR(img.texels[0].b, 1.0f, 1e-6f);
  EXPECT_NEAR(img.texels[0].a, 128.0f / 255.0f, 1e-6f);  // alpha is linear
  EXPECT_NEAR(img.texels[1].r, srgbToLinear(10.0f / 255.0f), 1e-6f);
  // Known points of the sRGB curve and an exact round trip through the encoder.
  EXPECT_NEAR(srgbToLinear(0.5f), 0.214041f, 1e-5f);
  EXPECT_NEAR(linearToSrgb(0.214041f), 0.5f, 1e-5f);
  EXPECT_EQ(linearToSrgb(std::nanf("")), 0.0f);
  EXPECT_EQ(linearToSrgb(7.0f), linearToSrgb(1.0f));
  Image lin;
  lin.width = 256;
  lin.height = 1;
  for (int i = 0; i < 256; ++i) lin.texels.emplace_back(srgbToLinear(i / 255.0f), 0.0f, 0.0f, 1.0f);
  const std::vector<uint8_t> enc = encodeSrgb8(lin);
  for (int i = 0; i < 256; ++i) ASSERT_EQ(enc[4 * i], i);
}

TEST(ImageIo, ExrRoundTripIsExactFloat) {
  TempDir tmp;
  Image img;
  img.width = 3;
  img.height = 2;
  img.texels = {{0.0f, 1.0f, 2.5f, 1.0f},  {1e-3f, 100.0f, 0.25f, 0.5f}, {3.0f, 2.0f, 1.0f, 0.0f},
                {7.0f, 8.0f, 9.0f, 1.0f},  {0.1f, 0.2f, 0.3f, 0.4f},     {65504.0f, 1e5f, 0.0f, 1.0f}};
  saveImageExr(tmp / "x.exr", img);
  const Image back = loadImage(tmp / "x.exr");
  EXPECT_EQ(back.width, 3);
  EXPECT_EQ(back.height, 2);
  EXPECT_EQ(back.texels, img.texels);
}

TEST(ImageIo, BadInputsAreInputErrorsNamingThePath) {
  TempDir tmp;
  const fs::path missing = tmp / "missing.png";
  EXPECT_NE(inputErrorOf([&] { loadImage(missing); }).find(missing.string() + ": image file not found"), std::string::npos);
  writeFile(tmp / "garbage.png", "this is not a PNG file at all");
  EXPECT_NE(inputErrorOf([&] { loadImage(tmp / "garbage.png"); }).find((tmp / "garbage.png").string()), std::string::npos);
  writeFile(tmp / "thing.xyz", "unknown format");
  EXPECT_NE(inputErrorOf([&] { loadImage(tmp / "thing.xyz"); }).find("thing.xyz"), std::string::npos);
  EXPECT_NE(inputErrorOf([&] { loadImage(tmp.path()); }).find("not a regular file"), std::string::npos);
  // An EXR holds floats: the byte reader refuses it rather than quantising silently.
  Image one;
  one.width = one.height = 1;
  one.texels = {glm::vec4(0.5f)};
  saveImageExr(tmp / "one.exr", one);
  EXPECT_NE(inputErrorOf([&] { loadImageRgba8(tmp / "one.exr"); }).find("not an 8-bit image"), std::string::npos);
  // Wrong buffer size is a programming error, not bad input.
  EXPECT_THROW(saveImageRgba8(tmp / "bad.png", 2, 2, std::vector<uint8_t>(15)), std::invalid_argument);
  // A parent that is a file: an InputError, and nothing written.
  writeFile(tmp / "file", "x");
  EXPECT_NE(inputErrorOf([&] { saveImageRgba8(tmp / "file/out.png", 1, 1, {1, 2, 3, 4}); }).find("out.png"),
            std::string::npos);
}

TEST(ImageIo, FailedWriteLeavesNoPartialFile) {
  // The final rename cannot replace a non-empty directory: the write fails after the temporary file
  // was complete, and neither a partial image nor the temporary may remain.
  TempDir tmp;
  const fs::path target = tmp / "out.png";
  fs::create_directories(target / "occupied");
  EXPECT_NE(inputErrorOf([&] { saveImageRgba8(target, 1, 1, {9, 9, 9, 9}); }).find(target.string()), std::string::npos);
  EXPECT_TRUE(fs::is_directory(target / "occupied"));
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(tmp.path())) entries += e.path() == target ? 0 : 1;
  EXPECT_EQ(entries, 0u) << "a temporary file was left behind";
  Image one;
  one.width = one.height = 1;
  one.texels = {glm::vec4(1.0f)};
  EXPECT_THROW(saveImageExr(target, one), InputError);
}

// 10^9 triangles (about 100 GB with the BVH) from any generator: an InputError naming the generator, the
// request and the limit, thrown before allocation (the test process would be killed otherwise).
TEST(Procedural, HugeRequestsAreRefusedWithTheNamedLimit) {
  const std::string limit = std::to_string(kMaxProceduralTriangles);
  struct Case {
    std::function<void()> call;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {[] { makeTriangleSoup(1'000'000'000); }, "makeTriangleSoup(1000000000): asks for 1000000000 triangles"},
      {[] { makeLargeMesh(1'000'000'000); }, "makeLargeMesh(1000000000): asks for 1000000000 triangles"},
      {[] { makeCube(10'000); }, "makeCube(10000): asks for 1200000000 triangles"},
      {[] { makeGridPlane(1 << 20, 1 << 20); }, "makeGridPlane(1048576, 1048576): asks for 2199023255552 triangles"},
      {[] { makeUvSphere(1 << 16, 1 << 16); }, "makeUvSphere(65536, 65536): asks for 8589803520 triangles"},
  };
  for (const Case& c : cases) {
    const std::string msg = inputErrorOf(c.call);
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_NE(msg.find("limit of " + limit + " (kMaxProceduralTriangles"), std::string::npos) << msg;
  }
  // At the limit's scale the generators still work (the limit is not below what experiments use).
  EXPECT_EQ(makeTriangleSoup(1000).triangles.size(), 1000u);
  EXPECT_GE(kMaxProceduralTriangles, size_t(10'000'000));  // experiments/configs/large.toml asks for 10M
}
