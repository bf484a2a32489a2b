// A scene made ready to render: its triangles built into a BVH by the chosen builder and packed
// into the chosen texture layout (layout/layouts.hpp), and its objects/materials/textures packed for
// the tracer.
#pragma once
#include <array>
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
  CostModel cost;    // the model the tree was built (and its SAH computed) with
  // The streams already on the GPU, where the tree was built and packed there (render/gpu_clip_build.hpp):
  // node, triangle and attribute storage buffers holding `packed`'s streams, which a GpuRenderer binds
  // instead of uploading `packed`'s (whose copies then serve for sizes, statistics and checks). Owned
  // elsewhere and alive while a renderer uses them; 0: none.
  std::array<unsigned, 3> gpuStreams{};

  // Clock-free identity and quality of the tree, computed on first use (EPO costs a pass over the
  // tree; `render` without --json never needs it). Both are 0 / "" without triangles.
  std::string treeHash() const;        // layout/tree_hash.hpp: equal streams -> equal hash
  double endPointOverlap() const;      // builders/epo.hpp, with `cost`

 private:
  mutable std::string treeHash_;
  mutable double epo_ = -1.0;  // < 0: not computed yet
};

// `scene` is moved in; SceneData points into it, so PreparedScene is not copyable. `layout`: a
// registered layout name (packed.layout is set to it, with or without triangles); stats.bytes is the
// packed streams' size in it.
// `triangles`: a triangle format (layout/triangle_formats.hpp), applied after the layout's packer.
std::unique_ptr<PreparedScene> prepareScene(Scene scene, const std::string& builder, const BuildOptions& options,
                                            const std::string& layout = "v1", const std::string& triangles = "raw");

}  // namespace bvhlab
