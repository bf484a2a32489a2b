// builders/clip.hpp (SBVH's exact clipping of a triangle into a slab or a box, in double, rounded
// outward) against CGAL's exact intersection, on random and degenerate triangles (axis-parallel,
// needles, zero area) and through successive splits.
//
// CGAL (EPECK, header-only with GMP/MPFR off, as datasets/cgal_oracle.cpp) is used in this file only.
#define CGAL_DISABLE_GMP 1
#define CGAL_DISABLE_MPFR 1
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/clip.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/random_draws.hpp"
#include "layout/layout.hpp"
#include "traversal/kernels.hpp"
#include "traversal/ray_triangle.hpp"

namespace bvhlab {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- exact clipping with CGAL -------------------------------------------------------------------

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using FT = K::FT;
using Point = K::Point_3;

Point point(const glm::vec3& p) { return Point(double(p.x), double(p.y), double(p.z)); }

struct ExactBox {
  bool empty = true;
  FT lo[3], hi[3];
  void grow(const Point& p) {
    for (int a = 0; a < 3; ++a) {
      if (empty || p[a] < lo[a]) lo[a] = p[a];
      if (empty || p[a] > hi[a]) hi[a] = p[a];
    }
    empty = false;
  }
};

// Exact bounds of T ∩ {lo <= x[axis] <= hi}: CGAL's intersection of the triangle (or, for a
// zero-area one, the segment or point it is) with an iso-cuboid that is the slab on `axis` and
// encloses the triangle on the other two.
ExactBox exactSlabBounds(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, int axis, float lo, float hi) {
  Aabb t;
  t.grow(a), t.grow(b), t.grow(c);
  double cmin[3], cmax[3];
  for (int k = 0; k < 3; ++k) cmin[k] = double(t.min[k]) - 1.0, cmax[k] = double(t.max[k]) + 1.0;
  if (std::isfinite(lo)) cmin[axis] = lo;
  if (std::isfinite(hi)) cmax[axis] = hi;
  ExactBox out;
  if (cmin[axis] > cmax[axis]) return out;
  const K::Iso_cuboid_3 box(Point(cmin[0], cmin[1], cmin[2]), Point(cmax[0], cmax[1], cmax[2]));
  const Point pa = point(a), pb = point(b), pc = point(c);
  if (!CGAL::collinear(pa, pb, pc)) {
    const auto r = CGAL::intersection(K::Triangle_3(pa, pb, pc), box);
    if (!r) return out;
    if (const Point* p = boost::get<Point>(&*r)) out.grow(*p);
    if (const K::Segment_3* s = boost::get<K::Segment_3>(&*r)) out.grow(s->source()), out.grow(s->target());
    if (const K::Triangle_3* tr = boost::get<K::Triangle_3>(&*r))
      for (int k = 0; k < 3; ++k) out.grow(tr->vertex(k));
    if (const std::vector<Point>* poly = boost::get<std::vector<Point>>(&*r))
      for (const Point& p : *poly) out.grow(p);
    return out;
  }
  if (pa == pb && pb == pc) {
    if (!box.has_on_unbounded_side(pa)) out.grow(pa);
    return out;
  }
  // Collinear: the hull is the longest of the three segments.
  K::Segment_3 seg(pa, pb);
  for (const K::Segment_3& s : {K::Segment_3(pb, pc), K::Segment_3(pc, pa)})
    if (s.squared_length() > seg.squared_length()) seg = s;
  const auto r = CGAL::intersection(seg, box);
  if (!r) return out;
  if (const Point* p = boost::get<Point>(&*r)) out.grow(*p);
  if (const K::Segment_3* s = boost::get<K::Segment_3>(&*r)) out.grow(s->source()), out.grow(s->target());
  return out;
}

// Exact bounds of T ∩ box by Sutherland-Hodgman clipping in CGAL's exact number type (CGAL's own
// triangle/iso-cuboid intersection is far slower on these nested boxes).
ExactBox exactBoxClipBounds(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const double lo[3],
                            const double hi[3]) {
  std::vector<Point> poly = {point(a), point(b), point(c)}, next;
  for (int axis = 0; axis < 3 && !poly.empty(); ++axis)
    for (int side = 0; side < 2 && !poly.empty(); ++side) {
      const FT plane = side == 0 ? FT(lo[axis]) : FT(hi[axis]);
      auto dist = [&](const Point& p) { return side == 0 ? p[axis] - plane : plane - p[axis]; };  // >= 0 inside
      next.clear();
      for (size_t i = 0; i < poly.size(); ++i) {
        const Point &p = poly[i], &q = poly[(i + 1) % poly.size()];
        const FT dp = dist(p), dq = dist(q);
        if (dp >= 0) next.push_back(p);
        if ((dp > 0 && dq < 0) || (dp < 0 && dq > 0)) next.push_back(p + (q - p) * (dp / (dp - dq)));
      }
      poly.swap(next);
    }
  ExactBox out;
  for (const Point& p : poly) out.grow(p);
  return out;
}

float up(float f) { return std::nextafter(f, kInf); }
float down(float f) { return std::nextafter(f, -kInf); }

// `box` contains the exact bounds and is at most one float step looser than rounding them outward,
// or than the crossing's documented error bound (builders/clip.hpp: 16u relative to the magnitudes
// of the coordinates involved, `scale`), whichever is larger.
::testing::AssertionResult matchesExact(const Aabb& box, const ExactBox& exact, double scale) {
  const double slack = 32.0 * std::numeric_limits<double>::epsilon() * scale;
  if (exact.empty != box.empty())
    return ::testing::AssertionFailure() << "exact " << (exact.empty ? "empty" : "non-empty") << ", clipped "
                                         << (box.empty() ? "empty" : "non-empty");
  if (exact.empty) return ::testing::AssertionSuccess();
  for (int a = 0; a < 3; ++a) {
    const double elo = CGAL::to_double(exact.lo[a]), ehi = CGAL::to_double(exact.hi[a]);
    if (!(FT(double(box.min[a])) <= exact.lo[a]) || !(FT(double(box.max[a])) >= exact.hi[a]))
      return ::testing::AssertionFailure() << "axis " << a << ": [" << box.min[a] << ", " << box.max[a]
                                           << "] does not contain the exact [" << elo << ", " << ehi << "]";
    const bool loTight = FT(double(up(up(box.min[a])))) > exact.lo[a] || FT(double(box.min[a]) + slack) >= exact.lo[a];
    const bool hiTight = FT(double(down(down(box.max[a])))) < exact.hi[a] || FT(double(box.max[a]) - slack) <= exact.hi[a];
    if (!loTight || !hiTight)
      return ::testing::AssertionFailure() << "axis " << a << ": [" << box.min[a] << ", " << box.max[a]
                                           << "] is more than a float step looser than the exact [" << elo << ", "
                                           << ehi << "]";
  }
  return ::testing::AssertionSuccess();
}

std::string describe(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, int axis, float lo, float hi) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "T = (%.9g %.9g %.9g) (%.9g %.9g %.9g) (%.9g %.9g %.9g), axis %d, slab [%.9g, %.9g]",
                a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, axis, lo, hi);
  return buf;
}

