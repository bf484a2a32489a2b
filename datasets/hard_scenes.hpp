// hard_scenes.hpp — the scene-level hard cases (datasets/hard/): whole scenes where a
// Whitted tracer's numerics fail visibly — grazing Fresnel, total internal reflection, nested
// refraction, self-intersection ("acne") of secondary rays, torus tangents, a camera inside a closed
// mesh, and one base scene moved far from the origin and scaled (it should render the same image).
// The ray-level cases (single rays against triangle soups) are hard_cases.hpp.
//
// Everything here is a pure function: the committed files in datasets/hard/ are exactly what
// hardSceneFiles() returns (tests/test_hard_scenes.cpp checks it; writeHardSceneFiles regenerates them).
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab::hard {

// A scene in the terms of the TOML format (docs/scene-format.md), only what the hard scenes use.
// Coordinates are doubles so that far offsets are written exactly as computed; the loader rounds
// them to float, as it would any scene file.
struct SceneSpec {
  struct Material {
    std::string name;
    glm::dvec3 color{0.8};
    std::string texture;  // "" = none
    double uvScale = 1.0;
    double diffuse = 1.0, ambient = 0.1, specular = 0.0, shininess = 32.0;
    double reflectivity = 0.0, transparency = 0.0, ior = 1.5;
  };
  struct Light {
    bool directional = false;
    glm::dvec3 vector{0.0};  // position (point) or travel direction (directional)
    glm::dvec3 color{1.0};
    double intensity = 1.0;
  };
  struct Object {
    std::string kind;  // sphere, box, torus, plane, mesh
    std::string name;
    std::string material;
    glm::dvec3 translate{0.0};
    glm::dvec3 rotate{0.0};  // Euler degrees (R = Rz Ry Rx)
    glm::dvec3 scale{1.0};
    double majorRadius = 1.0, minorRadius = 0.25;  // torus
    std::string mesh;                              // mesh: path relative to the scene file
  };
  std::string description;
  glm::dvec3 eye{0.0, 1.0, 5.0}, target{0.0}, up{0.0, 1.0, 0.0};
  double fovDeg = 45.0;
  int width = 96, height = 64, maxDepth = 6;
  bool worldColor = false;  // false: the default sky; true: a constant colour
  glm::dvec3 worldRgb{0.0};
  glm::dvec3 ambient{0.1};
  std::vector<Light> lights;
  std::vector<Material> materials;
  std::vector<Object> objects;
};

// The same scene moved and scaled as a whole: every point p becomes offset + scale * p (camera,
// point lights, object translations), every size is multiplied by `scale`. Directions, angles and
// colours are unchanged, and point lights have no falloff, so the ideal image is unchanged too.
SceneSpec transformed(const SceneSpec& s, glm::dvec3 offset, double scale);

// TOML text of a spec (comment header from `description`), loadable by loadScene.
std::string toToml(const SceneSpec& s);

// One scene of the suite with its documentation.
struct HardScene {
  std::string name;        // file stem in datasets/hard/
  std::string provokes;    // what numerical failure the scene is built to provoke
  std::string correct;     // what a correct image looks like
  std::string variants;    // which robustness variants should pass, and what is expected of the others
  SceneSpec spec;
  // Far/scaled family: the member's placement relative to `reference` (the unit-scale scene at the
  // origin whose image it must reproduce); reference empty for scenes outside a family.
  std::string reference;
  glm::dvec3 offset{0.0};
  double scale = 1.0;
  // Family members: does the image match the reference's (README's criterion) with the epsilon / the
  // ULP origin offset? Measured, recorded in the generator, asserted by tests/test_hard_scenes.cpp.
  bool matchesWithEpsilon = false, matchesWithUlp = false;
  bool cameraInsideClosedMesh = false;  // every primary ray must hit the mesh
  bool uniformSurfaces = false;  // each surface's correct colour is one constant (acne shows as outliers)
};

// The whole suite, in README order.
std::vector<HardScene> makeHardScenes();

// Generated meshes the scenes refer to ("meshes/NAME.obj" relative to datasets/hard/): closed,
// every vertex shared by all its triangles (no seams, no duplicates), no normals or UVs.
struct GeneratedFile {
  std::string path;  // relative to datasets/hard/
  std::string text;
};
// Every file of datasets/hard/: README.md, one .toml per scene, the meshes.
std::vector<GeneratedFile> hardSceneFiles();
// Writes hardSceneFiles() under `dir` (creating it); returns the paths written.
std::vector<std::filesystem::path> writeHardSceneFiles(const std::filesystem::path& dir);

}  // namespace bvhlab::hard
