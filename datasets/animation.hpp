// Animated scenes (docs/scene-format.md, "Animation"): a clip of frames, keyframed rigid transforms
// per object, procedural mesh deformations, a camera path, and the scene evaluated at a frame.
//
// Time: frame f of a clip lies at f / fps seconds. Keys are at integer frame numbers; between two keys
// positions and scales are interpolated linearly and rotations by slerp (glm::slerp, shortest arc);
// before the first key and after the last the nearest key holds (clamped). Deformations are functions
// of the time in seconds, applied to an object's rest mesh in object space before its rigid transform:
//   world(p, f) = M(f) * deform(p, f / fps)
// where M(f) is the keyed transform (or the object's fixed placement when it has no keys).
//
// Code: animation.cpp (keys, camera path), animation_deform.cpp (deformations),
// animation_frame.cpp (a scene at a frame, per-object instances), animation_reader.cpp (scene-file keys).
// Everything here is sequential and deterministic: the same scene and frame give the same bits,
// whatever the thread count of the caller.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "datasets/scene.hpp"

namespace bvhlab {

// `frames` frames, indices 0 .. frames - 1, shown at `fps` frames per second.
struct Clip {
  int frames = 1;
  double fps = 30.0;
};

// One key of an object's rigid track. position is relative to Scene::origin, like every position.
struct RigidKey {
  int frame = 0;
  glm::dvec3 position{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};  // unit quaternion (w, x, y, z)
  glm::dvec3 scale{1.0};                     // every component > 0
};

struct RigidPose {
  glm::dvec3 position{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
  glm::dvec3 scale{1.0};
  glm::dmat4 matrix() const;  // translate * rotate * scale (points scaled first)
};

// The pose at `frame` (may be fractional) from keys in strictly increasing frame order (at least one):
// at a key frame exactly that key's values; between keys lerp / slerp / lerp; clamped outside.
RigidPose samplePose(const std::vector<RigidKey>& keys, double frame);

// One key of the camera path. eye and target relative to Scene::origin.
struct CameraKey {
  int frame = 0;
  glm::dvec3 eye{0.0}, target{0.0};
  float fovDeg = 50.0f;
};
// The camera at `frame`: eye, target and fov interpolated linearly between keys, clamped outside;
// `up` is the scene camera's.
Camera sampleCamera(const std::vector<CameraKey>& keys, double frame, const Camera& base);

enum class DeformKind { None, Wave, Twist, Breathe, Explode };
const char* deformKindName(DeformKind kind);  // "none", "wave", "twist", "breathe", "explode"

// A procedural deformation of an object's rest mesh, in object space (after `fit`); t in seconds.
// Lengths are object-space units, frequencies in Hz, angles in degrees. Every one is the rest mesh at
// t = 0 (explode: until t = start).
//   wave    : p += axis * amplitude * sin(2 pi frequency t) * sin(2 pi dot(p - centre, direction) / wavelength)
//             (a standing wave along `direction`, displacing along `axis`)
//   twist   : rotation about the line through `centre` along `axis` by
//             angle * sin(2 pi frequency t) * h / halfHeight, h = dot(p - centre, axis), halfHeight the
//             rest mesh's half extent along `axis` (the ends turn by +-angle, the middle stays)
//   breathe : p = centre + (p - centre) * (1 + amplitude * sin(2 pi frequency t))  (radial scale)
//   explode : every piece (a triangle, or a connected component) moves by velocity * max(0, t - start);
//             velocity = speed * (1 - speedJitter * u) * normalize(d + jitter * r), d the unit direction
//             from `centre` to the piece's rest centroid, u in [0, 1) and r in the unit ball drawn per
//             piece from `seed`. jitter < 1 keeps every piece moving away from the centre.
// `centre` defaults to the rest mesh's bounding-box centre (set at load).
struct Deform {
  DeformKind kind = DeformKind::None;
  double amplitude = 0.0;   // wave: length; breathe: fraction of the radius
  double wavelength = 1.0;  // wave
  double frequency = 1.0;   // wave, twist, breathe
  double angleDeg = 0.0;    // twist
  glm::dvec3 axis{0.0, 1.0, 0.0};       // wave (displacement), twist (unit)
  glm::dvec3 direction{1.0, 0.0, 0.0};  // wave (unit)
  glm::dvec3 centre{0.0};               // every kind (wave: where the standing wave's phase is 0)
  bool centreGiven = false;             // false: the rest mesh's bounding-box centre (set at load)
  double speed = 1.0;        // explode: length per second
  double jitter = 0.0;       // explode: direction randomness, [0, 1)
  double speedJitter = 0.0;  // explode: speed spread, [0, 1]
  double start = 0.0;        // explode: seconds
  uint64_t seed = 1;         // explode
  bool componentPieces = false;  // explode: pieces are connected components (false: triangles)
};

// Per object (parallel to Scene::objects).
struct ObjectAnimation {
  std::vector<RigidKey> keys;  // empty: the object stays at `placement`
  glm::dmat4 placement{1.0};   // object -> world (Scene::origin-relative) without keys
  Deform deform;
  // Mesh objects that move or deform: their rest mesh in object space, an index into
  // SceneAnimation::localMeshes (shared by every object with the same mesh file, fit and piece split).
  int localMesh = -1;
  // Explode: the piece of each rest vertex and each piece's velocity (object units per second).
  std::vector<uint32_t> vertexPiece;
  std::vector<glm::dvec3> pieceVelocity;
  // Twist: the rest mesh's half extent along the axis.
  double halfHeight = 1.0;