size_t checkAgainstCgal(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, int axis, float lo, float hi) {
  const Aabb box = clip::clipTriangleToSlab(a, b, c, axis, lo, hi);
  const ExactBox exact = exactSlabBounds(a, b, c, axis, lo, hi);
  const glm::vec3 m = glm::max(glm::abs(a), glm::max(glm::abs(b), glm::abs(c)));
  EXPECT_TRUE(matchesExact(box, exact, 2.0 * std::max({m.x, m.y, m.z}))) << describe(a, b, c, axis, lo, hi);
  // A reference's clip: the same intersected with its box (here a random sub-box of the triangle's).
  return exact.empty ? 0 : 1;
}

// Slab bounds worth trying for a triangle on an axis: through its vertices, between them, beyond
// them, infinite, and zero-width.
std::vector<std::pair<float, float>> slabsFor(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, int axis,
                                              std::mt19937& rng) {
  const float v[3] = {a[axis], b[axis], c[axis]};
  const float lo = std::min({v[0], v[1], v[2]}), hi = std::max({v[0], v[1], v[2]});
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto inside = [&] { return lo + (hi - lo) * u(rng); };
  std::vector<float> planes = {v[0], v[1], v[2], inside(), inside(), inside(), down(lo), up(hi), up(v[1]), down(v[2])};
  std::vector<std::pair<float, float>> slabs;
  for (float p : planes) {
    slabs.push_back({-kInf, p});
    slabs.push_back({p, kInf});
    slabs.push_back({p, p});
  }
  for (int k = 0; k < 6; ++k) {
    float x = planes[std::uniform_int_distribution<size_t>(0, planes.size() - 1)(rng)];
    float y = planes[std::uniform_int_distribution<size_t>(0, planes.size() - 1)(rng)];
    slabs.push_back({std::min(x, y), std::max(x, y)});
  }
  slabs.push_back({-kInf, kInf});
  return slabs;
}

TEST(Clip, MatchesCgalOnRandomTriangles) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  size_t nonEmpty = 0, total = 0;
  for (int i = 0; i < 120; ++i) {
    const float scale = std::pow(10.0f, float(i % 7) - 3.0f);  // 1e-3 .. 1e3
    const glm::vec3 offset = draw3<glm::vec3>(u, rng) * (i % 2 ? 100.0f : 0.0f);
    auto corner = [&] { return offset + scale * draw3<glm::vec3>(u, rng); };
    const glm::vec3 a = corner(), b = corner(), c = corner();
    for (int axis = 0; axis < 3; ++axis)
      for (const auto& [lo, hi] : slabsFor(a, b, c, axis, rng)) {
        nonEmpty += checkAgainstCgal(a, b, c, axis, lo, hi);
        ++total;
      }
  }
  EXPECT_GT(nonEmpty, total / 2);
  EXPECT_LT(nonEmpty, total);
}

