#include "render/heatmap.hpp"

#include <algorithm>
#include <cmath>

namespace bvhlab {

namespace {
// Five stops of matplotlib's viridis (its published colour values at 0, .25, .5, .75, 1).
const glm::vec3 kViridis[5] = {{0.267f, 0.005f, 0.329f}, {0.229f, 0.322f, 0.546f}, {0.128f, 0.567f, 0.551f},
                               {0.369f, 0.789f, 0.383f}, {0.993f, 0.906f, 0.144f}};
glm::vec3 viridis(float x) {
  x = std::clamp(x, 0.0f, 1.0f) * 4.0f;
  int i = std::min(3, int(x));
  return glm::mix(kViridis[i], kViridis[i + 1], x - float(i));
}
}  // namespace

std::vector<uint8_t> visitsHeatmap(const std::vector<glm::uvec4>& stats, int width, int height) {
  std::vector<uint32_t> v;
  v.reserve(stats.size());
  for (const glm::uvec4& s : stats) v.push_back(s.x);
  std::vector<uint32_t> sorted = v;
  std::sort(sorted.begin(), sorted.end());
  float scale = sorted.empty() ? 1.0f : float(std::max<uint32_t>(1, sorted[size_t(0.99 * (sorted.size() - 1))]));
  std::vector<uint8_t> out(size_t(width) * height * 4);
  for (size_t i = 0; i < v.size() && i < size_t(width) * height; ++i) {
    glm::vec3 c = v[i] == 0 ? glm::vec3(0.0f) : viridis(float(v[i]) / scale);
    out[4 * i + 0] = uint8_t(std::lround(c.r * 255.0f));
    out[4 * i + 1] = uint8_t(std::lround(c.g * 255.0f));
    out[4 * i + 2] = uint8_t(std::lround(c.b * 255.0f));
    out[4 * i + 3] = 255;
  }
  return out;
}

}  // namespace bvhlab
