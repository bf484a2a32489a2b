#include "shaders/texture_mips.hpp"

#include <algorithm>
#include <stdexcept>

namespace bvhlab {

namespace {

// Source indices [first, last] that output texel i of a side of n -> max(1, n / 2) covers.
void span(int i, int n, int& first, int& last) {
  const int out = std::max(1, n / 2);
  first = std::min(2 * i, n - 1);
  last = i == out - 1 ? n - 1 : std::min(2 * i + 1, n - 1);
}

}  // namespace

std::vector<MipLevel> buildMipChain(const std::vector<glm::vec4>& texels, int width, int height, int layers) {
  if (width < 1 || height < 1 || layers < 1 || texels.size() != size_t(width) * size_t(height) * size_t(layers))
    throw std::invalid_argument("buildMipChain: " + std::to_string(texels.size()) + " texels for " +
                                std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(layers));
  std::vector<MipLevel> chain;
  chain.push_back(MipLevel{width, height, texels});
  while (chain.back().width > 1 || chain.back().height > 1) {
    const MipLevel& src = chain.back();
    MipLevel dst{std::max(1, src.width / 2), std::max(1, src.height / 2), {}};
    dst.texels.resize(size_t(dst.width) * dst.height * layers);
    for (int l = 0; l < layers; ++l) {
      const glm::vec4* s = src.texels.data() + size_t(l) * src.width * src.height;
      glm::vec4* d = dst.texels.data() + size_t(l) * dst.width * dst.height;
      for (int j = 0; j < dst.height; ++j)
        for (int i = 0; i < dst.width; ++i) {
          int x0, x1, y0, y1;
          span(i, src.width, x0, x1);
          span(j, src.height, y0, y1);
          glm::vec4 sum(0.0f);
          for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) sum += s[size_t(y) * src.width + x];
          d[size_t(j) * dst.width + i] = sum / float((x1 - x0 + 1) * (y1 - y0 + 1));
        }
    }
    chain.push_back(std::move(dst));
  }
  return chain;
}

TextureMips buildTextureMips(const SceneData& data) {
  TextureMips mips;
  const TextureArray& ta = data.textures;
  std::vector<glm::vec4> texels = ta.texels;
  if (texels.empty()) texels.assign(size_t(ta.width) * ta.height, glm::vec4(1.0f));
  mips.textures = buildMipChain(texels, ta.width, ta.height, std::max(1, ta.layers));
  if (data.worldMap) mips.world = buildMipChain(data.worldMap->texels, data.worldMap->width, data.worldMap->height);
  return mips;
}

}  // namespace bvhlab
