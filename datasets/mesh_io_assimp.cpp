// glTF 2.0, COLLADA, FBX, 3DS and AC3D through the Open Asset Import Library (mesh_io_detail.hpp:
// readWithAssimp). assimp parses the file and triangulates; this file flattens the node graph in
// double precision, keeps normals, the first UV channel and the materials (mapped to the scene's
// material model), and applies the same limits as the other readers.
//
// Precision: Debian's libassimp is built without ASSIMP_DOUBLE_PRECISION (ai_real is float, checked
// below), so assimp itself stores positions, normals and node matrices as float. Positions here are
// those floats widened to double, with the node transforms applied in double: a model whose own
// vertices lie 1e5 or more from its origin has already lost its detail inside assimp -- the
// far-coordinate guarantee of the OBJ/OFF/PLY/STL readers does not hold for these formats.
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <type_traits>
#include <utility>

#include "datasets/mesh_io_detail.hpp"

static_assert(std::is_same_v<ai_real, float>,
              "libassimp now stores double: update the precision notes here and in docs/scene-format.md");

namespace bvhlab::meshio {
namespace fs = std::filesystem;

namespace {

// Triangulate: polygons to triangles (assimp's ear clipping; points and lines stay and are skipped
// below). ValidateDataStructure: assimp checks indices and counts, so a broken file is its error
// message, not our crash (measured: free within noise). Not JoinIdenticalVertices: it would re-index
// the per-corner vertices COLLADA/FBX/AC3D importers emit (CG-57.ac: 352,821 -> 163,104 vertices),
// but it took 270-290 ms of a 65-80 ms import on that 180k-triangle file, and nothing downstream
// needs shared vertices (the renderer gathers a triangle soup). Not GenNormals: a mesh without
// normals renders with geometric normals, as the other formats do (and smoothing needs joined
// vertices).
constexpr unsigned kImportFlags = aiProcess_Triangulate | aiProcess_ValidateDataStructure;

// Vertices the flattened mesh may hold: 3 per triangle of the triangle limit (an indexed mesh has
// fewer; a file whose meshes are mostly unused vertices would otherwise escape the limit).
constexpr size_t kMaxMeshVertices = 3 * kMaxMeshTriangles;

// A squared normal length below which the normal carries no direction (as fromSoup in mesh_io.cpp):
// far below any normal a file stores on purpose, far above float underflow.
constexpr double kMinNormalLength2 = 1e-12;

glm::dmat4 toDmat4(const aiMatrix4x4& m) {
  // aiMatrix4x4 is row-major with column vectors (translation in a4, b4, c4); glm is column-major.
  glm::dmat4 r;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) r[col][row] = double(m[row][col]);
  return r;
}

bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

float clamp01(float v, float fallback) { return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : fallback; }

glm::vec3 colour(const aiColor4D& c) {
  return glm::vec3(clamp01(c.r, 0.8f), clamp01(c.g, 0.8f), clamp01(c.b, 0.8f));
}

// The nearest scene material (docs/scene-format.md, "Models: glTF, COLLADA, FBX, 3DS, AC3D").
MeshMaterial mapMaterial(const aiScene& scene, const aiMaterial& m, const fs::path& folder, size_t index) {
  MeshMaterial out;
  Material& mat = out.material;
  aiString name;
  mat.name = m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length ? std::string(name.C_Str())
                                                                       : "material" + std::to_string(index);
  // The bare-mesh look (scene_io.cpp) where the file says nothing.
  mat.color = glm::vec3(0.72f, 0.7f, 0.66f);
  mat.specular = 0.25f;
  mat.shininess = 48.0f;

  aiColor4D c;
  const bool hasBase = m.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS;  // glTF baseColorFactor
  if (hasBase || m.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) mat.color = colour(c);

  float metallic = 0.0f, roughness = 1.0f, f = 0.0f;
  if (m.Get(AI_MATKEY_METALLIC_FACTOR, metallic) == AI_SUCCESS) {
    // Metallic-roughness (glTF): a mirror as far as the metal is smooth; glTF's defaults (metallic 1,
    // roughness 1) are a rough metal, which a Whitted tracer shows as diffuse, not as a mirror.
    m.Get(AI_MATKEY_ROUGHNESS_FACTOR, roughness);
    metallic = clamp01(metallic, 0.0f);
    roughness = clamp01(roughness, 1.0f);
    mat.reflectivity = metallic * (1.0f - roughness);
    mat.specular = 0.5f * (1.0f - roughness);
    // Blinn-Phong exponent of the same lobe width: 2/alpha^2 - 2 with alpha = roughness^2 (Walter et
    // al. 2007), kept in the scene format's (0, 10000].
    const float alpha2 = std::max(roughness * roughness * roughness * roughness, 2.0f / 10002.0f);
    mat.shininess = std::clamp(2.0f / alpha2 - 2.0f, 1.0f, 10000.0f);
  } else {
    if (m.Get(AI_MATKEY_REFLECTIVITY, f) == AI_SUCCESS) mat.reflectivity = clamp01(f, 0.0f);
    aiColor4D spec;
    if (m.Get(AI_MATKEY_COLOR_SPECULAR, spec) == AI_SUCCESS) {
      float strength = 1.0f;
      m.Get(AI_MATKEY_SHININESS_STRENGTH, strength);
      mat.specular = clamp01(std::max({spec.r, spec.g, spec.b}) * strength, mat.specular);
    }
    if (m.Get(AI_MATKEY_SHININESS, f) == AI_SUCCESS && f > 0.0f && f <= 10000.0f) mat.shininess = f;
  }

  // Glass: glTF's KHR_materials_transmission, else an opacity below 1 (COLLADA, FBX, 3DS, AC3D, and
  // glTF's alpha).
  float transparency = 0.0f;
  if (m.Get(AI_MATKEY_TRANSMISSION_FACTOR, f) == AI_SUCCESS) transparency = clamp01(f, 0.0f);
  if (m.Get(AI_MATKEY_OPACITY, f) == AI_SUCCESS) transparency = std::max(transparency, 1.0f - clamp01(f, 1.0f));
  mat.transparency = transparency;
  // reflectivity + transparency <= 1 (the scene's rule): the mirror is a fraction of the opaque part.
  mat.reflectivity *= 1.0f - transparency;
  if (m.Get(AI_MATKEY_REFRACTI, f) == AI_SUCCESS && std::isfinite(f) && f >= 1.0f && f <= 10.0f) mat.ior = f;

  aiColor4D e;
  if (m.Get(AI_MATKEY_COLOR_EMISSIVE, e) == AI_SUCCESS) {
    float intensity = 1.0f;
    m.Get(AI_MATKEY_EMISSIVE_INTENSITY, intensity);
    if (!std::isfinite(intensity) || intensity < 0.0f) intensity = 1.0f;
    for (int k = 0; k < 3; ++k) {
      const float v = (&e.r)[k] * intensity;
      mat.emission[k] = std::isfinite(v) && v > 0.0f ? v : 0.0f;
    }
  }

  // Base-colour texture (UV channel 0 only: the only one kept).
  for (aiTextureType type : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}) {
    if (m.GetTextureCount(type) == 0) continue;
    aiString path;
    unsigned uvIndex = 0;
    if (m.GetTexture(type, 0, &path, nullptr, &uvIndex) != AI_SUCCESS || uvIndex != 0 || !path.length) break;
    if (const aiTexture* t = scene.GetEmbeddedTexture(path.C_Str())) {
      if (t->mHeight == 0 && t->pcData) {  // a compressed image file (PNG, JPEG) in memory
        out.textureBytes.assign(reinterpret_cast<const char*>(t->pcData), t->mWidth);
        out.textureFormat = t->achFormatHint;
      }  // raw texels (mHeight > 0) come only from formats not read here
    } else {
      std::string p = path.C_Str();
      std::replace(p.begin(), p.end(), '\\', '/');  // FBX and 3DS written on Windows
      fs::path file = fs::path(p).is_absolute() ? fs::path(p) : folder / p;
      std::error_code ec;
      // Models moved from another machine keep the author's absolute path: try the bare file name
      // next to the model.
      if (!fs::exists(file, ec) && fs::exists(folder / fs::path(p).filename(), ec)) file = folder / fs::path(p).filename();
      out.texturePath = file.string();
    }
    // With a texture, a Phong format's diffuse colour is what the texture replaces: white, unless
    // the file states a base colour factor that multiplies it (glTF).
    if (!hasBase) mat.color = glm::vec3(1.0f);
    break;
  }
  return out;
}

