// STL (ASCII and binary), read entirely here (mesh_io_detail.hpp says why OpenMesh is not used).
// Binary when the size is exactly 84 + 50 * count; otherwise ASCII "solid ... endsolid".
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

#include "datasets/mesh_io_detail.hpp"

namespace bvhlab::meshio {
namespace {

// Corners -> indexed triangles; equal positions (exact double comparison, all finite) share a vertex.
struct Welder {
  MeshData mesh;
  std::map<std::tuple<double, double, double>, uint32_t> index;
  uint32_t vertex(glm::dvec3 p) {
    auto [it, added] = index.emplace(std::tuple{p.x, p.y, p.z}, uint32_t(mesh.positions.size()));
    if (added) mesh.positions.push_back(p);
    return it->second;
  }
  void triangle(const glm::dvec3 (&c)[3]) {
    // One statement per corner: the order of evaluation of function arguments is unspecified, and the
    // vertices must be numbered in file order.
    const uint32_t a = vertex(c[0]);
    const uint32_t b = vertex(c[1]);
    const uint32_t d = vertex(c[2]);
    mesh.triangles.emplace_back(a, b, d);
  }
};

uint32_t declaredCount(std::string_view text) {
  uint32_t count = 0;
  std::memcpy(&count, text.data() + 80, 4);  // little-endian on every platform we build for
  return count;
}

}  // namespace

MeshData readStl(std::string_view text) {
  Welder weld;
  if (text.size() >= 84) {
    const uint32_t count = declaredCount(text);
    // Resource limit: the size of a binary STL is exactly 84 + 50 * count bytes, so a header claiming
    // more triangles than the file holds (4e9 in a small file) is refused below, before any allocation.
    if (84 + 50 * uint64_t(count) == text.size()) {
      for (uint32_t i = 0; i < count; ++i) {
        glm::dvec3 corners[3];
        for (int k = 0; k < 9; ++k) {
          float v = 0.0f;
          std::memcpy(&v, text.data() + 84 + 50 * size_t(i) + 12 + 4 * k, 4);
          // NaN would break the ordering of the welding map: reject non-finite coordinates first.
          if (!std::isfinite(v)) fail("triangle " + std::to_string(i) + ": vertex coordinate is NaN or infinite");
          corners[k / 3][k % 3] = v;
        }
        weld.triangle(corners);
      }
      return std::move(weld.mesh);
    }
  }
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || text.substr(first, 5) != "solid") {
    if (text.size() >= 84) {
      const uint32_t count = declaredCount(text);
      fail("binary STL size mismatch: header declares " + std::to_string(count) + " triangles (" +
           std::to_string(84 + 50 * uint64_t(count)) + " bytes) but the file has " + std::to_string(text.size()) +
           " bytes (truncated?)");
    }
    fail("not an STL file (too short for binary, no 'solid' for ASCII)");
  }
  LineScanner sc{text};
  std::string_view line;
  size_t facets = 0, vertices = 0, endfacets = 0;
  bool ended = false;
  glm::dvec3 corners[3];
  std::vector<double> xyz;
  while (sc.next(line)) {
    auto t = tokens(line);
    if (t.empty()) continue;
    if (t[0] == "facet") {
      if (facets != endfacets) failAt(sc.lineNo, "'facet' before the previous facet's 'endfacet'");
      ++facets;
    } else if (t[0] == "vertex") {
      if (facets == endfacets) failAt(sc.lineNo, "'vertex' outside a facet");
      xyz.clear();
      expectReals(t, 1, 3, sc.lineNo, "vertex", &xyz);
      const size_t k = vertices - 3 * (facets - 1);
      if (k >= 3) failAt(sc.lineNo, "facet with more than 3 vertices");
      corners[k] = glm::dvec3(xyz[0], xyz[1], xyz[2]);
      ++vertices;
    } else if (t[0] == "endfacet") {
      if (facets == endfacets) failAt(sc.lineNo, "'endfacet' without 'facet'");
      if (vertices != 3 * facets)
        failAt(sc.lineNo, "facet with " + std::to_string(vertices - 3 * (facets - 1)) + " vertices (need 3)");
      weld.triangle(corners);
      ++endfacets;
    } else if (t[0] == "endsolid") {
      ended = true;
      break;
    }
  }
  if (!ended || facets != endfacets) fail("truncated ASCII STL (no 'endsolid' after the last facet)");
  return std::move(weld.mesh);
}

}  // namespace bvhlab::meshio
