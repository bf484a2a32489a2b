// Scenes from files: TOML scene descriptions (docs/scene-format.md) and bare meshes.
// Code: scene_reader.cpp (TOML), scene_io.cpp (bare meshes, loadInput), scene_transform.cpp;
// animated scenes (a [clip]): datasets/animation.hpp.
// Every problem with an input is one InputError line, "FILE:LINE: message" where a line is known.
#pragma once
#include <filesystem>

#include <glm/glm.hpp>

#include "datasets/mesh_io.hpp"
#include "datasets/scene.hpp"

namespace bvhlab {

// A TOML scene (docs/scene-format.md). Paths inside it are relative to the scene file. Every image
// and mesh file is loaded once however often it is used; mesh objects are baked to world space.
Scene loadScene(const std::filesystem::path& path);

struct MeshSceneOptions {
  bool groundPlane = true;  // a finite grey plane under the mesh, 4x its bounding radius
};

// A bare mesh file (.obj .off .ply .stl .gltf .glb .dae .fbx .3ds .ac, see mesh_io.hpp) as a scene:
// camera framing the mesh's bounding sphere from a 3/4 view (front-right, above), a key light and a
// fill light, the procedural sky, a default material, optionally a ground plane touching the mesh's
// lowest point. The file is read in double; a mesh kRebaseDistance or more from the origin is stored
// relative to its bounding box centre (Scene::origin), so a far copy renders like the same mesh near
// the origin. A file with materials (MeshData::materials: the assimp formats) becomes one mesh object
// per material its triangles use, each with the mapped material and its base-colour texture (loaded
// here through OpenImageIO; a texture file that does not exist is a warning on stderr, an unreadable
// one an InputError).
Scene loadMeshScene(const std::filesystem::path& path, const MeshSceneOptions& options = {});

// The same framing for a mesh already in memory (e.g. procedural.hpp's makeLargeMesh).
Scene makeMeshScene(Mesh mesh, const MeshSceneOptions& options = {});
// The same for a mesh with double positions, rebased as loadMeshScene does (with its materials).
Scene makeMeshScene(const MeshData& mesh, const MeshSceneOptions& options = {});

// .toml -> loadScene, a mesh extension -> loadMeshScene, anything else -> InputError.
Scene loadInput(const std::filesystem::path& path);

// object -> world: translate * rotate * scale. Euler angles in degrees, applied about the fixed X,
// then Y, then Z axes (R = Rz * Ry * Rx).
glm::mat4 composeTransform(glm::vec3 translate, glm::vec3 rotateDeg, glm::vec3 scale);
glm::mat4 composeTransform(glm::vec3 translate, glm::vec3 axis, float angleDeg, glm::vec3 scale);
// The same in double precision (mesh objects are baked with these: their file coordinates may be far
// from the origin while the translation brings them near it).
glm::dmat4 composeTransformD(glm::dvec3 translate, glm::dvec3 rotateDeg, glm::dvec3 scale);
glm::dmat4 composeTransformD(glm::dvec3 translate, glm::dvec3 axis, double angleDeg, glm::dvec3 scale);

// A copy of `mesh` with positions transformed by `transform` and normals by its inverse transpose
// (renormalised). The transform must be invertible.
Mesh bakeMesh(const Mesh& mesh, const glm::mat4& transform);
// The same from double positions through a double transform, rounded to float once at the end.
Mesh bakeMesh(const MeshData& mesh, const glm::dmat4& transform);

}  // namespace bvhlab
