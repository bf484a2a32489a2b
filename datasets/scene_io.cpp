// Bare meshes as scenes (scene_io.hpp: makeMeshScene, loadMeshScene) and loadInput. The TOML reader
// is scene_reader.cpp, transforms and baking scene_transform.cpp.
#include "datasets/scene_io.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "datasets/mesh_io.hpp"

namespace bvhlab {
namespace fs = std::filesystem;

Scene makeMeshScene(Mesh mesh, const MeshSceneOptions& options) {
  if (mesh.triangles.empty()) throw InputError(mesh.name + ": mesh has no triangles");
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      lo = glm::min(lo, mesh.positions[t[k]]);
      hi = glm::max(hi, mesh.positions[t[k]]);
    }
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-6f);  // a point-sized mesh still gets a camera

  Scene s;
  s.source = mesh.name;
  Material body;
  body.name = "default";
  body.color = glm::vec3(0.72f, 0.7f, 0.66f);
  body.specular = 0.25f;
  body.shininess = 48.0f;
  s.materials.push_back(body);

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

  Object obj;
  obj.name = fs::path(mesh.name).filename().string();
  obj.kind = ObjectKind::Mesh;
  obj.material = 0;
  obj.mesh = 0;
  mesh.material = 0;
  s.meshes.push_back(std::move(mesh));
  s.objects.push_back(obj);

  if (options.groundPlane) {
    Material ground;
    ground.name = "ground";
    ground.color = glm::vec3(0.55f);
    s.materials.push_back(ground);
    Object plane;
    plane.name = "ground";
    plane.kind = ObjectKind::Plane;
    plane.material = 1;
    // 1e-3 of the radius below the lowest point: triangles lying flat on the bottom would otherwise be
    // coplanar with the plane; the gap is far below a pixel at this framing.
    plane.transform = composeTransform(glm::vec3(centre.x, lo.y - 1e-3f * radius, centre.z), glm::vec3(0.0f),
                                       glm::vec3(4.0f * radius, 1.0f, 4.0f * radius));
    s.objects.push_back(plane);
  }
  return s;
}

Scene makeMeshScene(const MeshData& mesh, const MeshSceneOptions& options) {
  // A mesh whose bounding box centre lies kRebaseDistance or more from the world origin is stored
  // relative to that centre (the subtraction in double), like a far scene relative to its eye: the
  // geometry near the camera then has small coordinates and float keeps its detail.
  const glm::dvec3 centre = boundsCentre(mesh);
  const bool far = glm::any(glm::greaterThanEqual(glm::abs(centre), glm::dvec3(kRebaseDistance)));
  const glm::dvec3 origin = far ? centre : glm::dvec3(0.0);
  Scene s = makeMeshScene(rebasedMesh(mesh, origin), options);
  s.origin = origin;
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
                   "' (expected a .toml scene or a mesh: .obj .off .ply .stl)");
}

}  // namespace bvhlab
