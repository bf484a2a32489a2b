// Bare meshes as scenes (scene_io.hpp: makeMeshScene, loadMeshScene) and loadInput; a model file's
// own materials and textures (glTF, COLLADA, FBX, 3DS, AC3D) become scene materials here. The TOML reader
// is scene_reader.cpp, transforms and baking scene_transform.cpp.
#include "datasets/scene_io.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <string>

#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"

namespace bvhlab {
namespace fs = std::filesystem;

namespace {

// The bare-mesh look: light grey with a soft highlight.
Material defaultBody() {
  Material body;
  body.name = "default";
  body.color = glm::vec3(0.72f, 0.7f, 0.66f);
  body.specular = 0.25f;
  body.shininess = 48.0f;
  return body;
}

// Camera, lights and ground plane around the meshes already in `s` (their materials too).
void frameMeshes(Scene& s, const MeshSceneOptions& options) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const Mesh& mesh : s.meshes)
    for (const glm::uvec3& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        lo = glm::min(lo, mesh.positions[t[k]]);
        hi = glm::max(hi, mesh.positions[t[k]]);
      }
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-6f);  // a point-sized mesh still gets a camera

  // Vertical fov 40 degrees; the bounding sphere fits when distance * sin(20 deg) >= radius, plus 10%.
  s.camera.fovDeg = 40.0f;
  s.camera.target = centre;
  const glm::vec3 viewFrom = glm::normalize(glm::vec3(0.75f, 0.55f, 1.0f));  // front-right, above
  s.camera.eye = centre + viewFrom * (1.1f * radius / std::sin(glm::radians(20.0f)));
  s.camera.up = glm::vec3(0, 1, 0);

  Light key;
  key.kind = LightKind::Directional;
  // Directions are the way the light travels: the key comes from above front-left (shadows fall back
  // right, where the camera sees them), the fill from the camera's side, low.
  key.direction = glm::normalize(glm::vec3(0.6f, -1.0f, -0.5f));
  key.color = glm::vec3(1.0f, 0.96f, 0.9f);
  key.intensity = 0.85f;
  Light fill = key;
  fill.direction = glm::normalize(glm::vec3(-1.0f, -0.3f, -0.2f));
  fill.color = glm::vec3(0.8f, 0.88f, 1.0f);
  fill.intensity = 0.25f;
  s.lights = {key, fill};

  if (options.groundPlane) {
    Material ground;
    ground.name = "ground";
    ground.color = glm::vec3(0.55f);
    s.materials.push_back(ground);
    Object plane;
    plane.name = "ground";
    plane.kind = ObjectKind::Plane;
    plane.material = int(s.materials.size()) - 1;
    // 1e-3 of the radius below the lowest point: triangles lying flat on the bottom would otherwise be
    // coplanar with the plane; the gap is far below a pixel at this framing.
    plane.transform = composeTransform(glm::vec3(centre.x, lo.y - 1e-3f * radius, centre.z), glm::vec3(0.0f),
                                       glm::vec3(4.0f * radius, 1.0f, 4.0f * radius));
    s.objects.push_back(plane);
  }
}

void addMeshObject(Scene& s, Mesh mesh, int material, std::string name) {
  Object obj;
  obj.name = std::move(name);
  obj.kind = ObjectKind::Mesh;
  obj.material = material;
  obj.mesh = int(s.meshes.size());
  mesh.material = material;
  s.meshes.push_back(std::move(mesh));
  s.objects.push_back(obj);
}

// The triangles of `all` whose material is `m`, with only the vertices they use.
Mesh subMesh(const Mesh& all, const std::vector<uint32_t>& triangleMaterials, uint32_t m) {
  Mesh out;
  out.name = all.name;
  std::vector<uint32_t> remap(all.positions.size(), UINT32_MAX);
  for (size_t t = 0; t < all.triangles.size(); ++t) {
    if (triangleMaterials[t] != m) continue;
    glm::uvec3 tri;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = all.triangles[t][k];
      if (remap[v] == UINT32_MAX) {
        remap[v] = uint32_t(out.positions.size());
        out.positions.push_back(all.positions[v]);
        if (!all.normals.empty()) out.normals.push_back(all.normals[v]);
        if (!all.uvs.empty()) out.uvs.push_back(all.uvs[v]);
      }
      tri[k] = remap[v];
    }
    out.triangles.push_back(tri);
  }
  return out;
}

