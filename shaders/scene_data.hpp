// Scene -> the data the tracer reads (std140 UBO records, texture array, world map), built once and
// used by BOTH the GPU renderer and the CPU mirror, so they see identical numbers.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"
#include "datasets/scene.hpp"

namespace bvhlab {

// std140 mirrors of scene.glsl's ObjectData / MaterialData / LightData (all members vec4-sized).
struct ObjectData {
  glm::vec4 worldToObject0, worldToObject1, worldToObject2;
  glm::vec4 params;
  glm::ivec4 info;
};
struct MaterialData {
  glm::vec4 color, lighting, optics, emission, uvScale;
};
struct LightData {
  glm::vec4 position, radiance;
};
static_assert(sizeof(ObjectData) == 80 && sizeof(MaterialData) == 80 && sizeof(LightData) == 32);

// Texture array: every material texture resampled to one size (layers in image order of use).
struct TextureArray {
  int width = 1, height = 1, layers = 0;
  std::vector<glm::vec4> texels;  // layer-major, rows bottom-up
};

struct SceneData {
  std::vector<ObjectData> objects;  // analytic objects only (meshes live in the BVH)
  std::vector<MaterialData> materials;
  std::vector<LightData> lights;
  glm::vec4 ambient{0.0f};
  TextureArray textures;
  const Image* worldMap = nullptr;  // points into the Scene
  float sceneRadius = 1.0f;         // bounding-sphere radius of everything, for the depth view
  std::vector<uint8_t> uniformBlock() const;  // SceneBlock bytes, std140
};

SceneData buildSceneData(const Scene& scene);

// What a frame looks at: image size, camera, exposure.
struct FrameOptions {
  int width = 640, height = 360;
  Camera camera;
  float exposure = 1.0f;
};

// Camera basis as main.glsl wants it.
struct CameraBasis {
  glm::vec3 eye, forward, right, up;  // right/up scaled by tan(fov/2) (and aspect for right)
};
CameraBasis cameraBasis(const Camera& camera, int width, int height);

}  // namespace bvhlab
