// hard_cases.cpp — generators of the hard-case suite (hard_cases.hpp). Every coordinate used to aim a
// ray at an edge or vertex is exactly representable (binary fractions), so "through the vertex" holds
// in the float data, not just in intent.
#include "datasets/hard_cases.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>
#include <utility>

namespace bvhlab::hard {
namespace {

using glm::uvec3;
using glm::vec3;

// Rays from `origin` through every vertex and every edge midpoint of the case's triangles.
void aimAtVerticesAndEdges(HardCase& c, vec3 origin, bool mustHit) {
  for (const vec3& p : c.positions) c.rays.push_back({origin, p - origin, 0.0f, HardRay{}.tMax, mustHit});
  std::map<std::pair<unsigned, unsigned>, bool> seen;
  for (const uvec3& t : c.triangles)
    for (int e = 0; e < 3; ++e) {
      unsigned a = t[e], b = t[(e + 1) % 3];
      if (!seen.emplace(std::minmax(a, b), true).second) continue;
      vec3 mid = 0.5f * (c.positions[a] + c.positions[b]);
      c.rays.push_back({origin, mid - origin, 0.0f, HardRay{}.tMax, mustHit});
    }
}

// Origins inside the closed unit-sized cases: the centre and an off-centre binary-fraction point.
void aimFromInside(HardCase& c) {
  aimAtVerticesAndEdges(c, vec3(0.0f), true);
  aimAtVerticesAndEdges(c, vec3(0.125f, -0.25f, 0.375f), true);
}

}  // namespace

HardCase closedCube(int n) {
  HardCase c;
  c.name = "cube-inside";
  c.description = "closed cube [-1,1]^3, " + std::to_string(n) + "x" + std::to_string(n) +
                  " quads per face sharing vertices; rays from two inside points through every vertex and edge "
                  "midpoint: every ray must hit";
  c.closed = true;
  std::map<std::tuple<int, int, int>, unsigned> index;  // lattice coordinates -> vertex
  auto vertex = [&](int i, int j, int k) {
    auto [it, added] = index.emplace(std::make_tuple(i, j, k), unsigned(c.positions.size()));
    if (added) c.positions.push_back(vec3(i, j, k) * (2.0f / float(n)) - vec3(1.0f));
    return it->second;
  };
  // Each face: axis `a` fixed at lattice 0 or n, the other two axes (u, v) in the grid.
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            int l[3];
            l[a] = side * n;
            l[(a + 1) % 3] = i + di;
            l[(a + 2) % 3] = j + dj;
            return vertex(l[0], l[1], l[2]);
          };
          unsigned p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
          // Outward winding: flip on the low side.
          if (side == 1) {
            c.triangles.push_back({p00, p10, p11});
            c.triangles.push_back({p00, p11, p01});
          } else {
            c.triangles.push_back({p00, p11, p10});
            c.triangles.push_back({p00, p01, p11});
          }
        }
  aimFromInside(c);
  return c;
}

