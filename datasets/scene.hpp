// The in-memory scene: what a scene file (TOML, see docs/scene-format.md) or a bare mesh turns into.
// Everything downstream (builders, shader assembly, the GPU and CPU renderers) reads only this.
#pragma once
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <stdexcept>

#include <glm/glm.hpp>

namespace bvhlab {

struct Camera {
  glm::vec3 eye{0.0f, 1.0f, 5.0f};
  glm::vec3 target{0.0f, 0.0f, 0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fovDeg = 50.0f;  // vertical field of view
};

enum class LightKind { Point, Directional };
struct Light {
  LightKind kind = LightKind::Point;
  glm::vec3 position{0.0f, 5.0f, 0.0f};   // Point
  glm::vec3 direction{0.0f, -1.0f, 0.0f}; // Directional: direction the light travels (normalised on load)
  glm::vec3 color{1.0f};
  float intensity = 1.0f;
};

// An RGBA32F image in linear colour, rows bottom-up (GL convention: row 0 is v = 0).
struct Image {
  int width = 0, height = 0;
  std::vector<glm::vec4> texels;
  std::string name;  // file path or generator name, for messages
};

enum class WorldKind { Color, Sky, Map };
struct World {
  WorldKind kind = WorldKind::Sky;
  glm::vec3 color{0.0f};                 // Color
  glm::vec3 zenith{0.25f, 0.45f, 0.85f}; // Sky: vertical gradient zenith -> horizon -> ground
  glm::vec3 horizon{0.85f, 0.9f, 1.0f};
  glm::vec3 ground{0.35f, 0.32f, 0.3f};
  int image = -1;         // Map: index into Scene::images (equirectangular, +Y up)
  float intensity = 1.0f; // multiplies the world radiance
  float rotationDeg = 0.0f; // rotation of the map about +Y
  glm::vec3 ambient{0.1f};  // ambient light colour used by Material::ambient
};

struct Material {
  std::string name;
  glm::vec3 color{0.8f};   // base colour (multiplies the texture when there is one)
  int texture = -1;        // index into Scene::images, or -1
  glm::vec2 uvScale{1.0f}; // texture repeat
  float diffuse = 1.0f;    // Lambert weight
  float ambient = 0.1f;    // ambient weight (times World::ambient)
  float specular = 0.0f;   // Blinn-Phong highlight weight
  float shininess = 32.0f;
  float reflectivity = 0.0f;  // mirror fraction of the opaque part
  float transparency = 0.0f;  // dielectric fraction: split by Schlick Fresnel into reflection/refraction
  float ior = 1.5f;           // index of refraction (> 0)
  glm::vec3 emission{0.0f};
};

enum class ObjectKind { Sphere, Box, Cylinder, Cone, Torus, Plane, Mesh };
constexpr int kObjectKindCount = 7;
const char* objectKindName(ObjectKind k);

// Analytic objects live in a canonical object space, placed by `transform` (object -> world):
//   sphere   : unit sphere at the origin
//   box      : [-1,1]^3
//   cylinder : radius 1 about +Y, y in [-1,1], capped
//   cone     : apex at y = 1, base of radius 1 at y = -1, capped
//   torus    : in the XZ plane, major radius `majorRadius`, minor radius `minorRadius`
//   plane    : y = 0, |x|,|z| <= 1 (scale it to size); `infinite` drops the bounds
// Meshes are baked into world space by `transform` at load time (one BVH over all triangles).
struct Object {
  std::string name;
  ObjectKind kind = ObjectKind::Sphere;
  glm::mat4 transform{1.0f};
  int material = 0;
  float majorRadius = 1.0f, minorRadius = 0.25f;  // Torus
  bool infinite = false;                          // Plane
  int mesh = -1;                                  // Mesh: index into Scene::meshes
};

// A triangle mesh in world space. normals/uvs are per vertex and may be empty.
struct Mesh {
  std::string name;  // source path
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec2> uvs;
  std::vector<glm::uvec3> triangles;
  int material = 0;
};

struct RenderSettings {
  int width = 640, height = 360;
  int maxDepth = 5;  // path segments per pixel, primary ray included (report's "recursion depth")
  float exposure = 1.0f;
  bool reinhard = false;  // tone map before the sRGB encode
};

// Distance from the world origin (largest coordinate) at which a scene is stored relative to a nearby
// origin (Scene::origin). Below it positions keep their coordinates exactly; at 1024 float spacing is
// 2^-13 = 1.2e-4, about where it reaches the tracer's secondary-ray offsets and rounding would show.
constexpr double kRebaseDistance = 1024.0;

struct SceneAnimation;  // datasets/animation.hpp

struct Scene {
  std::filesystem::path source;  // scene file (or mesh file) it came from
  // World position of this scene's coordinate origin. Every position (camera, lights, object
  // translations, baked mesh vertices) is stored relative to it. The loader sets it to the camera eye
  // when the eye is 1024 or more from the world origin (camera-relative rendering, computed in double
  // precision), else it stays 0. A bare mesh scene (loadMeshScene) uses the mesh's bounding box centre
  // instead, by the same distance rule. Mesh files are read in double and baked relative to this
  // origin in double, so a mesh whose own coordinates are far from the world origin keeps its detail.
  glm::dvec3 origin{0.0};
  Camera camera;
  std::vector<Light> lights;
  World world;
  std::vector<Material> materials;
  std::vector<Object> objects;   // analytic objects and mesh instances
  std::vector<Mesh> meshes;      // world-space triangles
  std::vector<Image> images;     // textures and world maps
  RenderSettings settings;
  // The clip, keys, deformations and object-space rest meshes of an animated scene (a [clip] in the
  // scene file; datasets/animation.hpp), or null for a static scene. Immutable and shared by copies;
  // the fields above hold frame 0 (setFrame moves them to another frame).
  std::shared_ptr<const SceneAnimation> animation;

  size_t triangleCount() const;
};

// Thrown for every kind of bad input; what() is one line naming the file (and line or key).
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A file that is missing or cannot be opened or read: the content is not at fault, so the command line
// counts it as a runtime failure (exit 1), not as bad input (exit 2). Caught as an InputError elsewhere.
struct FileError : InputError {
  using InputError::InputError;
};

}  // namespace bvhlab
