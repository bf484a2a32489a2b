// The indexed triangle format (layout/triangle_formats.hpp): corners welded per mesh by exact
// equality, one VERTEX texel per vertex (position, oct normal), half-float uvs and ids in ATTRIBUTE,
// one TRIANGLE texel (three vertex indices, the input triangle id) per triangle.
#include <array>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include <glm/gtc/packing.hpp>

#include "layout/triangle_formats.hpp"

namespace bvhlab {

namespace {

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("packTriangles (indexed): " + what); }

float signNotZero(float x) { return x >= 0.0f ? 1.0f : -1.0f; }

// What makes two corners one vertex: mesh, material, position, normal (or kFlatNormal), uv, as bits.
using CornerKey = std::array<uint32_t, 10>;

struct CornerKeyHash {
  size_t operator()(const CornerKey& k) const {
    uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a over the words
    for (uint32_t w : k) h = (h ^ w) * 0x100000001b3ull;
    return size_t(h ^ (h >> 29));
  }
};

}  // namespace

// Cigolle et al. 2014, section 3.3: project onto the octahedron |x| + |y| + |z| = 1, fold the lower
// half over the upper one, round each coordinate to the nearest snorm16 step.
uint32_t encodeOctNormal(glm::vec3 n) {
  const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 0.0f) || !std::isfinite(l1)) throw std::invalid_argument("encodeOctNormal: not a direction");
  glm::vec2 p = glm::vec2(n.x, n.y) / l1;
  if (n.z < 0.0f) p = glm::vec2((1.0f - std::abs(p.y)) * signNotZero(p.x), (1.0f - std::abs(p.x)) * signNotZero(p.y));
  return glm::packSnorm2x16(p);
}

// The GLSL decoder's statements (traversal/triangles_indexed.glsl, decodeOctNormal), with GLSL's
// unpackSnorm2x16 as specified: clamp(f / 32767, -1, 1) (glm's multiplies by 1 / 32767, which rounds
// differently).
glm::vec3 decodeOctNormal(uint32_t code) {
  const glm::vec2 q(float(int16_t(uint16_t(code & 0xFFFFu))), float(int16_t(uint16_t(code >> 16))));
  const glm::vec2 e = glm::clamp(q / 32767.0f, -1.0f, 1.0f);
  glm::vec3 v(e.x, e.y, 1.0f - std::abs(e.x) - std::abs(e.y));
  if (v.z < 0.0f) {
    const glm::vec2 folded((1.0f - std::abs(v.y)) * signNotZero(v.x), (1.0f - std::abs(v.x)) * signNotZero(v.y));
    v.x = folded.x;
    v.y = folded.y;
  }
  return glm::normalize(v);
}

void packIndexedTriangles(PackedBvh& packed, const TriangleSoup& soup, const std::vector<uint32_t>& order) {
  std::unordered_map<CornerKey, uint32_t, CornerKeyHash> vertexOf;
  vertexOf.reserve(order.size());  // a closed mesh has about half as many vertices as triangles
  std::vector<glm::uvec4> triangles, vertices;
  std::vector<uint32_t> attributeWords;  // 2 per vertex, packed 4 to a texel at the end
  triangles.reserve(order.size());
  for (size_t j = 0; j < order.size(); ++j) {
    const uint32_t p = order[j];
    if (soup.mesh[p] > kMaxIndexedIds || soup.material[p] > kMaxIndexedIds)
      fail("triangle " + std::to_string(p) + " has mesh " + std::to_string(soup.mesh[p]) + " and material " +
           std::to_string(soup.material[p]) + "; a vertex names at most " + std::to_string(kMaxIndexedIds + 1) +
           " meshes and materials (use --triangles raw)");
    const glm::vec3 v[3] = {soup.v0[p], soup.v1[p], soup.v2[p]};
    const glm::vec3 n[3] = {soup.n0[p], soup.n1[p], soup.n2[p]};
    const glm::vec2 uv[3] = {soup.uv0[p], soup.uv1[p], soup.uv2[p]};
    const glm::vec3 flat = geometricNormal(v[0], v[1], v[2]);
    uint32_t index[3];
    for (int k = 0; k < 3; ++k) {
      const bool isFlat = bits(n[k].x) == bits(flat.x) && bits(n[k].y) == bits(flat.y) && bits(n[k].z) == bits(flat.z);
      const CornerKey key = {soup.mesh[p],   soup.material[p],
                             bits(v[k].x),   bits(v[k].y),
                             bits(v[k].z),   isFlat ? kFlatNormal : bits(n[k].x),
                             isFlat ? 0u : bits(n[k].y), isFlat ? 0u : bits(n[k].z),
                             bits(uv[k].x),  bits(uv[k].y)};
      const auto [it, added] = vertexOf.try_emplace(key, uint32_t(vertices.size()));
      if (added) {
        if (vertices.size() >= kIndexMask)
          fail(std::to_string(vertices.size() + 1) + " vertices exceed the format's limit of " +
               std::to_string(kIndexMask));
        vertices.push_back({bits(v[k].x), bits(v[k].y), bits(v[k].z), isFlat ? kFlatNormal : encodeOctNormal(n[k])});
        attributeWords.push_back(glm::packHalf2x16(uv[k]));
        attributeWords.push_back(soup.material[p] | (soup.mesh[p] << 16));
      }
      index[k] = it->second;
    }
    triangles.push_back({index[0], index[1], index[2], p});
  }
  std::vector<glm::uvec4> attributes((attributeWords.size() + 3) / 4, glm::uvec4(0u));
  for (size_t w = 0; w < attributeWords.size(); ++w) attributes[w / 4][int(w % 4)] = attributeWords[w];
  packed.triangles = std::move(triangles);
  packed.vertices = std::move(vertices);
  packed.attributes = std::move(attributes);
}

}  // namespace bvhlab
