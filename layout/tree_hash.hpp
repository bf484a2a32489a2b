// A fingerprint of a packed tree: two runs whose packed streams hash the same traversed the very
// same bytes, whatever builder or options produced them (the experiment findings call such a pair
// "same tree" rather than measuring noise between them).
#pragma once
#include <string>

#include "layout/layout.hpp"

namespace bvhlab {

// FNV-1a 64 (Fowler/Noll/Vo: offset basis 0xcbf29ce484222325, prime 0x100000001b3) as 16 lower-case
// hex digits, over the NODE, TRIANGLE and ATTRIBUTE streams in that order. Each stream contributes
// its texel count (8 bytes, little-endian) and then every texel's x, y, z, w (4 bytes each,
// little-endian): the byte order is fixed so the hash is the same on every machine, and the counts
// keep texels from moving between streams unnoticed. PackedBvh::depth is not hashed: it follows from
// the node stream.
std::string packedTreeHash(const PackedBvh& packed);

}  // namespace bvhlab
