// Per-pixel node-visit counts -> a colour image (viridis, normalised by the frame's 99th percentile
// so one hot pixel does not wash the rest out).
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab {
std::vector<uint8_t> visitsHeatmap(const std::vector<glm::uvec4>& stats, int width, int height);
}
