#include "render/prepared_scene.hpp"

namespace bvhlab {

std::unique_ptr<PreparedScene> prepareScene(Scene scene, const std::string& builder, const BuildOptions& options) {
  auto p = std::make_unique<PreparedScene>();
  p->scene = std::move(scene);
  p->data = buildSceneData(p->scene);
  p->soup = gatherTriangles(p->scene);
  if (p->soup.size() > 0) {
    std::vector<Aabb> boxes = triangleBoxes(p->soup);
    std::vector<glm::vec3> centroids = triangleCentroids(p->soup);
    p->bvh = buildBvh(builder, BuildInput{boxes, centroids}, options, &p->stats);
    p->packed = packBvh(p->bvh, p->soup);
    p->stats.bytes = p->packed.bytes();
  } else {
    findBuilder(builder);  // an unknown name is still an error without a mesh
  }
  return p;
}

}  // namespace bvhlab
