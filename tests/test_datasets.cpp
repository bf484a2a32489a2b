// datasets/: fetched data and checksums, procedural generators, image and mesh file I/O.
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

using namespace bvhlab;
namespace fs = std::filesystem;

namespace {

const fs::path kSource = BVHLAB_SOURCE_DIR;
const fs::path kCache = kSource / "datasets/cache";

// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("bvhlab_test_datasets_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

void writeFile(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// "HASH  RELPATH" lines of datasets/checksums.sha256.
std::vector<std::string> checksummedFiles() {
  std::ifstream in(kSource / "datasets/checksums.sha256");
  std::vector<std::string> files;
  std::string hash, rel;
  while (in >> hash >> rel) files.push_back(rel);
  return files;
}

bool cachePresent() {
  for (const std::string& f : checksummedFiles())
    if (!fs::exists(kCache / f)) return false;
  return !checksummedFiles().empty();
}

#define REQUIRE_CACHE()                                                                     \
  if (!cachePresent())                                                                      \
  GTEST_SKIP() << "dataset cache incomplete (" << kCache.string() << "): run `bash datasets/fetch.sh`"

int runShell(const std::string& cmd) {
  const int status = std::system((cmd + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The message of the InputError `f` throws ("" when it throws nothing or something else).
template <class F>
std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("UNEXPECTED EXCEPTION: ") + e.what();
  }
  return "";
}

bool allFinite(const Mesh& m) {
  for (const glm::vec3& p : m.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  return true;
}

bool sameMesh(const Mesh& a, const Mesh& b) {
  return a.positions == b.positions && a.normals == b.normals && a.uvs == b.uvs && a.triangles == b.triangles;
}

bool sameImage(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.texels == b.texels;
}

void expectIndicesInRange(const Mesh& m) {
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) ASSERT_LT(t[k], m.positions.size());
}

// Fraction of triangles whose geometric normal points away from `centre`.
double outwardFraction(const Mesh& m, glm::vec3 centre) {
  size_t out = 0;
  for (const glm::uvec3& t : m.triangles) {
    const glm::vec3 a = m.positions[t.x], b = m.positions[t.y], c = m.positions[t.z];
    if (glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - centre) > 0.0f) ++out;
  }
  return double(out) / double(m.triangles.size());
}

}  // namespace

// ---- fetched data ---------------------------------------------------------------------------------

TEST(FetchedData, EveryChecksummedFileIsPresentAndVerifies) {
  REQUIRE_CACHE();
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

// ---- mesh I/O -------------------------------------------------------------------------------------

namespace {

// One quad (two triangles after fan triangulation) and one triangle, in each format.
const char* kObjQuad =
    "# a quad with uvs and normals\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "vn 0 0 1\n"
    "f 1/1/1 2/2/1 3/3/1 4/4/1\n";
const char* kOffQuad = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
const char* kPlyQuad =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
const char* kStlTriangle =
    "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n"
    "  endloop\n endfacet\nendsolid t\n";

std::string binaryPly(bool truncated) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float v[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  s.append(reinterpret_cast<const char*>(v), sizeof v);
  s.push_back(char(4));
  const int32_t idx[4] = {0, 1, 2, 3};
  s.append(reinterpret_cast<const char*>(idx), truncated ? 10 : sizeof idx);
  return s;
}

std::string binaryStl(uint32_t declared, uint32_t written, float badValue = 0.0f) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&declared), 4);
  for (uint32_t i = 0; i < written; ++i) {
    const float rec[12] = {0, 0, 1, float(i), 0, 0, float(i) + 1, badValue, 0, float(i), 1, 0};
    s.append(reinterpret_cast<const char*>(rec), sizeof rec);
    s.append(2, '\0');
  }
  return s;
}

}  // namespace

TEST(MeshIo, EverySupportedFormatLoads) {
  TempDir tmp;
  writeFile(tmp / "q.obj", kObjQuad);
  writeFile(tmp / "q.off", kOffQuad);
  writeFile(tmp / "q.ply", kPlyQuad);
  writeFile(tmp / "qb.ply", binaryPly(false));
  writeFile(tmp / "t.stl", kStlTriangle);
  writeFile(tmp / "tb.STL", binaryStl(3, 3));  // upper-case extension too
  for (const char* name : {"q.obj", "q.off", "q.ply", "qb.ply"}) {
    SCOPED_TRACE(name);
    const Mesh m = loadMesh(tmp / name);
    EXPECT_EQ(m.name, (tmp / name).string());
    ASSERT_EQ(m.positions.size(), 4u);
    ASSERT_EQ(m.triangles.size(), 2u);  // the quad, fan-triangulated
    EXPECT_EQ(m.positions[2], glm::vec3(1, 1, 0));
    EXPECT_EQ(m.triangles[0], glm::uvec3(0, 1, 2));
    EXPECT_EQ(m.triangles[1], glm::uvec3(0, 2, 3));
  }
  const Mesh obj = loadMesh(tmp / "q.obj");
  ASSERT_EQ(obj.normals.size(), 4u);
  ASSERT_EQ(obj.uvs.size(), 4u);
  EXPECT_EQ(obj.normals[3], glm::vec3(0, 0, 1));
  EXPECT_EQ(obj.uvs[2], glm::vec2(1, 1));
  EXPECT_TRUE(loadMesh(tmp / "q.off").normals.empty());
  const Mesh stl = loadMesh(tmp / "t.stl");
  EXPECT_EQ(stl.triangles.size(), 1u);
  const Mesh stlb = loadMesh(tmp / "tb.STL");
  EXPECT_EQ(stlb.triangles.size(), 3u);
  expectIndicesInRange(stlb);
}

