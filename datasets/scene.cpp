#include "datasets/scene.hpp"

namespace bvhlab {

const char* objectKindName(ObjectKind k) {
  switch (k) {
    case ObjectKind::Sphere: return "sphere";
    case ObjectKind::Box: return "box";
    case ObjectKind::Cylinder: return "cylinder";
    case ObjectKind::Cone: return "cone";
    case ObjectKind::Torus: return "torus";
    case ObjectKind::Plane: return "plane";
    case ObjectKind::Mesh: return "mesh";
  }
  return "?";
}

size_t Scene::triangleCount() const {
  size_t n = 0;
  for (const Mesh& m : meshes) n += m.triangles.size();
  return n;
}

}  // namespace bvhlab