// A material's base-colour texture as an index into s.images (-1: none). An external file that does
// not exist is a warning (models often name a path on their author's machine); one that exists but
// cannot be read is an error, as in scene files. Embedded images are written to a temporary file for
// OpenImageIO. `cache` maps a texture's path (or "*N" for embedded ones) to its image.
int textureFor(Scene& s, const MeshData& mesh, size_t index, std::map<std::string, int>& cache) {
  const MeshMaterial& mm = mesh.materials[index];
  const std::string what = mesh.name + ": material '" + mm.material.name + "'";
  if (!mm.texturePath.empty()) {
    if (auto it = cache.find(mm.texturePath); it != cache.end()) return it->second;
    std::error_code ec;
    if (!fs::is_regular_file(mm.texturePath, ec)) {
      std::cerr << "bvhlab: warning: " << what << ": texture '" << mm.texturePath
                << "' not found; using the base colour\n";
      return cache[mm.texturePath] = -1;
    }
    Image img;
    try {
      img = loadImage(mm.texturePath);
    } catch (const InputError& e) {
      throw InputError(what + ": texture: " + e.what());
    }
    s.images.push_back(std::move(img));
    return cache[mm.texturePath] = int(s.images.size()) - 1;
  }
  if (mm.textureBytes.empty()) return -1;
  const std::string key = "embedded:" + mm.textureBytes;  // identical images (glTF shares them) load once
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  std::string ext;
  for (char c : mm.textureFormat)
    if (std::isalnum(static_cast<unsigned char>(c)) && ext.size() < 8) ext += char(std::tolower(static_cast<unsigned char>(c)));
  static std::atomic<unsigned> counter{0};
  const fs::path tmp = fs::temp_directory_path() / ("bvhlab_texture_" + std::to_string(::getpid()) + "_" +
                                                    std::to_string(counter++) + (ext.empty() ? "" : "." + ext));
  Image img;
  try {
    {
      std::ofstream out(tmp, std::ios::binary);
      out.write(mm.textureBytes.data(), std::streamsize(mm.textureBytes.size()));
      if (!out) throw InputError("cannot write a temporary file " + tmp.string());
    }
    img = loadImage(tmp);
  } catch (const InputError& e) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw InputError(what + ": embedded texture: " + e.what());
  }
  std::error_code ec;
  fs::remove(tmp, ec);
  img.name = mesh.name + " (embedded texture of '" + mm.material.name + "')";
  s.images.push_back(std::move(img));
  return cache[key] = int(s.images.size()) - 1;
}

}  // namespace

Scene makeMeshScene(Mesh mesh, const MeshSceneOptions& options) {
  if (mesh.triangles.empty()) throw InputError(mesh.name + ": mesh has no triangles");
  Scene s;
  s.source = mesh.name;
  s.materials.push_back(defaultBody());
  const std::string name = fs::path(mesh.name).filename().string();
  addMeshObject(s, std::move(mesh), 0, name);
  frameMeshes(s, options);
  return s;
}

Scene makeMeshScene(const MeshData& mesh, const MeshSceneOptions& options) {
  // A mesh whose bounding box centre lies kRebaseDistance or more from the world origin is stored
  // relative to that centre (the subtraction in double), like a far scene relative to its eye: the
  // geometry near the camera then has small coordinates and float keeps its detail.
  const glm::dvec3 centre = boundsCentre(mesh);
  const bool far = glm::any(glm::greaterThanEqual(glm::abs(centre), glm::dvec3(kRebaseDistance)));
  const glm::dvec3 origin = far ? centre : glm::dvec3(0.0);
  if (mesh.materials.empty()) {
    Scene s = makeMeshScene(rebasedMesh(mesh, origin), options);
    s.origin = origin;
    return s;
  }
  // A file with materials (the assimp formats): one mesh object per material that triangles use, in
  // the file's material order, each with its mapped material and base-colour texture.
  if (mesh.triangles.empty()) throw InputError(mesh.name + ": mesh has no triangles");
  if (mesh.triangleMaterials.size() != mesh.triangles.size())
    throw InputError(mesh.name + ": " + std::to_string(mesh.triangleMaterials.size()) + " triangle materials for " +
                     std::to_string(mesh.triangles.size()) + " triangles");
  const Mesh all = rebasedMesh(mesh, origin);
  std::vector<uint8_t> used(mesh.materials.size(), 0);
  for (uint32_t m : mesh.triangleMaterials) {
    if (m >= used.size())
      throw InputError(mesh.name + ": material index " + std::to_string(m) + " out of range (file has " +
                       std::to_string(used.size()) + ")");
    used[m] = 1;
  }
  Scene s;
  s.source = mesh.name;
  s.origin = origin;
  std::map<std::string, int> textures;
  const std::string file = fs::path(mesh.name).filename().string();
  for (size_t m = 0; m < mesh.materials.size(); ++m) {
    if (!used[m]) continue;
    Material mat = mesh.materials[m].material;
    mat.texture = textureFor(s, mesh, m, textures);
    s.materials.push_back(mat);
    addMeshObject(s, subMesh(all, mesh.triangleMaterials, uint32_t(m)), int(s.materials.size()) - 1,
                  file + "/" + mat.name);
  }
  frameMeshes(s, options);
  return s;
}

Scene loadMeshScene(const fs::path& path, const MeshSceneOptions& options) {
  Scene s = makeMeshScene(loadMeshData(path), options);
  s.source = path;
  return s;
}

Scene loadInput(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".toml") return loadScene(path);
  if (isMeshFile(path)) return loadMeshScene(path);
  throw InputError(path.string() + ": unsupported input '" + ext +
                   "' (expected a .toml scene or a mesh: .obj .off .ply .stl .gltf .glb .dae .fbx .3ds .ac)");
}

}  // namespace bvhlab
