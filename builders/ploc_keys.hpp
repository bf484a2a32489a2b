// How PLOC's clustering ranks a cluster's candidates, shared by ploc (builders/ploc.cpp) and hploc
// (builders/hploc.cpp), and word for word by the GPU passes (builders/gpu/gpubuild_ploc_pairs.glsl).
//   tieKey        orders the candidates of cluster x that tie on merged area by a key of the pair
//                 {x, j} alone (distance, parity of the lower position, the side), so both ends of a
//                 pair rank it alike; below 2^32 for any distance below 2^29
//   candidateKey  candidate j of cluster x with merged area `area`, as one number: areas are >= 0
//                 (and not NaN), so their bit patterns order as they do; the nearest neighbour is the
//                 candidate with the smallest key
//   mergedArea    the half area of the union of two boxes as Aabb::halfArea computes it, without the
//                 union: (ex ey + ey ez) + ez ex, each extent max - min
// With these keys the smallest pair in a window is always mutual (at least one merge per pass), and
// equal boxes pair up (2k, 2k + 1) instead of chaining.
#pragma once
#include <algorithm>
#include <bit>
#include <cstdint>

#include "builders/bvh.hpp"

namespace bvhlab::detail::ploc {

inline uint32_t tieKey(uint32_t x, uint32_t j) {
  const uint32_t d = x > j ? x - j : j - x, lower = std::min(x, j);
  return 4 * d + 2 * (lower & 1) + (j > x ? 1 : 0);
}

// "+ 0.0f" turns -0 into +0 (and changes nothing else): a coordinate of -0 next to one of +0 can make
// an extent, and so an area, -0 or +0 depending on the operand order of min/max, and -0's bit pattern
// would rank it above every positive area.
inline uint64_t candidateKey(float area, uint32_t x, uint32_t j) {
  return uint64_t(std::bit_cast<uint32_t>(area + 0.0f)) << 32 | tieKey(x, j);
}

// Inputs are finite and validated to a finite scene area (validateBuildInput), so it is finite.
inline float mergedArea(const Aabb& a, const Aabb& b) {
  const float ex = std::max(a.max.x, b.max.x) - std::min(a.min.x, b.min.x);
  const float ey = std::max(a.max.y, b.max.y) - std::min(a.min.y, b.min.y);
  const float ez = std::max(a.max.z, b.max.z) - std::min(a.min.z, b.min.z);
  return (ex * ey + ey * ez) + ez * ex;
}

}  // namespace bvhlab::detail::ploc
