// Internal to the mesh readers (datasets/mesh_io*.cpp): error type, the line/token scanner used by
// the per-format readers, and what each format's reader returns. Not part of the public interface
// (mesh_io.hpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "datasets/mesh_io.hpp"

namespace bvhlab::meshio {

// Thrown inside the readers; loadMeshData turns it into one InputError line "PATH[:LINE]: message".
struct MeshFileError {
  size_t line = 0;  // 1-based; 0 = no line
  std::string message;
};
[[noreturn]] void failAt(size_t line, std::string message);
[[noreturn]] void fail(std::string message);

// Next line (without '\n' / '\r') of a text, with its 1-based number.
struct LineScanner {
  std::string_view text;
  size_t pos = 0, lineNo = 0;
  bool next(std::string_view& line);  // false at the end of the text
};

std::vector<std::string_view> tokens(std::string_view line);
// A file's token for a message: at most 32 characters, non-printable bytes as \xNN; quoted in ''.
std::string printable(std::string_view token);
std::string quoted(std::string_view token);
std::optional<double> parseReal(std::string_view s);
std::optional<long long> parseInt(std::string_view s);
// `count` finite reals starting at toks[first] (`what` names them in the message); the values are
// appended to `out` when it is given.
void expectReals(const std::vector<std::string_view>& toks, size_t first, size_t count, size_t line, const char* what,
                 std::vector<double>* out = nullptr);

// What a text or PLY file declares and holds, from our own pass over it: the counts it promises (to
// detect truncation after OpenMesh has read it) and every vertex position in double precision, in
// file order (OpenMesh's readers narrow positions to float; these replace them).
struct Scanned {
  std::optional<size_t> vertices, faces;
  std::vector<glm::dvec3> positions;
};

Scanned scanOff(std::string_view text);  // mesh_io_off.cpp
Scanned scanObj(std::string_view text);  // mesh_io_obj.cpp
Scanned scanPly(std::string_view text);  // mesh_io_ply.cpp

// STL is read entirely by our own code (mesh_io_stl.cpp): OpenMesh merges STL corners into vertices
// keyed by their float position, which would merge distinct far vertices. Corners with the same
// (double) position become one vertex, in order of first appearance.
MeshData readStl(std::string_view text);

// OpenMesh's reading of OBJ, OFF and PLY (faces, normals, UVs) as a flat soup (mesh_io_openmesh.cpp).
struct Soup {
  std::vector<glm::vec3> positions, normals;  // positions as OpenMesh read them (float)
  std::vector<glm::vec2> uvs;
  std::vector<uint8_t> hasNormal, hasUv;
  std::vector<uint32_t> faceStart{0};  // polygon p = faceIndices[faceStart[p] .. faceStart[p+1])
  std::vector<int> faceIndices;
  size_t faceCount() const { return faceStart.size() - 1; }
};
Soup readWithOpenMesh(const std::string& path);

// Most triangles a mesh file may produce (after triangulation and, for the assimp formats, after
// instancing: a small file can place one mesh many times). 2^26 as kMaxProceduralTriangles: about
// 16-24 GB with the BVH, beyond what this testbed renders.
constexpr size_t kMaxMeshTriangles = size_t(1) << 26;

// The formats read through assimp (mesh_io_assimp.cpp): .gltf .glb .dae .fbx .3ds .ac
const std::vector<std::string>& assimpExtensions();
// The whole file through assimp: scene graph flattened (node transforms in double), triangles only
// (points and lines skipped), materials mapped (MeshData::materials). Errors are MeshFileError with
// assimp's message.
MeshData readWithAssimp(const std::string& path);
// Our own passes over a file before assimp reads it (mesh_io_prechecks.cpp): COLLADA's node graph and
// counts, AC3D's structure and counts, and content that would reach another reader than the
// extension's. Each refuses, with a named error, a file that crashed, exhausted memory or corrupted
// memory inside assimp 5.2.5.
void checkBeforeAssimp(const std::string& path);
// AC3D: every count (numvert, numsurf, refs, kids) against the lines left in the file (assimp loops
// and allocates per claimed item), every SURF a known type with a 'refs' line, lines of at least 2
// points, and every 'mat' index below the MATERIALs defined before it.
void checkAc3d(std::string_view text);

}  // namespace bvhlab::meshio