struct Flattener {
  const aiScene& scene;
  MeshData& out;
  std::vector<uint8_t> meshHasNormals, meshHasUvs;
  bool anyNormals = false, anyUvs = false;

  static size_t triangleCount(const aiMesh& mesh) {
    size_t tris = 0;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) tris += mesh.mFaces[f].mNumIndices == 3;
    return tris;
  }

  void addInstance(const aiMesh& mesh, const glm::dmat4& toWorld) {
    const size_t base = out.positions.size();
    const glm::dmat3 linear(toWorld);
    const double det = glm::determinant(linear);
    // Normals go through the cofactor matrix (det * inverse transpose; defined for singular
    // transforms too), its sign corrected so they keep their side.
    const double side = det < 0.0 ? -1.0 : 1.0;
    const glm::dmat3 normalMatrix(side * glm::cross(linear[1], linear[2]), side * glm::cross(linear[2], linear[0]),
                                  side * glm::cross(linear[0], linear[1]));
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      const glm::dvec3 q(toWorld * glm::dvec4(p.x, p.y, p.z, 1.0));
      if (!finite3(q)) fail("vertex position is NaN or infinite (mesh '" + std::string(mesh.mName.C_Str()) + "')");
      out.positions.push_back(q);
      glm::dvec3 n(0.0);
      if (mesh.mNormals) n = normalMatrix * glm::dvec3(mesh.mNormals[v].x, mesh.mNormals[v].y, mesh.mNormals[v].z);
      const double len2 = glm::dot(n, n);
      // A missing, zero or non-finite normal stays (0,0,0) here and is repaired below.
      out.normals.push_back(len2 > 0.0 && std::isfinite(len2) ? glm::vec3(n / std::sqrt(len2)) : glm::vec3(0.0f));
      glm::vec2 uv(0.0f);
      if (mesh.mTextureCoords[0]) {
        uv = glm::vec2(mesh.mTextureCoords[0][v].x, mesh.mTextureCoords[0][v].y);
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) fail("texture coordinate is NaN or infinite");
      }
      out.uvs.push_back(uv);
    }
    anyNormals = anyNormals || mesh.mNormals;
    anyUvs = anyUvs || mesh.mTextureCoords[0];

    const bool mirror = det < 0.0;  // keep the winding (and the geometric normal) outward, as bakeMesh
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      glm::uvec3 t;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh.mNumVertices)
          fail("face " + std::to_string(f) + " references vertex " + std::to_string(face.mIndices[k]) + " (mesh has " +
               std::to_string(mesh.mNumVertices) + ")");
        t[k] = unsigned(base + face.mIndices[k]);
      }
      if (mirror) std::swap(t.y, t.z);
      out.triangles.push_back(t);
      out.triangleMaterials.push_back(mesh.mMaterialIndex);
    }
  }

  void flatten() {
    // Every (mesh, transform) placement, depth first with an explicit stack (a file's node tree may
    // be deep); then the totals are checked against the limits before anything is allocated.
    std::vector<std::pair<const aiMesh*, glm::dmat4>> instances;
    std::vector<std::pair<const aiNode*, glm::dmat4>> stack{{scene.mRootNode, toDmat4(scene.mRootNode->mTransformation)}};
    std::vector<size_t> meshTriangles(scene.mNumMeshes);
    for (unsigned i = 0; i < scene.mNumMeshes; ++i) meshTriangles[i] = triangleCount(*scene.mMeshes[i]);
    size_t triangles = 0, vertices = 0;
    while (!stack.empty()) {
      auto [node, toWorld] = stack.back();
      stack.pop_back();
      for (unsigned i = 0; i < node->mNumMeshes; ++i) {
        const unsigned m = node->mMeshes[i];
        if (m >= scene.mNumMeshes) fail("node references a mesh that does not exist");
        if (meshTriangles[m] == 0) continue;  // points and lines (AC3D line surfaces, COLLADA lines)
        triangles += meshTriangles[m];
        vertices += scene.mMeshes[m]->mNumVertices;
        if (triangles > kMaxMeshTriangles)
          fail("more than " + std::to_string(kMaxMeshTriangles) + " triangles after instancing (kMaxMeshTriangles)");
        if (vertices > kMaxMeshVertices)
          fail("more than " + std::to_string(kMaxMeshVertices) + " vertices after instancing");
        instances.emplace_back(scene.mMeshes[m], toWorld);
      }
      for (unsigned c = node->mNumChildren; c-- > 0;)
        stack.emplace_back(node->mChildren[c], toWorld * toDmat4(node->mChildren[c]->mTransformation));
    }
    out.positions.reserve(vertices);
    out.normals.reserve(vertices);
    out.uvs.reserve(vertices);
    out.triangles.reserve(triangles);
    out.triangleMaterials.reserve(triangles);
    for (const auto& [mesh, toWorld] : instances) addInstance(*mesh, toWorld);
  }

  // Normals are kept when any mesh has them; a vertex without one (a mesh without normals, or a
  // zero/non-finite one) gets the normal of a triangle that uses it -- flat, as the renderer would
  // shade it without normals. Vertices only degenerate triangles use get +Z (they cover no pixel).
  void finishNormals() {
    if (!anyNormals) {
      out.normals.clear();
      return;
    }
    auto bad = [](const glm::vec3& n) { return !(double(glm::dot(n, n)) > kMinNormalLength2); };
    for (const glm::uvec3& t : out.triangles) {
      if (!bad(out.normals[t.x]) && !bad(out.normals[t.y]) && !bad(out.normals[t.z])) continue;
      const glm::dvec3 g = glm::cross(out.positions[t.y] - out.positions[t.x], out.positions[t.z] - out.positions[t.x]);
      const double len = glm::length(g);
      if (!(len > 0.0) || !std::isfinite(len)) continue;
      for (int k = 0; k < 3; ++k)
        if (bad(out.normals[t[k]])) out.normals[t[k]] = glm::vec3(g / len);
    }
    for (glm::vec3& n : out.normals)
      if (bad(n)) n = glm::vec3(0.0f, 0.0f, 1.0f);
  }
};

}  // namespace

