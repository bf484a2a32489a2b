// Mesh loading (mesh_io.hpp): the file is read once, scanned by our per-format pass (double
// positions, counts, indices), parsed by OpenMesh for faces and attributes (OBJ, OFF, PLY) or by our
// own STL reader, and validated again; glTF/COLLADA/FBX/3DS/AC3D go to assimp (mesh_io_assimp.cpp),
// after our checks (mesh_io_prechecks.cpp).
// Also the OBJ writer.
#include "datasets/mesh_io.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <fstream>
#include <limits>

#include "datasets/mesh_io_detail.hpp"

namespace bvhlab {
namespace fs = std::filesystem;
using namespace meshio;

namespace {

// Larger files are refused rather than read into memory (the biggest shipped mesh is 4 MB).
constexpr uintmax_t kMaxFileBytes = uintmax_t(1) << 31;

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// The file's size, after the checks every format shares (exists, regular, at most kMaxFileBytes).
uintmax_t checkedFileSize(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) fail("mesh file not found");
  if (!fs::is_regular_file(path, ec)) fail("not a regular file");
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) fail("cannot stat file (" + ec.message() + ")");
  if (size > kMaxFileBytes) fail("file too large (" + std::to_string(size) + " bytes)");
  return size;
}

std::string readWholeFile(const fs::path& path) {
  const uintmax_t size = checkedFileSize(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot open file");
  std::string data(size, '\0');
  in.read(data.data(), std::streamsize(size));
  if (size_t(in.gcount()) != size) fail("cannot read file");
  return data;
}

template <class V>
bool allFinite(const std::vector<V>& values) {
  return std::all_of(values.begin(), values.end(), [](const V& v) {
    for (int i = 0; i < V::length(); ++i)
      if (!std::isfinite(v[i])) return false;
    return true;
  });
}

// OpenMesh read the same vertices (in the same order) as our scan, narrowed to float: each of its
// coordinates is within 2 float ulps of ours (1 for its rounding, 1 for the double rounding of
// float(double(text))). A larger gap means the two readers disagree about which vertex is which.
void checkAgreement(const std::vector<glm::dvec3>& ours, const std::vector<glm::vec3>& openMesh) {
  if (ours.size() != openMesh.size())
    fail("truncated or malformed: the file holds " + std::to_string(ours.size()) + " vertices, OpenMesh read " +
         std::to_string(openMesh.size()));
  for (size_t i = 0; i < ours.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const double tolerance = std::ldexp(std::max(std::abs(ours[i][k]), double(FLT_MIN)), -22);
      if (!(std::abs(double(openMesh[i][k]) - ours[i][k]) <= tolerance))
        fail("vertex " + std::to_string(i) + ": OpenMesh read a different position than the file states");
    }
}

MeshData fromSoup(Soup& soup, std::vector<glm::dvec3> positions) {
  const size_t nV = positions.size(), nF = soup.faceCount();
  MeshData mesh;
  mesh.positions = std::move(positions);
  for (size_t f = 0; f < nF; ++f) {
    const int* idx = soup.faceIndices.data() + soup.faceStart[f];
    const size_t n = soup.faceStart[f + 1] - soup.faceStart[f];
    for (size_t k = 0; k < n; ++k)
      if (idx[k] < 0 || size_t(idx[k]) >= nV)
        fail("face " + std::to_string(f) + " references vertex " + std::to_string(idx[k]) + " (file has " +
             std::to_string(nV) + " vertices)");
    for (size_t k = 1; k + 1 < n; ++k) mesh.triangles.emplace_back(idx[0], idx[k], idx[k + 1]);
  }

  // Attributes count as present when every vertex a triangle uses has one; vertices no triangle uses
  // (files have them) get a placeholder so the arrays stay parallel to the positions.
  std::vector<uint8_t> used(nV, 0);
  for (const glm::uvec3& t : mesh.triangles) used[t.x] = used[t.y] = used[t.z] = 1;
  auto everyUsed = [&](const std::vector<uint8_t>& has) {
    for (size_t v = 0; v < nV; ++v)
      if (used[v] && !has[v]) return false;
    return true;
  };
  if (everyUsed(soup.hasNormal)) {
    for (size_t v = 0; v < nV; ++v)
      if (!used[v]) soup.normals[v] = glm::vec3(0.0f, 0.0f, 1.0f);
    if (!allFinite(soup.normals)) fail("vertex normal is NaN or infinite");
    // A zero normal carries no direction: then the file's normals are unusable and we drop them all
    // (the renderer falls back to geometric normals). 1e-12 on the squared length: far below any
    // normal a file would store on purpose, far above float underflow.
    const bool usable = std::all_of(soup.normals.begin(), soup.normals.end(),
                                    [](const glm::vec3& n) { return glm::dot(n, n) > 1e-12f; });
    if (usable) {
      mesh.normals = std::move(soup.normals);
      for (glm::vec3& n : mesh.normals) n = glm::normalize(n);
    }
  }
  if (everyUsed(soup.hasUv)) {
    if (!allFinite(soup.uvs)) fail("texture coordinate is NaN or infinite");
    mesh.uvs = std::move(soup.uvs);  // unused vertices keep (0, 0)
  }
  return mesh;
}

MeshData loadMeshImpl(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  if (!isMeshFile(path))
    fail("unsupported mesh format '" + ext + "' (supported: .obj .off .ply .stl .gltf .glb .dae .fbx .3ds .ac)");
  const auto& viaAssimp = assimpExtensions();
  const bool assimp = std::find(viaAssimp.begin(), viaAssimp.end(), ext) != viaAssimp.end();
  // assimp reads the file itself (and what it references: a glTF's .bin buffers), after our own
  // checks (readWithAssimp: checkBeforeAssimp).
  const std::string text = assimp ? std::string() : readWholeFile(path);
  if (assimp ? checkedFileSize(path) == 0 : text.empty()) fail("empty file");

  MeshData mesh;
  if (assimp) {
    mesh = readWithAssimp(path.string());
  } else if (ext == ".stl") {
    mesh = readStl(text);
  } else {
    Scanned scanned = ext == ".off" ? scanOff(text) : ext == ".obj" ? scanObj(text) : scanPly(text);
    // Our scan has checked every value, index and count against the file size, so OpenMesh only sees
    // files whose claims fit (it trusts header counts and loops on absurd ones).
    Soup soup = readWithOpenMesh(path.string());
    const size_t nV = soup.positions.size(), nF = soup.faceCount();
    if (scanned.vertices && nV != *scanned.vertices)
      fail("truncated or malformed: declares " + std::to_string(*scanned.vertices) + " vertices, read " + std::to_string(nV));
    if (scanned.faces && nF != *scanned.faces)
      fail("truncated or malformed: declares " + std::to_string(*scanned.faces) + " faces, read " + std::to_string(nF));
    // Positions beyond float's range would be infinite in OpenMesh's copy (and in any float image of
    // the mesh): refused as before, before the agreement check compares with them.
    for (const glm::dvec3& p : scanned.positions)
      for (int k = 0; k < 3; ++k)
        if (!(std::abs(p[k]) <= double(FLT_MAX))) fail("vertex position is NaN or infinite (beyond float's range)");
    checkAgreement(scanned.positions, soup.positions);
    mesh = fromSoup(soup, std::move(scanned.positions));
  }
  if (mesh.triangles.empty()) fail("mesh has no faces");
  for (const glm::dvec3& p : mesh.positions)
    for (int k = 0; k < 3; ++k)
      if (!(std::abs(p[k]) <= double(FLT_MAX))) fail("vertex position is NaN or infinite (beyond float's range)");
  mesh.name = path.string();
  return mesh;
}

std::string uniqueSuffix() {
  static std::atomic<unsigned> counter{0};
  return ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

}  // namespace

const std::vector<std::string>& meshExtensions() {
  static const std::vector<std::string> exts = [] {
    std::vector<std::string> e{".obj", ".off", ".ply", ".stl"};
    e.insert(e.end(), assimpExtensions().begin(), assimpExtensions().end());
    return e;
  }();
  return exts;
}

bool isMeshFile(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  const auto& exts = meshExtensions();
  return std::find(exts.begin(), exts.end(), ext) != exts.end();
}

MeshData loadMeshData(const fs::path& path) {
  // Missing or unopenable: a FileError, not a complaint about the content (the readers check again).
  if (std::error_code ec; !fs::exists(path, ec)) throw FileError(path.string() + ": mesh file not found");
  if (!std::ifstream(path, std::ios::binary))
    throw FileError(path.string() + ": cannot open the mesh file");
  try {
    return loadMeshImpl(path);
  } catch (const MeshFileError& e) {
    const std::string where = e.line ? path.string() + ":" + std::to_string(e.line) : path.string();
    throw InputError(where + ": " + e.message);
  } catch (const std::bad_alloc&) {
    throw InputError(path.string() + ": out of memory while reading the mesh");
  }
}

glm::dvec3 boundsCentre(const MeshData& mesh) {
  if (mesh.triangles.empty()) return glm::dvec3(0.0);
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      lo = glm::min(lo, mesh.positions[t[k]]);
      hi = glm::max(hi, mesh.positions[t[k]]);
    }
  return 0.5 * lo + 0.5 * hi;  // halves first: lo + hi may overflow
}

