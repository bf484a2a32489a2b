// The triangle-format registry and packTriangles (layout/triangle_formats.hpp describes the formats):
// raw is what the node packers write; precomputed is written here; indexed in
// layout/pack_triangles_indexed.cpp.
#include <bit>
#include <stdexcept>

#include "layout/triangle_formats.hpp"

namespace bvhlab {

namespace {

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("packTriangles: " + what); }

// The soup triangle of each TRIANGLE-stream position, read back from the raw stream's id lane.
std::vector<uint32_t> streamOrder(const PackedBvh& packed, const TriangleSoup& soup) {
  if (packed.triangleFormat != "raw") fail("the streams are already in format '" + packed.triangleFormat + "'");
  if (packed.triangles.size() % kTriangleTexels != 0 ||
      packed.attributes.size() != packed.triangles.size() / kTriangleTexels * kAttributeTexels)
    fail("the raw TRIANGLE/ATTRIBUTE streams do not hold whole triangles");
  std::vector<uint32_t> order(packed.triangles.size() / kTriangleTexels);
  for (size_t j = 0; j < order.size(); ++j) {
    order[j] = packed.triangles[kTriangleTexels * j].w;
    if (order[j] >= soup.size())
      fail("stream triangle " + std::to_string(j) + " names soup triangle " + std::to_string(order[j]) + " of " +
           std::to_string(soup.size()));
  }
  return order;
}

void packPrecomputed(PackedBvh& packed, const TriangleSoup& soup, const std::vector<uint32_t>& order) {
  std::vector<glm::uvec4> out;
  out.reserve(kPrecomputedTriangleTexels * order.size());
  for (uint32_t p : order) {
    // The same float subtractions and cross product Moller-Trumbore does per test (GLSL rounds them
    // the same way), so both tests see the same edges and normal.
    const glm::vec3 v0 = soup.v0[p], e1 = soup.v1[p] - v0, e2 = soup.v2[p] - v0;
    const glm::vec3 n = glm::cross(e1, e2);
    out.push_back({bits(v0.x), bits(v0.y), bits(v0.z), p});
    out.push_back({bits(e1.x), bits(e1.y), bits(e1.z), soup.material[p]});
    out.push_back({bits(e2.x), bits(e2.y), bits(e2.z), soup.mesh[p]});
    out.push_back({bits(n.x), bits(n.y), bits(n.z), 0u});
  }
  packed.triangles = std::move(out);  // ATTRIBUTE stays raw
}

}  // namespace

const std::vector<TriangleFormatInfo>& triangleFormats() {
  static const std::vector<TriangleFormatInfo> table = {
      {TriangleFormat::Raw, "raw", "3 vertices + ids (48 B) and per-corner normals/uvs (64 B): 112 B a triangle",
       "triangles_raw.glsl", true},
      {TriangleFormat::Precomputed, "precomputed",
       "v0, edges, geometric normal + ids (64 B), attributes as raw: 128 B; Moller-Trumbore only",
       "triangles_precomputed.glsl", false},
      {TriangleFormat::Indexed, "indexed",
       "3 vertex indices + id (16 B); welded vertices: position, oct normal (16 B), half uv + ids (8 B)",
       "triangles_indexed.glsl", true},
  };
  return table;
}

const TriangleFormatInfo& findTriangleFormat(const std::string& name) {
  for (const TriangleFormatInfo& f : triangleFormats())
    if (f.name == name) return f;
  std::string msg = "unknown triangle format '" + name + "'; valid formats:";
  for (const TriangleFormatInfo& f : triangleFormats()) msg += " " + f.name;
  throw std::invalid_argument(msg);
}

void checkTriangleFormat(const std::string& format, Robustness robust) {
  const TriangleFormatInfo& f = findTriangleFormat(format);
  if (robust.triangle == TriangleTest::Watertight && !f.watertight)
    // (The variant's name is not spelled from robustnessName: traversal/ links after layout/.)
    throw std::invalid_argument("triangle format '" + f.name + "' does not keep the input vertices, which the " +
                                "watertight triangle test needs (--robust tri, tri+box, tri+ulp, watertight); use it " +
                                "with --robust fast, box, ulp or box+ulp, or use --triangles raw or indexed");
}

void packTriangles(PackedBvh& packed, const TriangleSoup& soup, const std::string& format) {
  const TriangleFormatInfo& f = findTriangleFormat(format);
  if (f.format == TriangleFormat::Raw) {
    packed.triangleFormat = f.name;
    return;
  }
  const std::vector<uint32_t> order = streamOrder(packed, soup);
  if (f.format == TriangleFormat::Precomputed) packPrecomputed(packed, soup, order);
  else packIndexedTriangles(packed, soup, order);
  packed.triangleFormat = f.name;
}

}  // namespace bvhlab