const std::vector<std::string>& assimpExtensions() {
  static const std::vector<std::string> exts{".gltf", ".glb", ".dae", ".fbx", ".3ds", ".ac"};
  return exts;
}

MeshData readWithAssimp(const std::string& path) {
  Assimp::Importer importer;
  // AC3D 'subdiv N' asks for N Catmull-Clark steps (4^N triangles): a resource the file controls.
  // Kept off; the control mesh is used.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_AC_EVAL_SUBDIVISION, false);
  checkBeforeAssimp(path);
  const aiScene* scene = importer.ReadFile(path, kImportFlags);
  if (!scene) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown error";
    // assimp tries every reader when the one for the extension refuses the content.
    if (why.rfind("No suitable reader", 0) == 0)
      fail("not a readable " + fs::path(path).extension().string() + " file (assimp: no reader accepts its content)");
    fail("cannot read the file (assimp: " + why + ")");
  }
  if (!scene->mRootNode || scene->mNumMeshes == 0) fail("mesh has no faces (the file holds no meshes)");

  MeshData mesh;
  const fs::path folder = fs::path(path).parent_path();
  for (unsigned i = 0; i < scene->mNumMaterials; ++i) mesh.materials.push_back(mapMaterial(*scene, *scene->mMaterials[i], folder, i));
  if (mesh.materials.empty()) mesh.materials.emplace_back();  // assimp always adds a default; be safe

  Flattener flat{*scene, mesh, {}, {}};
  flat.flatten();
  for (uint32_t& m : mesh.triangleMaterials)
    if (m >= mesh.materials.size()) m = 0;  // ValidateDataStructure refuses this; never index past the end
  flat.finishNormals();
  if (!flat.anyUvs) mesh.uvs.clear();
  return mesh;
}

}  // namespace bvhlab::meshio