HardCase closedSphere(int segments, int rings) {
  HardCase c;
  c.name = "sphere-inside";
  c.description = "closed unit UV sphere, " + std::to_string(segments) + " segments x " + std::to_string(rings) +
                  " rings, single poles and no seam duplicates; rays from two inside points through every vertex "
                  "and edge midpoint: every ray must hit";
  c.closed = true;
  c.positions.push_back(vec3(0.0f, 0.0f, -1.0f));  // south pole
  for (int r = 1; r < rings; ++r) {
    double theta = M_PI * double(r) / double(rings);
    for (int s = 0; s < segments; ++s) {
      double phi = 2.0 * M_PI * double(s) / double(segments);
      c.positions.push_back(vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                                 float(-std::cos(theta))));
    }
  }
  c.positions.push_back(vec3(0.0f, 0.0f, 1.0f));  // north pole
  const unsigned north = unsigned(c.positions.size() - 1);
  auto ring = [&](int r, int s) { return unsigned(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) {
    c.triangles.push_back({0u, ring(1, s + 1), ring(1, s)});
    c.triangles.push_back({north, ring(rings - 1, s), ring(rings - 1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r) {
      c.triangles.push_back({ring(r, s), ring(r, s + 1), ring(r + 1, s + 1)});
      c.triangles.push_back({ring(r, s), ring(r + 1, s + 1), ring(r + 1, s)});
    }
  }
  aimFromInside(c);
  return c;
}

HardCase transformed(const HardCase& c, vec3 offset, float scale) {
  HardCase out = c;
  char suffix[96];
  std::snprintf(suffix, sizeof suffix, "@offset%gscale%g", double(offset.x), double(scale));
  out.name += suffix;
  out.description += std::string(" (moved to offset + scale * p: ") + suffix + ")";
  out.farOrScaled = true;
  for (vec3& p : out.positions) p = offset + scale * p;
  // Rays keep aiming at the (rounded) transformed targets: recompute the directions from them.
  for (HardRay& r : out.rays) {
    vec3 target = r.origin + r.dir;
    r.origin = offset + scale * r.origin;
    r.dir = (offset + scale * target) - r.origin;
  }
  return out;
}

std::vector<HardCase> makeHardCases() {
  std::vector<HardCase> cases;
  cases.push_back(closedCube(6));
  cases.push_back(closedSphere(24, 12));

  {  // The quad-diagonal seam: pixel centres on the shared diagonal.
    HardCase c;
    c.name = "quad-seam";
    c.description =
        "quad [-1,1]^2 at z=0 split along the diagonal x=y; an orthographic 32x32 pixel grid along +z whose "
        "diagonal pixel centres lie exactly on the seam, and pinhole rays from (0,0,-2) through seam points: "
        "every ray passes through the inside of the quad and must hit";
    c.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    c.triangles = {{0, 1, 2}, {0, 2, 3}};
    const int n = 32;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        vec3 o(-1.0f + (float(i) + 0.5f) * (2.0f / n), -1.0f + (float(j) + 0.5f) * (2.0f / n), -1.0f);
        c.rays.push_back({o, vec3(0, 0, 1), 0.0f, HardRay{}.tMax, true});
      }
    for (int i = 0; i < n; ++i) {
      float x = -1.0f + (float(i) + 0.5f) * (2.0f / n);
      c.rays.push_back({vec3(0, 0, -2), vec3(x, x, 2), 0.0f, HardRay{}.tMax, true});
      c.rays.push_back({vec3(0.25f, 0.25f, -2), vec3(x - 0.25f, x - 0.25f, 2), 0.0f, HardRay{}.tMax, true});
    }
    cases.push_back(std::move(c));
  }
  {  // A ray grid along -y through the vertices of a grid mesh.
    HardCase c;
    c.name = "grid-vertices";
    c.description =
        "plane y=0 over [-1,1]^2 as 16x16 quads with alternating diagonals; rays along -y through every vertex "
        "and every edge midpoint (interior ones must hit; ones on the outer border are ties), and oblique rays "
        "through the interior vertices";
    const int n = 16;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) c.positions.push_back(vec3(-1.0f + i * (2.0f / n), 0.0f, -1.0f + j * (2.0f / n)));
    auto id = [&](int i, int j) { return unsigned(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if ((i + j) % 2 == 0) {
          c.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
          c.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        } else {
          c.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
          c.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
        }
      }
    auto interior = [](vec3 p) { return std::abs(p.x) < 1.0f && std::abs(p.z) < 1.0f; };
    for (int j = 0; j <= 2 * n; ++j)
      for (int i = 0; i <= 2 * n; ++i) {
        vec3 p(-1.0f + i * (1.0f / n), 0.0f, -1.0f + j * (1.0f / n));
        c.rays.push_back({p + vec3(0, 1, 0), vec3(0, -1, 0), 0.0f, HardRay{}.tMax, interior(p)});
      }
    for (const vec3& p : c.positions)
      if (interior(p)) c.rays.push_back({vec3(0.5f, 2.0f, 0.25f), p - vec3(0.5f, 2.0f, 0.25f), 0.0f, HardRay{}.tMax, true});
    cases.push_back(std::move(c));
  }
  {  // Axis-parallel rays with origins exactly on slab planes of a box, and a flat box.
    HardCase c;
    c.name = "slab-planes";
    c.description =
        "closed box [0,1]^3 (12 triangles) and the flat square z=2, [0,1]^2 (zero-thickness box); axis-parallel "
        "rays whose origins lie exactly on the slab planes x,y,z in {0,1}, inside and outside the other slabs, "
        "in both directions along each axis: box tests must accept every ray that touches a box";
    c.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1},
                   {0, 0, 2}, {1, 0, 2}, {1, 1, 2}, {0, 1, 2}};
    c.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                   {3, 7, 6}, {3, 6, 2}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5},
                   {8, 9, 10}, {8, 10, 11}};
    const float coords[] = {-0.5f, 0.0f, 0.5f, 1.0f, 1.5f};
    for (int axis = 0; axis < 3; ++axis)
      for (int plane = 0; plane < 3; ++plane) {
        if (plane == axis) continue;
        for (float onPlane : {0.0f, 1.0f})
          for (float other : coords)
            for (float along : {-1.0f, 0.5f, 2.5f})
              for (float sign : {-1.0f, 1.0f}) {
                vec3 o(0.0f), d(0.0f);
                int third = 3 - axis - plane;
                o[plane] = onPlane;
                o[third] = other;
                o[axis] = along;
                d[axis] = sign;
                c.rays.push_back({o, d, 0.0f, HardRay{}.tMax, false});
              }
      }
    cases.push_back(std::move(c));
  }
  {  // Needles and zero-area triangles.
    HardCase c;
    c.name = "needles";
    c.description =
        "needle triangles (1 x 1e-6 and 1 x 1e-30 wide), exactly collinear vertices, two and three coincident "
        "vertices; rays along +z through their length, their tips and just beside them";
    c.positions = {{0, 0, 0},    {1, 0, 0},    {0.5f, 1e-6f, 0},  // needle
                   {0, 1, 0.5f}, {1, 1, 0.5f}, {0.5f, 1, 0.5f},   // collinear
                   {0, 2, 1},    {0, 2, 1},    {1, 2, 1},         // two coincident
                   {0, 3, 1},    {0, 3, 1},    {0, 3, 1},         // three coincident
                   {0, 4, 0},    {1, 4, 0},    {0.5f, 4.0f + 1e-30f, 0}};  // sub-ulp needle: rounds to collinear
    for (unsigned k = 0; k < 5; ++k) c.triangles.push_back({3 * k, 3 * k + 1, 3 * k + 2});
    for (int row = 0; row < 5; ++row)
      for (int i = 0; i <= 16; ++i)
        for (float dy : {-1e-6f, 0.0f, 2.5e-7f, 5e-7f}) {
          vec3 o(float(i) / 16.0f, float(row) + dy, -1.0f);
          c.rays.push_back({o, vec3(0, 0, 1), 0.0f, HardRay{}.tMax, false});
        }
    cases.push_back(std::move(c));
  }
  {  // Coplanar overlapping triangles, a duplicate, a nearly coplanar neighbour.
    HardCase c;
    c.name = "coplanar-overlap";
    c.description =
        "in z=0: a triangle, a second one overlapping half of it, an exact duplicate of the first; a parallel "
        "triangle 1e-6 above; rays along +z and oblique through the overlaps (first hit: a tie among the "
        "coplanar ones), and rays lying in the plane z=0";
    c.positions = {{0, 0, 0},    {2, 0, 0},    {0, 2, 0},   {0.5f, 0.5f, 0}, {2.5f, 0.5f, 0}, {0.5f, 2.5f, 0},
                   {0, 0, 0},    {2, 0, 0},    {0, 2, 0},   {0, 0, 1e-6f},   {2, 0, 1e-6f},   {0, 2, 1e-6f}};
    c.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}};
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) {
        vec3 p(float(i) * 0.25f, float(j) * 0.25f, 0.0f);
        c.rays.push_back({p - vec3(0, 0, 1), vec3(0, 0, 1), 0.0f, HardRay{}.tMax, false});
        c.rays.push_back({p + vec3(0.5f, 0.25f, 1.0f), vec3(-0.5f, -0.25f, -1.0f), 0.0f, HardRay{}.tMax, false});
      }
    for (int i = 0; i < 8; ++i)
      c.rays.push_back({vec3(-1, 0.125f * float(i), 0), vec3(1, 0, 0), 0.0f, HardRay{}.tMax, false});
    cases.push_back(std::move(c));
  }
  {  // A closed octahedron as a soup: every triangle has its own copies of its vertices.
    HardCase c;
    c.name = "duplicated-vertices";
    c.description =
        "closed octahedron (vertices on the axes at distance 1) as a triangle soup: each of the 8 triangles "
        "has its own copies of its vertices (equal coordinates, different indices); rays from two inside "
        "points through every vertex and edge midpoint: every ray must hit";
    c.closed = true;
    const vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int sx = 0; sx < 2; ++sx)
      for (int sy = 0; sy < 2; ++sy)
        for (int sz = 0; sz < 2; ++sz) {
          vec3 a = axes[sx], b = axes[2 + sy], d = axes[4 + sz];
          // Outward winding: (b - a) x (d - a) must point along (a + b + d).
          if (glm::dot(glm::cross(b - a, d - a), a + b + d) < 0.0f) std::swap(b, d);
          unsigned base = unsigned(c.positions.size());
          c.positions.insert(c.positions.end(), {a, b, d});
          c.triangles.push_back({base, base + 1, base + 2});
        }
    aimFromInside(c);
    cases.push_back(std::move(c));
  }

  // Far offsets and extreme scales of the closed cases: the same rays must still all hit.
  const size_t closedCount = 2;
  for (size_t k = 0; k < closedCount; ++k) {
    for (float offset : {1e4f, 1e5f, 1e6f}) cases.push_back(transformed(cases[k], vec3(offset, -0.5f * offset, 0.25f * offset), 1.0f));
    for (float scale : {1e-4f, 1e-2f, 1e2f, 1e4f}) cases.push_back(transformed(cases[k], vec3(0.0f), scale));
  }
  return cases;
}

}  // namespace bvhlab::hard