Mesh rebasedMesh(const MeshData& data, glm::dvec3 origin) {
  Mesh mesh;
  mesh.name = data.name;
  mesh.positions.reserve(data.positions.size());
  for (const glm::dvec3& p : data.positions) {
    const glm::vec3 q(p - origin);
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
      throw InputError(data.name + ": a vertex lies beyond float's range from the rebasing origin");
    mesh.positions.push_back(q);
  }
  mesh.normals = data.normals;
  mesh.uvs = data.uvs;
  mesh.triangles = data.triangles;
  return mesh;
}

Mesh loadMesh(const fs::path& path) { return rebasedMesh(loadMeshData(path)); }

void saveMeshObj(const fs::path& path, const Mesh& mesh) {
  std::error_code ec;
  if (!path.parent_path().empty()) fs::create_directories(path.parent_path(), ec);
  fs::path tmp = path;
  tmp += uniqueSuffix();
  {
    std::ofstream out(tmp);
    if (!out) throw FileError(path.string() + ": cannot write file");
    out.precision(9);  // float round-trips exactly with 9 significant digits
    out << "# " << mesh.positions.size() << " vertices, " << mesh.triangles.size() << " triangles\n";
    for (const glm::vec3& p : mesh.positions) out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (const glm::vec2& t : mesh.uvs) out << "vt " << t.x << ' ' << t.y << '\n';
    for (const glm::vec3& n : mesh.normals) out << "vn " << n.x << ' ' << n.y << ' ' << n.z << '\n';
    const bool hasT = !mesh.uvs.empty(), hasN = !mesh.normals.empty();
    for (const glm::uvec3& t : mesh.triangles) {
      out << 'f';
      for (int k = 0; k < 3; ++k) {
        const unsigned i = t[k] + 1;
        out << ' ' << i;
        if (hasT && hasN) out << '/' << i << '/' << i;
        else if (hasT) out << '/' << i;
        else if (hasN) out << "//" << i;
      }
      out << '\n';
    }
    out.flush();
    if (!out) {
      fs::remove(tmp, ec);
      throw FileError(path.string() + ": cannot write file");
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError(path.string() + ": cannot rename temporary file into place (" + ec.message() + ")");
  }
}

}  // namespace bvhlab