TEST(Clip, MatchesCgalOnDegenerateTriangles) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<std::array<glm::vec3, 3>> tris;
  for (int i = 0; i < 12; ++i) {
    const glm::vec3 a = draw3<glm::vec3>(u, rng), b = draw3<glm::vec3>(u, rng),
                    c = draw3<glm::vec3>(u, rng);
    for (int axis = 0; axis < 3; ++axis) {
      // Axis-parallel: all three in the plane x[axis] = a[axis].
      glm::vec3 b2 = b, c2 = c;
      b2[axis] = c2[axis] = a[axis];
      tris.push_back({a, b2, c2});
      // One edge parallel to the axis (a and b differ only on it).
      glm::vec3 b3 = a;
      b3[axis] = b[axis];
      tris.push_back({a, b3, c});
      // Axis-aligned segment and a triangle with two coordinates shared.
      glm::vec3 c4 = b3;
      c4[(axis + 1) % 3] = c[(axis + 1) % 3];
      tris.push_back({a, b3, c4});
    }
    // Needles: one long edge and a tiny third vertex, at large and at small offsets.
    const glm::vec3 far = a + 1000.0f * (b - a);
    tris.push_back({a, far, a + glm::vec3(1e-6f, 0.0f, 2e-6f)});
    tris.push_back({a, far, glm::vec3(up(far.x), far.y, far.z)});
    tris.push_back({a, b, glm::vec3(std::nextafter(b.x, kInf), b.y, std::nextafter(b.z, -kInf))});
    // Zero area: collinear (quarters are exact), repeated vertices, a point.
    const glm::vec3 q0 = glm::round(a * 8.0f) / 8.0f, q1 = glm::round(b * 8.0f) / 8.0f;
    tris.push_back({q0, 0.5f * (q0 + q1), q1});
    tris.push_back({q0, q1, q1});
    tris.push_back({a, a, a});
    tris.push_back({a, b, a});
  }
  for (const auto& t : tris)
    for (int axis = 0; axis < 3; ++axis)
      for (const auto& [lo, hi] : slabsFor(t[0], t[1], t[2], axis, rng)) checkAgainstCgal(t[0], t[1], t[2], axis, lo, hi);
}

// A reference's clip is the triangle's slab clip ∩ the reference's box ∩ the slab: containment of
// the exact T ∩ slab ∩ box, on random sub-boxes of triangles (the order of successive splits).
TEST(Clip, SuccessiveSplitsKeepTheExactPart) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), unit(0.0f, 1.0f);
  for (int i = 0; i < 40; ++i) {
    const glm::vec3 a = draw3<glm::vec3>(u, rng), b = draw3<glm::vec3>(u, rng),
                    c = draw3<glm::vec3>(u, rng);
    Aabb box;
    box.grow(a), box.grow(b), box.grow(c);
    // Split repeatedly at random planes, following a random side, as a builder does.
    for (int step = 0; step < 8 && !box.empty(); ++step) {
      const int axis = int(rng() % 3);
      const float s = box.min[axis] + (box.max[axis] - box.min[axis]) * unit(rng);
      const bool left = rng() % 2;
      const Aabb next = left ? clip::clipReference(a, b, c, box, axis, -kInf, s) : clip::clipReference(a, b, c, box, axis, s, kInf);
      // Exact part so far: T ∩ every slab taken; its bounds must lie in `next`. The clip of T to
      // the box's own slabs (three axes) bounds it from outside, so check containment of the exact
      // T ∩ next-slab ∩ previous box, clipped exactly.
      double lo[3], hi[3];
      for (int k = 0; k < 3; ++k) lo[k] = box.min[k], hi[k] = box.max[k];
      if (left) hi[axis] = std::min(hi[axis], double(s));
      else lo[axis] = std::max(lo[axis], double(s));
      const ExactBox exact = exactBoxClipBounds(a, b, c, lo, hi);
      if (!exact.empty) {
        ASSERT_FALSE(next.empty()) << describe(a, b, c, axis, s, s);
        for (int k = 0; k < 3; ++k) {
          EXPECT_TRUE(FT(double(next.min[k])) <= exact.lo[k]) << describe(a, b, c, axis, s, s);
          EXPECT_TRUE(FT(double(next.max[k])) >= exact.hi[k]) << describe(a, b, c, axis, s, s);
        }
      }
      EXPECT_TRUE(next.empty() || box.contains(next));
      box = next;
    }
  }
}

}  // namespace
}  // namespace bvhlab
