#include "render/prepared_scene.hpp"

#include "builders/epo.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "layout/tree_hash.hpp"

namespace bvhlab {

std::unique_ptr<PreparedScene> prepareScene(Scene scene, const std::string& builder, const BuildOptions& options,
                                            const std::string& layout, const std::string& triangles) {
  const LayoutInfo& packer = findLayout(layout);  // an unknown name fails before the build
  const std::string& triangleFormat = findTriangleFormat(triangles).name;
  auto p = std::make_unique<PreparedScene>();
  p->scene = std::move(scene);
  p->cost = options.cost;
  p->data = buildSceneData(p->scene);
  p->soup = gatherTriangles(p->scene);
  if (p->soup.size() > 0) {
    std::vector<Aabb> boxes = triangleBoxes(p->soup);
    std::vector<glm::vec3> centroids = triangleCentroids(p->soup);
    p->bvh = buildBvh(builder, BuildInput{boxes, centroids, p->soup.v0, p->soup.v1, p->soup.v2}, options, &p->stats);
    p->packed = packer.pack(p->bvh, p->soup);
    packTriangles(p->packed, p->soup, triangleFormat);
    p->stats.bytes = p->packed.bytes();
  } else {
    findBuilder(builder);  // an unknown name is still an error without a mesh
    p->packed.layout = packer.name;
    p->packed.triangleFormat = triangleFormat;
  }
  return p;
}

std::string PreparedScene::treeHash() const {
  if (treeHash_.empty() && soup.size() > 0) treeHash_ = packedTreeHash(packed);
  return treeHash_;
}

double PreparedScene::endPointOverlap() const {
  // No tree (a two-level frame's streams: render/render_clip.cpp): no EPO either.
  if (epo_ < 0.0)
    epo_ = soup.size() > 0 && !bvh.nodes.empty() ? bvhlab::endPointOverlap(bvh, soup.v0, soup.v1, soup.v2, cost) : 0.0;
  return epo_;
}

}  // namespace bvhlab
