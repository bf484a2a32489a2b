// Morton (Z-order) codes shared by the Morton-order builders (lbvh, ploc): 21 bits per axis,
// interleaved into a 63-bit key, and the (code, primitive id) pair they sort.
#pragma once
#include <cstdint>

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

}  // namespace bvhlab::detail
