// cgal_oracle.cpp — the only CGAL translation unit of the datasets library (cgal_oracle.hpp).
// GMP and MPFR are switched off so that the exact number type is Boost.Multiprecision's (header-only):
// the project's libraries link no CGAL target, and CGAL itself is header-only. Slower than GMP, which
// does not matter for the few thousand rays of the suite.
#define CGAL_DISABLE_GMP 1
#define CGAL_DISABLE_MPFR 1
#include "datasets/cgal_oracle.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <cmath>
#include <stdexcept>

namespace bvhlab::oracle {
namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using FT = K::FT;
using Point = K::Point_3;
using Vector = K::Vector_3;

Point point(glm::vec3 p) { return Point(double(p.x), double(p.y), double(p.z)); }  // floats are exact doubles
Vector vector(glm::vec3 v) { return Vector(double(v.x), double(v.y), double(v.z)); }

bool meetsTriangle(const K::Ray_3& ray, const Point& a, const Point& b, const Point& c) {
  if (!CGAL::collinear(a, b, c)) return CGAL::do_intersect(ray, K::Triangle_3(a, b, c));
  // Zero area: the triangle is a segment (or a point); its hull is the longest of the three segments.
  if (a == b && b == c) return ray.has_on(a);
  const K::Segment_3 edges[3] = {{a, b}, {b, c}, {c, a}};
  for (const K::Segment_3& e : edges)
    if (!e.is_degenerate() && CGAL::do_intersect(ray, e)) return true;
  return false;
}

}  // namespace

ExactFirstHit exactFirstHit(const std::vector<glm::vec3>& positions, const std::vector<glm::uvec3>& triangles,
                            glm::vec3 origin, glm::vec3 dir, float tMin, float tMax) {
  if (!(tMin >= 0.0f) || std::isnan(tMax)) throw std::invalid_argument("exactFirstHit: tMin must be >= 0, tMax not NaN");
  const Point o = point(origin);
  const Vector d = vector(dir);
  const K::Ray_3 ray(o, d);
  const FT ftMin = FT(double(tMin));
  const bool bounded = std::isfinite(tMax);
  const FT ftMax = FT(bounded ? double(tMax) : 0.0);

  ExactFirstHit result;
  bool interior = false, boundaryTouch = false, haveFirst = false, firstInterior = false;
  FT firstT, firstMargin = 0;
  for (size_t i = 0; i < triangles.size(); ++i) {
    const glm::uvec3 tri = triangles[i];
    const glm::vec3 v0 = positions.at(tri.x), v1 = positions.at(tri.y), v2 = positions.at(tri.z);
    // Cheap exact reject first: the ray misses the triangle's box (a filtered predicate).
    const glm::vec3 lo = glm::min(v0, glm::min(v1, v2)), hi = glm::max(v0, glm::max(v1, v2));
    if (!CGAL::do_intersect(ray, CGAL::Bbox_3(lo.x, lo.y, lo.z, hi.x, hi.y, hi.z))) continue;
    const Point a = point(v0), b = point(v1), c = point(v2);
    const Vector e1 = b - a, e2 = c - a;
    const Vector p = CGAL::cross_product(d, e2);
    const FT det = e1 * p;
    if (det == 0) {
      // Parallel to the plane, or zero area: at most a boundary touch.
      if (meetsTriangle(ray, a, b, c)) boundaryTouch = true;
      continue;
    }
    const Vector s = o - a;
    const Vector q = CGAL::cross_product(s, e1);
    const FT u = (s * p) / det, v = (d * q) / det, t = (e2 * q) / det;
    if (u < 0 || v < 0 || u + v > 1) continue;
    if (t < ftMin || (bounded && t > ftMax)) continue;
    const bool onBoundary = u == 0 || v == 0 || u + v == 1 || t == ftMin || (bounded && t == ftMax);
    if (onBoundary) boundaryTouch = true;
    else interior = true;
    if (t == ftMin || (bounded && t == ftMax)) continue;  // outside the open t interval: boundary only
    if (!haveFirst || t < firstT) {
      haveFirst = true;
      firstT = t;
      result.firstTriangles.assign(1, int(i));
      firstInterior = !onBoundary;
      firstMargin = CGAL::min(CGAL::min(u, v), 1 - u - v);
    } else if (t == firstT) {
      result.firstTriangles.push_back(int(i));
      firstInterior = firstInterior || !onBoundary;
      firstMargin = CGAL::max(firstMargin, CGAL::min(CGAL::min(u, v), 1 - u - v));
    }
  }
  result.hit = interior ? Decision::Hit : (boundaryTouch || haveFirst ? Decision::Tie : Decision::Miss);
  if (result.hit != Decision::Hit) result.firstTriangles.clear();
  if (haveFirst) {
    result.firstT = CGAL::to_double(firstT);
    result.firstMargin = CGAL::to_double(firstMargin);
  }
  result.firstDecisive = result.hit == Decision::Hit && !boundaryTouch && firstInterior;
  return result;
}

bool exactRayMeetsBox(glm::vec3 origin, glm::vec3 dir, glm::vec3 bmin, glm::vec3 bmax) {
  const K::Ray_3 ray(point(origin), vector(dir));
  return CGAL::do_intersect(ray, K::Iso_cuboid_3(point(bmin), point(bmax)));
}

bool exactRayMeetsTriangle(glm::vec3 origin, glm::vec3 dir, glm::vec3 v0, glm::vec3 v1, glm::vec3 v2) {
  return meetsTriangle(K::Ray_3(point(origin), vector(dir)), point(v0), point(v1), point(v2));
}

}  // namespace bvhlab::oracle
