#include "shaders/scene_data.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include <glm/gtc/matrix_inverse.hpp>

namespace bvhlab {

namespace {

// Bilinear resample with repeat wrap (texel centres at (i + 0.5) / size), the same filter the GPU
// applies when the array is sampled, so resampling adds no second kind of error.
glm::vec4 sampleRepeat(const Image& img, float u, float v) {
  float x = u * img.width - 0.5f, y = v * img.height - 0.5f;
  float fx = std::floor(x), fy = std::floor(y);
  float ax = x - fx, ay = y - fy;
  auto at = [&](int i, int j) {
    i = ((i % img.width) + img.width) % img.width;
    j = ((j % img.height) + img.height) % img.height;
    return img.texels[size_t(j) * img.width + i];
  };
  int i0 = int(fx), j0 = int(fy);
  return glm::mix(glm::mix(at(i0, j0), at(i0 + 1, j0), ax), glm::mix(at(i0, j0 + 1), at(i0 + 1, j0 + 1), ax), ay);
}

}  // namespace

SceneData buildSceneData(const Scene& scene) {
  SceneData d;
  // Textures: common size = the largest used, capped (GPU arrays need one size; 2048 keeps memory sane).
  std::map<int, int> imageToLayer;
  for (const Material& m : scene.materials)
    if (m.texture >= 0 && !imageToLayer.count(m.texture)) {
      int layer = static_cast<int>(imageToLayer.size());
      imageToLayer[m.texture] = layer;
    }
  for (auto [image, layer] : imageToLayer) {
    const Image& img = scene.images.at(image);
    d.textures.width = std::max(d.textures.width, std::min(img.width, 2048));
    d.textures.height = std::max(d.textures.height, std::min(img.height, 2048));
  }
  d.textures.layers = static_cast<int>(imageToLayer.size());
  d.textures.texels.resize(size_t(d.textures.width) * d.textures.height * d.textures.layers);
  for (auto [image, layer] : imageToLayer) {
    const Image& img = scene.images.at(image);
    glm::vec4* dst = d.textures.texels.data() + size_t(layer) * d.textures.width * d.textures.height;
    for (int j = 0; j < d.textures.height; ++j)
      for (int i = 0; i < d.textures.width; ++i) {
        if (img.width == d.textures.width && img.height == d.textures.height)
          dst[size_t(j) * d.textures.width + i] = img.texels[size_t(j) * img.width + i];
        else
          dst[size_t(j) * d.textures.width + i] =
              sampleRepeat(img, (i + 0.5f) / d.textures.width, (j + 0.5f) / d.textures.height);
      }
  }

  auto toData = [&](const Material& m) {
    MaterialData md;
    float layer = m.texture >= 0 ? float(imageToLayer.at(m.texture)) : -1.0f;
    md.color = glm::vec4(m.color, layer);
    md.lighting = glm::vec4(m.diffuse, m.ambient, m.specular, m.shininess);
    md.optics = glm::vec4(m.reflectivity, m.transparency, m.ior, 0.0f);
    md.emission = glm::vec4(m.emission, 0.0f);
    md.uvScale = glm::vec4(m.uvScale, 0.0f, 0.0f);
    return md;
  };
  for (const Material& m : scene.materials) d.materials.push_back(toData(m));
  if (d.materials.empty()) d.materials.push_back(toData(Material{}));  // objects default to material 0
  for (const Light& l : scene.lights) {
    LightData ld;
    ld.position = l.kind == LightKind::Point ? glm::vec4(l.position, 0.0f)
                                             : glm::vec4(glm::normalize(l.direction), 1.0f);
    ld.radiance = glm::vec4(l.color * l.intensity, 0.0f);
    d.lights.push_back(ld);
  }
  d.ambient = glm::vec4(scene.world.ambient, 0.0f);

  Aabb bounds;
  for (const Object& o : scene.objects) {
    if (o.kind == ObjectKind::Mesh) continue;
    glm::mat4 inv = glm::inverse(o.transform);
    glm::mat4 rows = glm::transpose(inv);  // column i of `rows` = row i of inv
    ObjectData od;
    od.worldToObject0 = rows[0];
    od.worldToObject1 = rows[1];
    od.worldToObject2 = rows[2];
    od.params = glm::vec4(o.majorRadius, o.minorRadius, o.infinite ? 1.0f : 0.0f, 0.0f);
    od.info = glm::ivec4(static_cast<int>(o.kind), o.material, 0, 0);
    d.objects.push_back(od);
    if (!(o.kind == ObjectKind::Plane && o.infinite)) {
      float extent = o.kind == ObjectKind::Torus ? o.majorRadius + o.minorRadius : 1.0f;
      for (int c = 0; c < 8; ++c) {
        glm::vec3 corner((c & 1) ? extent : -extent, (c & 2) ? extent : -extent, (c & 4) ? extent : -extent);
        bounds.grow(glm::vec3(o.transform * glm::vec4(corner, 1.0f)));
      }
    }
  }
  for (const Mesh& m : scene.meshes)
    for (const glm::vec3& p : m.positions) bounds.grow(p);
  d.sceneRadius = bounds.empty() ? 1.0f : std::max(1e-6f, 0.5f * glm::length(bounds.extent()));
  if (scene.world.kind == WorldKind::Map && scene.world.image >= 0) d.worldMap = &scene.images.at(scene.world.image);
  return d;
}

std::vector<uint8_t> SceneData::uniformBlock() const {
  // Arrays are sized max(1, n) in the shader; empty ones still occupy one (zeroed) element.
  auto bytesOf = [](const auto& v, size_t elem) { return std::max<size_t>(1, v.size()) * elem; };
  std::vector<uint8_t> out(bytesOf(objects, sizeof(ObjectData)) + bytesOf(materials, sizeof(MaterialData)) +
                               bytesOf(lights, sizeof(LightData)) + sizeof(glm::vec4),
                           0);
  size_t at = 0;
  auto put = [&](const auto& v, size_t elem) {
    if (!v.empty()) std::memcpy(out.data() + at, v.data(), v.size() * elem);
    at += std::max<size_t>(1, v.size()) * elem;
  };
  put(objects, sizeof(ObjectData));
  put(materials, sizeof(MaterialData));
  put(lights, sizeof(LightData));
  std::memcpy(out.data() + at, &ambient, sizeof(glm::vec4));
  return out;
}

CameraBasis cameraBasis(const Camera& c, int width, int height) {
  CameraBasis b;
  b.eye = c.eye;
  b.forward = glm::normalize(c.target - c.eye);
  glm::vec3 right = glm::normalize(glm::cross(b.forward, c.up));
  glm::vec3 up = glm::cross(right, b.forward);
  float tanHalf = std::tan(glm::radians(c.fovDeg) * 0.5f);
  float aspect = float(width) / float(height);
  b.right = right * tanHalf * aspect;
  b.up = up * tanHalf;
  return b;
}

}  // namespace bvhlab
