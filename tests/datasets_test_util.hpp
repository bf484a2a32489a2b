// Shared by the datasets/ tests (test_datasets.cpp, test_mesh_io.cpp): temp dirs, file helpers, the
// fetched-data cache check, and mesh predicates.
#pragma once
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "datasets/mesh_io.hpp"
#include "datasets/scene.hpp"
#include "require.hpp"

namespace bvhlab::datasets_test {

namespace fs = std::filesystem;

inline const fs::path kSource = BVHLAB_SOURCE_DIR;
inline const fs::path kCache = kSource / "datasets/cache";

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

inline void writeFile(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

inline std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// "HASH  RELPATH" lines of datasets/checksums.sha256.
inline std::vector<std::string> checksummedFiles() {
  std::ifstream in(kSource / "datasets/checksums.sha256");
  std::vector<std::string> files;
  std::string hash, rel;
  while (in >> hash >> rel) files.push_back(rel);
  return files;
}

inline bool cachePresent() {
  for (const std::string& f : checksummedFiles())
    if (!fs::exists(kCache / f)) return false;
  return !checksummedFiles().empty();
}

#define REQUIRE_CACHE()                                                                     \
  if (!cachePresent())                                                                      \
  BVHLAB_SKIP_OR_FAIL("dataset cache incomplete (" << kCache.string() << "): run `bash datasets/fetch.sh`")

inline int runShell(const std::string& cmd) {
  const int status = std::system((cmd + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The message of the InputError `f` throws ("" when it throws nothing or something else).
template <class F>
inline std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("UNEXPECTED EXCEPTION: ") + e.what();
  }
  return "";
}

inline bool allFinite(const Mesh& m) {
  for (const glm::vec3& p : m.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  return true;
}

inline bool sameMesh(const Mesh& a, const Mesh& b) {
  return a.positions == b.positions && a.normals == b.normals && a.uvs == b.uvs && a.triangles == b.triangles;
}

inline bool sameImage(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.texels == b.texels;
}

inline void expectIndicesInRange(const Mesh& m) {
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) ASSERT_LT(t[k], m.positions.size());
}

// Fraction of triangles whose geometric normal points away from `centre`.
inline double outwardFraction(const Mesh& m, glm::vec3 centre) {
  size_t out = 0;
  for (const glm::uvec3& t : m.triangles) {
    const glm::vec3 a = m.positions[t.x], b = m.positions[t.y], c = m.positions[t.z];
    if (glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - centre) > 0.0f) ++out;
  }
  return double(out) / double(m.triangles.size());
}

}  // namespace bvhlab::datasets_test
