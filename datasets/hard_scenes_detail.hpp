// Internal to datasets/hard_scenes_*.cpp (the generator of datasets/hard/, hard_scenes.hpp): number
// formatting, scene building blocks, the individual scenes, the far mesh files.
//   hard_scenes_common.cpp      formatting, materials/lights/objects, transformed(), toToml()
//   hard_scenes_cases.cpp       the individual scenes (grazing, TIR, nested, torus, inside, acne, base)
//   hard_scenes_far_meshes.cpp  mesh files far from the origin and their scenes
//   hard_scenes_families.cpp    makeHardScenes(): the suite, far/scaled families, measured facts
//   hard_scenes_files.cpp       hardSceneFiles(): README.md, .toml files, meshes; the writer
#pragma once
#include <string>
#include <vector>

#include "datasets/hard_scenes.hpp"

namespace bvhlab::hard::detail {

using glm::dvec3;
using Material = SceneSpec::Material;
using Light = SceneSpec::Light;
using Object = SceneSpec::Object;

// Shortest text that reads back as the same double / float (std::to_chars: locale-free).
std::string number(double v);
std::string number(float v);
// 12 significant digits (scene coordinates), "[x, y, z]", "\"s\"".
std::string coordinate(double v);
std::string vec(dvec3 v);
std::string quoted(const std::string& s);
std::string exponentTag(double v);  // 1e5 -> "1e5"

// Mesh files of the suite (relative to datasets/hard/).
extern const char* const kSphereMesh;
extern const char* const kCubeMesh;

Material checkerFloor(double uvScale);
Material glass(std::string name = "glass", double ior = 1.5);
Material mirror(double reflectivity);
Material paint(std::string name, dvec3 color, double specular = 0.3);
Light pointLight(dvec3 position, double intensity);
Light sunLight(dvec3 direction, double intensity);
Object object(std::string kind, std::string name, std::string material, dvec3 translate, dvec3 scale = dvec3(1.0),
              dvec3 rotate = dvec3(0.0));
Object torus(std::string name, std::string material, dvec3 translate, double major, double minor,
             dvec3 rotate = dvec3(0.0));
Object mesh(std::string name, std::string path, std::string material, dvec3 translate, dvec3 scale,
            dvec3 rotate = dvec3(0.0));

// The individual scenes (hard_scenes_cases.cpp).
SceneSpec baseScene();
SceneSpec acneScene();
HardScene acneZoom();
HardScene grazingGlass();
HardScene grazingMirror();
HardScene tirSlab();
HardScene tirSphere();
HardScene nestedSpheres();
HardScene nestedCubes();
HardScene torusAxis();
HardScene torusEdgeOn();
HardScene insideMesh(bool sphere);

// What tests/test_hard_scenes.cpp measured for each far/scaled member (hard_scenes_families.cpp).
struct FamilyMeasurement {
  const char* name;
  bool epsilon, ulp;
  const char* numbers;
  const char* why;
};
const FamilyMeasurement& familyMeasurement(const std::string& name);

// Mesh files far from the origin (hard_scenes_far_meshes.cpp): the ball mesh (kBallMesh) moved by
// `offset`, written in `format` with every digit a double holds.
struct FarMesh {
  std::string path;    // relative to datasets/hard/
  std::string format;  // "obj", "ply-ascii", "ply-binary" (property double), "off", "stl-ascii"
  dvec3 offset{0.0};   // where the ball's centre lies
};
extern const char* const kBallMesh;
std::vector<FarMesh> farMeshes();
std::string farMeshText(const FarMesh& m);
std::string ballMeshText();
// mesh_near (the ball on a floor near the origin) and its far copies mesh_far_1eN, which move the
// whole scene by the file's offset and read the ball from the far file.
HardScene meshNearScene();
std::vector<HardScene> meshFarScenes();

}  // namespace bvhlab::hard::detail
