// A scene at a frame (datasets/animation.hpp): the camera path, the rigid transforms and the deformed
// meshes in world space, and per-object instances (local triangles + transform) for two-level trees.
#include <cmath>
#include <stdexcept>
#include <string>

#include "datasets/animation.hpp"

namespace bvhlab {
namespace {

void checkFrame(const Scene& scene, int frame) {
  const int frames = clipFrames(scene);
  if (frame < 0 || frame >= frames)
    throw std::out_of_range("frame " + std::to_string(frame) + " is outside the clip [0, " + std::to_string(frames) +
                            ") of " + scene.source.string());
}

double timeOf(const Scene& scene, int frame) { return double(frame) / clipFps(scene); }

glm::dmat4 transformAt(const ObjectAnimation& anim, int frame) {
  return anim.keys.empty() ? anim.placement : samplePose(anim.keys, double(frame)).matrix();
}

// n transformed by the inverse transpose of `m` (the rest normal when m is singular), renormalised.
glm::dvec3 transformNormal(const glm::dmat3& m, const glm::dvec3& n) {
  const double det = glm::determinant(m);
  const glm::dvec3 out = std::abs(det) > 0.0 ? glm::transpose(glm::inverse(m)) * n : n;
  const double len = glm::length(out);
  return len > 0.0 ? out / len : n;  // a NaN length (non-finite input) also keeps the rest normal
}

// The deformed rest mesh through `toWorld` into `world` (positions and normals; the topology is the
// rest mesh's and is written only when the vertex count differs).
void writeMesh(const ObjectAnimation& anim, const Mesh& rest, double t, const glm::dmat4& toWorld, Mesh& world,
               const std::string& label) {
  std::vector<glm::dvec3> p;
  deformPositions(anim, rest, t, p);
  if (world.positions.size() != rest.positions.size() || world.triangles.size() != rest.triangles.size()) {
    world.triangles = rest.triangles;
    world.uvs = rest.uvs;
  }
  world.positions.resize(p.size());
  for (size_t i = 0; i < p.size(); ++i) {
    const glm::vec3 q(glm::dvec3(toWorld * glm::dvec4(p[i], 1.0)));
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
      throw InputError(label + ": vertex " + std::to_string(i) + " leaves float's range at t = " + std::to_string(t) + " s");
    world.positions[i] = q;
  }
  world.normals.resize(rest.normals.size());
  if (rest.normals.empty()) return;
  const glm::dmat3 linear(toWorld);
  const bool bends = anim.deform.kind == DeformKind::Wave || anim.deform.kind == DeformKind::Twist;
  for (size_t i = 0; i < rest.normals.size(); ++i) {
    glm::dvec3 n(rest.normals[i]);
    if (bends) n = transformNormal(deformJacobian(anim, glm::dvec3(rest.positions[i]), t), n);
    world.normals[i] = glm::vec3(transformNormal(linear, n));
  }
}

}  // namespace

int clipFrames(const Scene& scene) { return scene.animation ? scene.animation->clip.frames : 1; }
double clipFps(const Scene& scene) { return scene.animation ? scene.animation->clip.fps : 30.0; }

void setFrame(Scene& scene, int frame) {
  checkFrame(scene, frame);
  if (!scene.animation) return;
  const SceneAnimation& a = *scene.animation;
  const double t = timeOf(scene, frame);
  if (!a.camera.empty()) scene.camera = sampleCamera(a.camera, double(frame), scene.camera);
  for (size_t i = 0; i < scene.objects.size() && i < a.objects.size(); ++i) {
    const ObjectAnimation& anim = a.objects[i];
    if (!anim.animated()) continue;
    Object& o = scene.objects[i];
    const glm::dmat4 m = transformAt(anim, frame);
    o.transform = glm::mat4(m);
    if (o.kind == ObjectKind::Mesh && anim.localMesh >= 0)
      writeMesh(anim, a.localMeshes[size_t(anim.localMesh)], t, m, scene.meshes[size_t(o.mesh)],
                "object '" + o.name + "' at frame " + std::to_string(frame));
  }
}

Scene sceneAtFrame(const Scene& scene, int frame) {
  Scene copy = scene;
  setFrame(copy, frame);
  return copy;
}

void triangleCorners(const Scene& scene, std::vector<glm::vec3>& v0, std::vector<glm::vec3>& v1,
                     std::vector<glm::vec3>& v2) {
  const size_t n = scene.triangleCount();
  v0.resize(n), v1.resize(n), v2.resize(n);
  size_t i = 0;
  for (const Mesh& m : scene.meshes)
    for (const glm::uvec3& t : m.triangles) {
      // An index past the vertices is refused, as gatherTriangles refuses it, never read.
      const size_t count = m.positions.size();
      if (t.x >= count || t.y >= count || t.z >= count)
        throw InputError("mesh '" + m.name + "': triangle " + std::to_string(i) + " uses a vertex past " + std::to_string(count));
      v0[i] = m.positions[t.x], v1[i] = m.positions[t.y], v2[i] = m.positions[t.z];
      ++i;
    }
}

std::vector<ObjectInstance> objectInstances(const Scene& scene, int frame) {
  checkFrame(scene, frame);
  std::vector<uint32_t> first(scene.meshes.size() + 1, 0);
  for (size_t m = 0; m < scene.meshes.size(); ++m) first[m + 1] = first[m] + uint32_t(scene.meshes[m].triangles.size());
  std::vector<ObjectInstance> out;
  out.reserve(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    ObjectInstance inst;
    inst.object = int(i);
    inst.mesh = o.kind == ObjectKind::Mesh ? o.mesh : -1;
    if (inst.mesh >= 0) {
      inst.firstTriangle = first[size_t(inst.mesh)];
      inst.triangleCount = first[size_t(inst.mesh) + 1] - inst.firstTriangle;
    }
    const ObjectAnimation* anim =
        scene.animation && i < scene.animation->objects.size() ? &scene.animation->objects[i] : nullptr;
    if (anim && anim->animated()) {
      inst.transform = glm::mat4(transformAt(*anim, frame));
      inst.localMesh = inst.mesh >= 0 ? anim->localMesh : -1;
      inst.moves = anim->moves();
      inst.deforms = anim->deforms();
    } else {
      // A static mesh is stored in world space: its local triangles are those, placed by the identity.
      inst.transform = inst.mesh >= 0 ? glm::mat4(1.0f) : o.transform;
    }
    out.push_back(inst);
  }
  return out;
}

Mesh worldMeshAt(const Scene& scene, int object, int frame) {
  checkFrame(scene, frame);
  if (object < 0 || size_t(object) >= scene.objects.size())
    throw std::out_of_range("object " + std::to_string(object) + " of " + std::to_string(scene.objects.size()));
  const Object& o = scene.objects[size_t(object)];
  if (o.kind != ObjectKind::Mesh) throw std::invalid_argument("object '" + o.name + "' is not a mesh");
  const ObjectAnimation* anim =
      scene.animation && size_t(object) < scene.animation->objects.size() ? &scene.animation->objects[size_t(object)] : nullptr;
  if (!anim || anim->localMesh < 0) return scene.meshes[size_t(o.mesh)];
  Mesh out;
  out.name = scene.meshes[size_t(o.mesh)].name;
  out.material = scene.meshes[size_t(o.mesh)].material;
  writeMesh(*anim, scene.animation->localMeshes[size_t(anim->localMesh)], timeOf(scene, frame), transformAt(*anim, frame), out,
            "object '" + o.name + "' at frame " + std::to_string(frame));
  return out;
}

Mesh localMeshAt(const Scene& scene, int object, int frame) {
  checkFrame(scene, frame);
  if (object < 0 || size_t(object) >= scene.objects.size())
    throw std::out_of_range("object " + std::to_string(object) + " of " + std::to_string(scene.objects.size()));
  const Object& o = scene.objects[size_t(object)];
  if (o.kind != ObjectKind::Mesh) throw std::invalid_argument("object '" + o.name + "' is not a mesh");
  const ObjectAnimation* anim =
      scene.animation && size_t(object) < scene.animation->objects.size() ? &scene.animation->objects[size_t(object)] : nullptr;
  if (!anim || anim->localMesh < 0) return scene.meshes[size_t(o.mesh)];
  const Mesh& rest = scene.animation->localMeshes[size_t(anim->localMesh)];
  Mesh out;
  out.name = rest.name;
  out.material = o.material;
  writeMesh(*anim, rest, timeOf(scene, frame), glm::dmat4(1.0), out,
            "object '" + o.name + "' at frame " + std::to_string(frame));
  return out;
}

}  // namespace bvhlab
