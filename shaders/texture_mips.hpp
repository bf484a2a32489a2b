// Mipmap chains for ray-cone texture filtering (--texture-lod cones | cones-aniso): built once on the
// host and used by BOTH the GPU renderer (uploaded level by level) and the C++ mirror, so the two
// filter the same texels. GL's own glGenerateMipmap leaves the filter to the driver.
#pragma once
#include <vector>

#include <glm/glm.hpp>

#include "shaders/scene_data.hpp"

namespace bvhlab {

struct MipLevel {
  int width = 1, height = 1;
  std::vector<glm::vec4> texels;  // layer-major (a texture array's layers), rows bottom-up
};

// Level 0 is the input; level k+1 halves level k (each side floor(n/2), at least 1) down to 1x1.
// Each texel is the mean of the 2x2 texels it covers; on an odd side the last texel also takes the
// row or column left over, so every texel of a level contributes to the next one.
std::vector<MipLevel> buildMipChain(const std::vector<glm::vec4>& texels, int width, int height, int layers = 1);

// The chains of a scene's material texture array (a scene without textures: the renderer's 1x1 white
// layer) and of its world map (empty without one).
struct TextureMips {
  std::vector<MipLevel> textures;  // all layers per level
  std::vector<MipLevel> world;
};
TextureMips buildTextureMips(const SceneData& data);

}  // namespace bvhlab