TEST(MeshIo, ObjWriterRoundTrips) {
  TempDir tmp;
  const Mesh sphere = makeUvSphere(8, 5);
  saveMeshObj(tmp / "out/s.obj", sphere);
  const Mesh back = loadMesh(tmp / "out/s.obj");
  EXPECT_EQ(back.positions, sphere.positions);
  EXPECT_EQ(back.triangles, sphere.triangles);
  ASSERT_EQ(back.uvs.size(), sphere.uvs.size());
  ASSERT_EQ(back.normals.size(), sphere.normals.size());
  // The sphere has two vertices no triangle uses (a pole's seam copies); the loader gives those
  // placeholders, so compare the attributes triangles actually use.
  for (const glm::uvec3& t : sphere.triangles)
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(back.uvs[t[k]], sphere.uvs[t[k]]);
      EXPECT_NEAR(glm::distance(back.normals[t[k]], sphere.normals[t[k]]), 0.0f, 1e-6f);
    }
}

TEST(MeshIo, BadFilesGiveOneLineInputErrorsWithPathAndLine) {
  TempDir tmp;
  struct Case {
    std::string file, content, expect;  // expect: a substring after "PATH"
  };
  const std::vector<Case> cases = {
      {"missing.obj", "", ": mesh file not found"},
      {"mesh.dae", "<collada/>", ": unsupported mesh format '.dae'"},
      {"empty.off", "", ": empty file"},
      {"nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", ": mesh has no faces"},
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", ":2: vertex: value 'nan' is NaN or infinite"},
      {"inf.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", ":4: vertex: value 'inf' is NaN or infinite"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", ":4: face: vertex index 9 out of range"},
      {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4: face: index 0"},
      {"range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", ":6: face: vertex index 3 out of range"},
      {"twocorners.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", ":3: face with 2 corners"},
      {"trunc.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n", "truncated: file ends after 1 of 2 faces"},
      {"truncline.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", ":6: face: declares 3 vertices but lists 2"},
      {"hugecount.off", "OFF\n4000000000 1 0\n0 0 0\n", ":2: truncated: header declares 4000000000 vertices"},
      {"hugeface.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000000 0 1 2\n", ":6: face: declares 1000000000"},
      {"binary.off", "OFF BINARY\n", ":1: binary OFF is not supported"},
      {"trunc.ply", std::string(kPlyQuad).substr(0, std::string(kPlyQuad).size() - 10), "truncated"},
      {"truncb.ply", binaryPly(true), "truncated"},
      {"nan.ply", std::string(kPlyQuad).replace(std::string(kPlyQuad).find("1 1 0"), 5, "1 nan 0"), "is NaN or infinite"},
      {"trunc.stl", std::string(kStlTriangle).substr(0, 60), "truncated ASCII STL"},
      {"truncb.stl", binaryStl(5, 3), "binary STL size mismatch: header declares 5 triangles"},
      {"nanb.stl", binaryStl(2, 2, std::nanf("")), "triangle 0: vertex coordinate is NaN or infinite"},
      {"noheader.off", "3 1 0\n0 0 0\n", ":1: not an OFF file"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const fs::path p = tmp / c.file;
    if (c.file != "missing.obj") writeFile(p, c.content);
    const std::string msg = inputErrorOf([&] { loadMesh(p); });
    EXPECT_EQ(msg.rfind(p.string(), 0), 0u) << msg;  // starts with the path
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(MeshIo, CorruptedFilesNeverCrash) {
  // Flipped bytes, cuts and inserted junk in small valid files of every format: each load either
  // succeeds with a well-formed mesh or throws InputError (a crash or another exception fails).
  TempDir tmp;
  const std::vector<std::pair<std::string, std::string>> seeds = {
      {".obj", kObjQuad}, {".off", kOffQuad}, {".ply", kPlyQuad}, {".ply", binaryPly(false)},
      {".stl", kStlTriangle}, {".stl", binaryStl(4, 4)}};
  const char* junk[] = {"9999999999", "-1", "nan", " ", "\n", "/", "3 ", "\xff\xff\xff\x7f", "1e39"};
  SplitMix64 rng(2024);
  int loaded = 0, rejected = 0;
  for (const auto& [ext, seed] : seeds)
    for (int k = 0; k < 60; ++k) {
      std::string s = seed;
      const int mode = int(rng.next() % 3);
      if (mode == 0) {
        s.resize(rng.next() % s.size());
      } else if (mode == 1) {
        for (int j = 0; j < 3; ++j) s[rng.next() % s.size()] = char(rng.next() & 0xff);
      } else {
        s.insert(rng.next() % s.size(), junk[rng.next() % std::size(junk)]);
      }
      const fs::path p = tmp / ("f" + std::to_string(k) + ext);
      writeFile(p, s);
      try {
        const Mesh m = loadMesh(p);
        EXPECT_TRUE(allFinite(m));
        expectIndicesInRange(m);
        ++loaded;
      } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(p.string(), 0), 0u);
        ++rejected;
      }
    }
  EXPECT_GT(rejected, 0);
  EXPECT_EQ(loaded + rejected, int(seeds.size()) * 60);
}

// ---- far meshes (issue 16): positions stay double until rebased -------------------------------------

namespace {

// A small mesh with coordinates that need every bit of a float near the origin (thirds, sevenths).
const std::vector<glm::dvec3> kNearCorners = {
    {0.0, 0.0, 0.0}, {1.0 / 3.0, 0.0, 1.0 / 7.0}, {0.1, 0.2, 0.3}, {-0.25, 1.0 / 3.0, 0.05}};
const std::vector<glm::uvec3> kNearTriangles = {{0, 1, 2}, {0, 2, 3}, {1, 3, 2}};

std::string g17(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The mesh moved by `offset`, in `format`, every coordinate with 17 significant digits.
std::string farMeshFile(const std::string& format, glm::dvec3 offset) {
  std::string s;
  auto xyz = [&](glm::dvec3 p) { return g17(p.x) + " " + g17(p.y) + " " + g17(p.z); };
  if (format == "obj") {
    for (const glm::dvec3& p : kNearCorners) s += "v " + xyz(offset + p) + "\n";
    for (const glm::uvec3& t : kNearTriangles)
      s += "f " + std::to_string(t.x + 1) + " " + std::to_string(t.y + 1) + " " + std::to_string(t.z + 1) + "\n";
  } else if (format == "off") {
    s = "OFF\n" + std::to_string(kNearCorners.size()) + " " + std::to_string(kNearTriangles.size()) + " 0\n";
    for (const glm::dvec3& p : kNearCorners) s += xyz(offset + p) + "\n";
    for (const glm::uvec3& t : kNearTriangles)
      s += "3 " + std::to_string(t.x) + " " + std::to_string(t.y) + " " + std::to_string(t.z) + "\n";
  } else if (format == "ply" || format == "plyb") {
    const bool binary = format == "plyb";
    s = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") + " 1.0\nelement vertex " +
        std::to_string(kNearCorners.size()) + "\nproperty double x\nproperty double y\nproperty double z\n" +
        "element face " + std::to_string(kNearTriangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const glm::dvec3& p : kNearCorners) {
      const glm::dvec3 q = offset + p;
      if (binary) s.append(reinterpret_cast<const char*>(&q[0]), 3 * sizeof(double));  // little-endian host
      else s += xyz(q) + "\n";
    }
    for (const glm::uvec3& t : kNearTriangles) {
      if (binary) {
        s.push_back(char(3));
        const int32_t idx[3] = {int32_t(t.x), int32_t(t.y), int32_t(t.z)};
        s.append(reinterpret_cast<const char*>(idx), sizeof idx);
      } else {
        s += "3 " + std::to_string(t.x) + " " + std::to_string(t.y) + " " + std::to_string(t.z) + "\n";
      }
    }
  } else if (format == "stl") {
    s = "solid far\n";
    for (const glm::uvec3& t : kNearTriangles) {
      s += " facet normal 0 0 0\n  outer loop\n";
      for (int k = 0; k < 3; ++k) s += "   vertex " + xyz(offset + kNearCorners[t[k]]) + "\n";
      s += "  endloop\n endfacet\n";
    }
    s += "endsolid far\n";
  }
  return s;
}

}  // namespace

// Every text format, and binary PLY with `property double`, keeps far coordinates to double precision:
// at 1e6 (float spacing 0.0625) and 1e7 (spacing 1) the corners come back within 1e-8 of the file's
// values (double's spacing there is 1.2e-10 / 1.9e-9); a reader that narrows to float is off by up to
// half a float spacing (0.03 / 0.5), which these bounds reject.
TEST(MeshIo, FarCoordinatesKeepDoublePrecisionInEveryFormat) {
  TempDir tmp;
  for (double d : {1e6, 1e7}) {
    const glm::dvec3 offset = d * glm::dvec3(1.0, 0.5, -1.0);
    for (const std::string format : {"obj", "off", "ply", "plyb", "stl"}) {
      SCOPED_TRACE(format + " at " + g17(d));
      const fs::path p = tmp / ("far_" + format + (format == "plyb" ? ".ply" : "." + format.substr(0, 3)));
      writeFile(p, farMeshFile(format, offset));
      const MeshData m = loadMeshData(p);
      ASSERT_EQ(m.triangles.size(), kNearTriangles.size());
      ASSERT_EQ(m.positions.size(), kNearCorners.size());  // STL corners are welded back into 4 vertices
      for (size_t t = 0; t < kNearTriangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
          const glm::dvec3 got = m.positions[m.triangles[t][k]] - offset, want = kNearCorners[kNearTriangles[t][k]];
          EXPECT_LE(glm::length(got - want), 1e-8) << "triangle " << t << " corner " << k;
        }
      // Rebased at the bounding box centre (what loadMeshScene does), the float mesh keeps that precision.
      const glm::dvec3 centre = boundsCentre(m);
      const Mesh rebased = rebasedMesh(m, centre);
      for (size_t v = 0; v < m.positions.size(); ++v)
        EXPECT_LE(glm::length(glm::dvec3(rebased.positions[v]) - (m.positions[v] - centre)), 1e-6);
    }
  }
}

// Binary STL stores float: the double path adds no further rounding (the values come back bit-exact).
TEST(MeshIo, BinaryStlFloatsConvertExactly) {
  TempDir tmp;
  std::string s(80, ' ');
  const uint32_t one = 1;
  s.append(reinterpret_cast<const char*>(&one), 4);
  const float rec[12] = {0, 0, 1, 1e6f + 0.0625f, 5e5f, -1e6f, 1e6f + 0.125f, 5e5f, -1e6f, 1e6f, 5e5f + 0.0625f, -1e6f};
  s.append(reinterpret_cast<const char*>(rec), sizeof rec);
  s.append(2, '\0');
  writeFile(tmp / "f.stl", s);
  const MeshData m = loadMeshData(tmp / "f.stl");
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[0], glm::dvec3(1e6 + 0.0625, 5e5, -1e6));
  EXPECT_EQ(m.positions[2], glm::dvec3(1e6, 5e5 + 0.0625, -1e6));
}

// ---- resource limits (issue 16): absurd claimed counts fail with a clear error before allocation ----

TEST(MeshIo, AbsurdDeclaredCountsAreRefusedBeforeAllocation) {
  TempDir tmp;
  std::string stl(80, ' ');  // no "solid": a binary STL header claiming 4e9 triangles, one record present
  const uint32_t claimed = 4'000'000'000u;
  stl.append(reinterpret_cast<const char*>(&claimed), 4);
  stl.append(50, '\0');
  const std::string plyHead = "ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\nproperty float x\n"
                              "property float y\nproperty float z\n";
  const std::string plyFaces = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 4000000000\n"
                               "property list uchar int vertex_indices\nend_header\n" + std::string(36, '\0') +
                               std::string("\x03\0\0\0\0\1\0\0\0\2\0\0\0", 13);
  struct Case {
    std::string file, content, expect;
  };
  const std::vector<Case> cases = {
      {"huge.stl", stl, ": binary STL size mismatch: header declares 4000000000 triangles (200000000084 bytes)"},
      {"hugev.ply", plyHead + "end_header\n" + std::string(36, '\0'),
       ": truncated: binary data too short for 2147483648 vertex records (12 bytes each"},
      {"hugev_ascii.ply", "ply\nformat ascii 1.0\nelement vertex 2147483648\nproperty float x\nproperty float y\n"
                          "property float z\nend_header\n0 0 0\n",
       ": truncated: file ends after 1 of 2147483648 vertex records"},
      {"hugef.ply", plyFaces, ": truncated: binary data ends inside face 1"},
      {"huge.off", "OFF\n2147483648 4000000000 0\n0 0 0\n", ":2: truncated: header declares 2147483648 vertices and "
                                                            "4000000000 faces but the file has only"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const fs::path p = tmp / c.file;
    writeFile(p, c.content);
    const std::string msg = inputErrorOf([&] { loadMeshData(p); });
    EXPECT_EQ(msg.rfind(p.string(), 0), 0u) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find("out of memory"), std::string::npos) << msg;  // refused, not caught after bad_alloc
  }
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
