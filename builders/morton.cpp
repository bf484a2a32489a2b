// The Morton code setup of builders/morton.hpp: the grid over the centroids and the size scale.
#include "builders/morton.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace bvhlab::detail {

namespace {

// The diagonal of a box, in double: the float extents are finite (validated input), and their squares'
// sum cannot overflow a double (3 FLT_MAX^2 < DBL_MAX), so it is finite and >= 0, never NaN. IEEE sqrt
// is correctly rounded: the same value on every machine.
double diagonal(const Aabb& box) {
  const glm::dvec3 e = glm::dvec3(box.max) - glm::dvec3(box.min);
  return std::sqrt(e.x * e.x + e.y * e.y + e.z * e.z);
}

}  // namespace

MortonEncoder::MortonEncoder(const BuildInput& input, uint32_t sizeBits, MortonGrid grid)
    : centroids_(input.centroids), boxes_(input.boxes), sizeBits_(sizeBits) {
  if (sizeBits > kMaxMortonSizeBits)
    throw std::invalid_argument("Morton codes: mortonSizeBits " + std::to_string(sizeBits) + " is outside 0.." +
                                std::to_string(kMaxMortonSizeBits));
  Aabb centroidBounds;
  for (const glm::vec3& c : input.centroids) centroidBounds.grow(c);
  min_ = centroidBounds.min;
  // Grid scale per axis: 2^21 cells over the longest extent (Cube) or over the axis's own (Axes). A
  // zero (or denormal, 2^21 / extent overflowing) extent maps to cell 0. Inputs are finite and
  // c >= min, so every product in code() is finite and >= 0; with Cube a shorter axis only reaches
  // cells below 2^21 * its extent / the longest (code() clamps the top cell either way).
  const float cells = float(1 << kMortonBitsPerAxis);
  const glm::vec3 extents = centroidBounds.max - centroidBounds.min;
  const float longest = std::max({extents.x, extents.y, extents.z});
  for (int a = 0; a < 3; ++a) {
    const float extent = grid == MortonGrid::Cube ? longest : extents[a];
    const float s = cells / extent;
    if (extents[a] > 0.0f && std::isfinite(s)) scale_[a] = s;
  }
  if (sizeBits == 0) return;
  Aabb scene;
  for (const Aabb& box : input.boxes) scene.grow(box);
  sceneDiagonal_ = diagonal(scene);
}

uint32_t MortonEncoder::sizeClass(const Aabb& box) const {
  if (sizeBits_ == 0 || !(sceneDiagonal_ > 0.0)) return 0;  // a scene of one point: one class
  // In [0, 1] (a box inside the scene has no longer diagonal; rounding, or a box from another input,
  // may pass 1: clamped to the top class).
  const double f = std::sqrt(diagonal(box) / sceneDiagonal_);
  const uint32_t classes = 1u << sizeBits_;
  return uint32_t(std::min(f * double(classes), double(classes - 1)));
}

}  // namespace bvhlab::detail
