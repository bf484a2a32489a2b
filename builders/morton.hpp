// Morton (Z-order) codes shared by the Morton-order builders (lbvh, ploc): centroids quantised to a
// 2^21 grid over their bounds, interleaved into a 63-bit key (x, y, z from the top down), optionally
// extended with bits of the primitive's size, and the (code, primitive id) pair the builders sort.
//
// The grid (BuildOptions::mortonGrid): Cube (default) gives every axis the same cell size, the
// longest centroid extent over 2^21, so a cell is a cube and a code's top bits split the scene along
// its long axes first, as a top-down builder's first splits would. Axes scales each axis over its own
// extent: on a flat or long scene (a terrain 1000 x 160 x 1000, a building 60 x 9 x 30) that makes
// every cell as flat as the scene, so the codes alternate between cutting the short axis into slivers
// and the long ones, and clusters come out long and thin. Measured (experiments/configs/morton-grid.toml):
// with the cube, lbvh's SAH drops 20-24% on the interior and terrain bench scenes, 11-13% on the ship
// and stadium, and ploc's 6% on both; on the scans (extents within 1.3x of each other) it moves
// within +-1.6%.
//
// Size bits (BuildOptions::mortonSizeBits = s, 0..kMaxMortonSizeBits): Vinkler, Bittner & Havran
// 2017, "Extended Morton Codes for High Performance Bounding Volume Hierarchy Construction" (HPG 2017).
// Their abstract names three extensions: the objects' size encoded in the code, an adaptive order of
// the code bits and variable bit counts per axis; only the first is here (the other two change where
// position bits go; the cube grid above is the nearest thing to the adaptive order). Why size
// helps: a large primitive whose centroid lies among small ones gets sorted among them and inflates
// every cluster it joins; with size bits it sorts next to other large primitives of that region.
// Where the bits go: one size bit after every kPositionBitsPerSizeBit position bits from the top
// (most significant size bit first), so the size splits a region only after two octree levels of
// position each, and the s lowest position bits are dropped to keep 63 bits. We could not read the
// paper's text here (only its abstract); this spacing, 7 bits per size bit with 6 size bits in a
// 64-bit code, is what the public implementations of the paper's codes we looked at use.
// The size: the box diagonal over the scene's (the union of the boxes), square-rooted, in 2^s equal
// classes: class c holds the diagonals in [(c / 2^s)^2, ((c + 1) / 2^s)^2) of the scene's. Relative to
// the scene, as the abstract's "size of the objects" against the position grid: a size bit separates
// primitives only when they differ in size on the scale of the cells at that level. The square root
// (one of the public implementations offers it) gives the small sizes finer classes. Measured
// (docs/builders.md, PLOC section): a log scale between the input's smallest and largest diagonal,
// tried first, made every tree worse (bunny: ploc 1.21x, lbvh 1.57x sah-binned's SAH instead of 1.09x
// and 1.20x): on a mesh whose triangles span a few octaves, it splits every region into overlapping
// subtrees of "larger" and "smaller" triangles; a linear scale changed no tree of the scans at all.
// With s = 0 the codes are exactly the plain 63-bit codes (with the Axes grid, the trees of before
// size bits, bit for bit).
#pragma once
#include <cstdint>
#include <span>

#include "builders/bvh.hpp"

namespace bvhlab::detail {

// Spreads the low 21 bits of v so that bit i lands at bit 3i.
inline uint64_t spreadBits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

struct Keyed {
  uint64_t code;
  uint32_t id;
};

constexpr int kMortonBitsPerAxis = 21;                    // 3 * 21 = 63 bits in a 64-bit code
constexpr int kMortonCodeBits = 3 * kMortonBitsPerAxis;
constexpr int kPositionBitsPerSizeBit = 6;                 // two octree levels of position per size bit
// Every size bit with its position bits above it within the 63 bits (bvh.hpp states the bound).
static_assert(kMaxMortonSizeBits == kMortonCodeBits / (kPositionBitsPerSizeBit + 1));

// The s-bit size class into a 63-bit position code: one size bit after every kPositionBitsPerSizeBit
// position bits from the top; the position code's s lowest bits are dropped. s = 0: `position` itself.
inline uint64_t insertSizeBits(uint64_t position, uint32_t sizeClass, uint32_t s) {
  const uint64_t p = position >> s;
  int left = kMortonCodeBits - int(s);  // position bits of p not placed yet
  uint64_t code = 0;
  for (int k = int(s) - 1; k >= 0; --k) {
    left -= kPositionBitsPerSizeBit;
    code = (code << kPositionBitsPerSizeBit | (p >> left & ((1u << kPositionBitsPerSizeBit) - 1))) << 1 |
           (sizeClass >> k & 1);
  }
  return code << left | (p & ((uint64_t(1) << left) - 1));  // left >= 0: 7s <= 63
}

// The codes of one input. Construction scans the input once (centroid bounds; with size bits, the
// diagonals' range too); code(i) is a pure function of primitive i, so callers may compute the codes
// in any chunks on any threads.
class MortonEncoder {
 public:
  // Throws std::invalid_argument (naming mortonSizeBits and the range) when sizeBits > kMaxMortonSizeBits.
  MortonEncoder(const BuildInput& input, uint32_t sizeBits, MortonGrid grid);

  uint64_t code(uint32_t i) const {
    const float top = float(1 << kMortonBitsPerAxis) - 1.0f;
    const glm::vec3 q = glm::min((centroids_[i] - min_) * scale_, glm::vec3(top));
    const uint64_t position = spreadBits(uint64_t(q.x)) << 2 | spreadBits(uint64_t(q.y)) << 1 | spreadBits(uint64_t(q.z));
    return sizeBits_ == 0 ? position : insertSizeBits(position, sizeClass(boxes_[i]), sizeBits_);
  }

  // 0..2^sizeBits - 1; 0 without size bits.
  uint32_t sizeClass(const Aabb& box) const;

 private:
  std::span<const glm::vec3> centroids_;
  std::span<const Aabb> boxes_;
  glm::vec3 min_{0.0f}, scale_{0.0f};
  uint32_t sizeBits_ = 0;
  double sceneDiagonal_ = 0.0;  // of the union of the boxes (only with size bits)
};

}  // namespace bvhlab::detail
