// A scene made ready to render: its triangles built into a BVH by the chosen builder and packed
// into the one texture layout, and its objects/materials/textures packed for the tracer.
#pragma once
#include <memory>
#include <string>

#include "builders/builder.hpp"
#include "datasets/scene.hpp"
#include "layout/layout.hpp"
#include "shaders/scene_data.hpp"

namespace bvhlab {

struct PreparedScene {
  Scene scene;
  SceneData data;
  TriangleSoup soup;
  Bvh bvh;
  PackedBvh packed;
  BuildStats stats;  // empty (primitives == 0) when the scene has no triangles
};

// `scene` is moved in; SceneData points into it, so PreparedScene is not copyable.
std::unique_ptr<PreparedScene> prepareScene(Scene scene, const std::string& builder, const BuildOptions& options);

}  // namespace bvhlab