  bool moves() const { return keys.size() > 1; }  // the transform changes over the clip
  bool deforms() const { return deform.kind != DeformKind::None; }
  bool animated() const { return !keys.empty() || deforms(); }
};

struct SceneAnimation {
  Clip clip;
  std::vector<CameraKey> camera;         // empty: the camera stands still
  std::vector<ObjectAnimation> objects;  // one per Scene::objects entry
  std::vector<Mesh> localMeshes;         // object-space rest meshes
};

// ---- deformations (animation_deform.cpp) ----

// The rest mesh `rest` deformed at time t seconds, positions in double (object space).
void deformPositions(const ObjectAnimation& anim, const Mesh& rest, double t, std::vector<glm::dvec3>& out);
// The Jacobian of the deformation at rest vertex v (normals transform by its inverse transpose).
glm::dmat3 deformJacobian(const ObjectAnimation& anim, const glm::dvec3& restPosition, double t);
// Explode: pieces and seeded velocities for `rest` (sets anim.vertexPiece and anim.pieceVelocity).
void prepareExplode(ObjectAnimation& anim, const Mesh& rest);
// Gives every triangle its own three vertices (explode by triangles needs pieces that can part).
Mesh unweldTriangles(const Mesh& mesh);

// ---- a scene at a frame (animation_frame.cpp) ----

// Frames of the scene's clip: 1 for a static scene.
int clipFrames(const Scene& scene);
double clipFps(const Scene& scene);

// Sets `scene` to frame `frame`: the camera, every animated object's transform and every animated
// mesh's world-space positions and normals (triangles, vertex count and order never change, so
// gatherTriangles gives the same triangle order at every frame). Static objects are untouched. The
// loaded scene is frame 0. Throws std::out_of_range for a frame outside [0, clipFrames).
void setFrame(Scene& scene, int frame);
// A copy of `scene` at `frame` (the animation data is shared, not copied: see Scene::animation).
Scene sceneAtFrame(const Scene& scene, int frame);

// The world-space corners of every triangle of the scene as it stands (after setFrame), in
// gatherTriangles order: triangle i is (v0[i], v1[i], v2[i]). What a refit or a rebuild needs per frame
// (builders/refit.hpp FrameTriangles spans them), without gatherTriangles' normals, uvs and checks.
void triangleCorners(const Scene& scene, std::vector<glm::vec3>& v0, std::vector<glm::vec3>& v1,
                     std::vector<glm::vec3>& v2);

// An object as an instance for two-level trees: its local-space triangles and its transform at a frame.
// Moving or deforming mesh objects have object-space triangles (localMesh >= 0; a static one is its
// world-space mesh with the identity transform).
struct ObjectInstance {
  int object = -1;     // index into Scene::objects
  int mesh = -1;       // index into Scene::meshes; -1 for analytic objects
  int localMesh = -1;  // index into SceneAnimation::localMeshes; -1: the local triangles are Scene::meshes[mesh]
  uint32_t firstTriangle = 0, triangleCount = 0;  // the object's range in gatherTriangles(scene) order
  glm::mat4 transform{1.0f};  // object -> world (Scene::origin-relative) at the frame
  bool moves = false;         // transform changes over the clip
  bool deforms = false;       // local triangles change over the clip (a BLAS must be refit or rebuilt)
};
std::vector<ObjectInstance> objectInstances(const Scene& scene, int frame);
// The object's local-space mesh at `frame`: the rest mesh deformed (rest mesh when it does not deform;
// the world-space mesh for a static mesh object). Triangles and vertex order as the rest mesh's.
Mesh localMeshAt(const Scene& scene, int object, int frame);
// The object's world-space mesh at `frame` (what setFrame writes into Scene::meshes) without changing
// the scene. Throws InputError when a vertex leaves float's range.
Mesh worldMeshAt(const Scene& scene, int object, int frame);

}  // namespace bvhlab
