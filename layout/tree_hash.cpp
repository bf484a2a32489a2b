// packedTreeHash (layout/tree_hash.hpp). Written here rather than shared with experiments/config.cpp's
// hashHex: layout is upstream of experiments and cannot depend on it.
#include "layout/tree_hash.hpp"

#include <cstdint>
#include <cstdio>

namespace bvhlab {

namespace {

struct Fnv1a64 {
  uint64_t h = 0xcbf29ce484222325ull;

  void byte(uint8_t b) {
    h ^= b;
    h *= 0x100000001b3ull;
  }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) byte(uint8_t(v >> (8 * i)));
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) byte(uint8_t(v >> (8 * i)));
  }
  void stream(const std::vector<glm::uvec4>& texels) {
    u64(texels.size());
    for (const glm::uvec4& t : texels) {
      u32(t.x);
      u32(t.y);
      u32(t.z);
      u32(t.w);
    }
  }
};

}  // namespace

std::string packedTreeHash(const PackedBvh& packed) {
  Fnv1a64 f;
  f.stream(packed.nodes);
  f.stream(packed.triangles);
  f.stream(packed.attributes);
  if (!packed.vertices.empty()) f.stream(packed.vertices);  // indexed triangles; absent: the hash stays as before
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(f.h));
  return hex;
}

}  // namespace bvhlab
