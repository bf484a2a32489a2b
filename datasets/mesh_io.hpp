// Triangle meshes from files: OBJ, OFF (ASCII), PLY (ASCII and binary), STL (ASCII and binary), and
// through the Open Asset Import Library (assimp, mesh_io_assimp.cpp): glTF 2.0 (.gltf, .glb), COLLADA
// (.dae), FBX (.fbx), 3DS (.3ds), AC3D (.ac) -- scene graphs flattened, with their materials.
//
// OpenMesh's readers do the parsing into a plain indexed triangle soup (no half-edge topology, so
// non-manifold scans lose nothing). OpenMesh accepts many broken files silently or loops on absurd
// counts, so every file first goes through a cheap structural pre-check of our own (header counts
// against file size, line shapes, index ranges, NaN/Inf), and the result is validated again after.
// Every problem is one InputError line: "PATH[:LINE]: message".
//
// Positions are read in double precision and stay double (MeshData) until the caller rebases them
// (rebasedMesh): a scanned or georeferenced mesh 1e5..1e7 from the origin keeps its detail, which
// float (spacing 2^-7 at 1e5, 1 at 1e7) would round away. The code is split by format:
// mesh_io_{off,obj,ply,stl}.cpp (our own scanners, which also collect the double positions),
// mesh_io_openmesh.cpp (OpenMesh for faces, normals, UVs of OBJ/OFF/PLY), mesh_io_text.cpp.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "datasets/scene.hpp"

namespace bvhlab {

// A material a mesh file defines (the assimp formats; OBJ/OFF/PLY/STL define none), already mapped to
// the scene's material model (docs/scene-format.md, "Models: glTF, COLLADA, FBX, 3DS, AC3D"). The base-colour texture
// is not loaded by the mesh reader (a TOML mesh object ignores the file's materials): it is named by
// a file path or carried as an embedded image file's bytes, and loadMeshScene loads it.
struct MeshMaterial {
  Material material;         // material.texture is -1 here
  std::string texturePath;   // base-colour image file, resolved against the mesh file's folder; or ""
  std::string textureBytes;  // an embedded (compressed) image file: its bytes; or ""
  std::string textureFormat; // the embedded image's format hint ("png", "jpg"), without a dot
};

// A mesh as its file states it: positions in double, in the file's own coordinates.
struct MeshData {
  std::string name;  // source path
  std::vector<glm::dvec3> positions;
  std::vector<glm::vec3> normals;  // per vertex or empty
  std::vector<glm::vec2> uvs;      // per vertex or empty
  std::vector<glm::uvec3> triangles;
  // The file's materials, and per triangle an index into them (both empty for formats without
  // materials; then every triangle uses the caller's material).
  std::vector<MeshMaterial> materials;
  std::vector<uint32_t> triangleMaterials;
};

// Loads a mesh with double positions (every format below; binary STL stores float, which converts
// exactly). Same checks and errors as loadMesh. The assimp formats are parsed by assimp in float
// (Debian's libassimp is built without ASSIMP_DOUBLE_PRECISION): their positions are exact float
// values widened to double, and only the node transforms are applied in double -- a model whose own
// vertices lie far from its origin has lost detail inside assimp already.
MeshData loadMeshData(const std::filesystem::path& path);

// Centre of the bounding box of the vertices that triangles use (double; (0,0,0) without triangles).
glm::dvec3 boundsCentre(const MeshData& mesh);

// The mesh with positions float(p - origin): exact to float's relative precision of |p - origin|, so
// choose `origin` near the geometry (Scene::origin, or boundsCentre) for far meshes. Throws
// InputError naming the mesh when a rebased coordinate does not fit a float.
Mesh rebasedMesh(const MeshData& mesh, glm::dvec3 origin = glm::dvec3(0.0));

// Loads a mesh in its own (object) space. Polygons are fan-triangulated (exact for convex faces).
// Normals and UVs are kept when the file gives one for every vertex (OBJ: one per position, last
// wins), otherwise left empty. Mesh::name is the path; Mesh::material is 0. Positions are rounded
// to float in the file's coordinates (rebasedMesh(loadMeshData(path))): use loadMeshData for meshes
// far from the origin.
Mesh loadMesh(const std::filesystem::path& path);

// Lower-case extensions (with the dot) that loadMesh reads: .obj .off .ply .stl .gltf .glb .dae .fbx
// .3ds .ac
const std::vector<std::string>& meshExtensions();
bool isMeshFile(const std::filesystem::path& path);  // by extension only

// Writes a mesh as a Wavefront OBJ (positions, normals/UVs when present); atomic like the image
// writers. For tests, debugging and exporting procedural meshes.
void saveMeshObj(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace bvhlab
