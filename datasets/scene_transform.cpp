// Object-to-world transforms and mesh baking (scene_io.hpp), in float for analytic objects and in
// double for meshes, whose file coordinates may lie far from the origin.
#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "datasets/scene_io.hpp"

namespace bvhlab {
namespace {

// translate * Rz * Ry * Rx * scale, in T's precision.
template <class T>
glm::mat<4, 4, T> euler(glm::vec<3, T> translate, glm::vec<3, T> rotateDeg, glm::vec<3, T> scale) {
  const glm::mat<4, 4, T> I(T(1));
  const glm::mat<4, 4, T> R = glm::rotate(I, glm::radians(rotateDeg.z), glm::vec<3, T>(0, 0, 1)) *
                              glm::rotate(I, glm::radians(rotateDeg.y), glm::vec<3, T>(0, 1, 0)) *
                              glm::rotate(I, glm::radians(rotateDeg.x), glm::vec<3, T>(1, 0, 0));
  return glm::translate(I, translate) * R * glm::scale(I, scale);
}

template <class T>
glm::mat<4, 4, T> axisAngle(glm::vec<3, T> translate, glm::vec<3, T> axis, T angleDeg, glm::vec<3, T> scale) {
  const glm::mat<4, 4, T> I(T(1));
  return glm::translate(I, translate) * glm::rotate(I, glm::radians(angleDeg), glm::normalize(axis)) *
         glm::scale(I, scale);
}

}  // namespace

glm::mat4 composeTransform(glm::vec3 translate, glm::vec3 rotateDeg, glm::vec3 scale) {
  return euler(translate, rotateDeg, scale);
}
glm::mat4 composeTransform(glm::vec3 translate, glm::vec3 axis, float angleDeg, glm::vec3 scale) {
  return axisAngle(translate, axis, angleDeg, scale);
}
glm::dmat4 composeTransformD(glm::dvec3 translate, glm::dvec3 rotateDeg, glm::dvec3 scale) {
  return euler(translate, rotateDeg, scale);
}
glm::dmat4 composeTransformD(glm::dvec3 translate, glm::dvec3 axis, double angleDeg, glm::dvec3 scale) {
  return axisAngle(translate, axis, angleDeg, scale);
}

Mesh bakeMesh(const Mesh& mesh, const glm::mat4& transform) {
  Mesh out = mesh;
  for (glm::vec3& p : out.positions) p = glm::vec3(transform * glm::vec4(p, 1.0f));
  if (!out.normals.empty()) {
    const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(transform)));
    for (glm::vec3& n : out.normals) n = glm::normalize(normalMatrix * n);
  }
  // A mirroring transform turns counter-clockwise triangles clockwise; swap two corners to keep the
  // winding (and so the geometric normal) outward.
  if (glm::determinant(glm::mat3(transform)) < 0.0f)
    for (glm::uvec3& t : out.triangles) std::swap(t.y, t.z);
  return out;
}

Mesh bakeMesh(const MeshData& mesh, const glm::dmat4& transform) {
  Mesh out;
  out.name = mesh.name;
  out.positions.reserve(mesh.positions.size());
  for (const glm::dvec3& p : mesh.positions) {
    const glm::vec3 q(glm::dvec3(transform * glm::dvec4(p, 1.0)));
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
      throw InputError(mesh.name + ": a transformed vertex lies beyond float's range");
    out.positions.push_back(q);
  }
  out.uvs = mesh.uvs;
  out.triangles = mesh.triangles;
  if (!mesh.normals.empty()) {
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
    out.normals.reserve(mesh.normals.size());
    for (const glm::vec3& n : mesh.normals) out.normals.push_back(glm::vec3(glm::normalize(normalMatrix * glm::dvec3(n))));
  }
  // A mirroring transform turns counter-clockwise triangles clockwise: swap two corners (see above).
  if (glm::determinant(glm::dmat3(transform)) < 0.0)
    for (glm::uvec3& t : out.triangles) std::swap(t.y, t.z);
  return out;
}

}  // namespace bvhlab
