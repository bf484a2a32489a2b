// Conservative triangle clipping for builders that split primitives (builders/sbvh.cpp).
//
// clipTriangleToSlab() returns a float box that contains the exact bounds of
//     T ∩ { lo <= x[axis] <= hi }      (T the closed triangle (a, b, c), lo/hi may be -inf/+inf)
// and exceeds them by at most one float step per face beyond rounding outward. The exact set's
// bounds are attained at its vertices: the triangle's vertices inside the slab and the points where
// its edges cross the slab's planes (a plane section of a convex set has no other corners). Vertex
// coordinates and plane values are floats, so every comparison that decides WHICH points exist is
// exact; only the crossing coordinates on the two other axes are computed, in double, and each is
// widened by a proven bound on its rounding error before it is rounded outward to float (see
// crossingRange). So the box always contains the exact clipped part, whatever the triangle's shape:
// axis-parallel triangles (differences are exact zeros), needles, zero-area triangles (segments and
// points are convex too) and planes through vertices.
//
// The SBVH clips a reference by intersecting this box with the reference's current box (Stich et
// al. 2009; Embree does the same): the float box of a reference then contains the exact part of its
// triangle that the reference stands for, and every builder box is an intersection/union of such
// float boxes, so nothing is ever rounded inward.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"

namespace bvhlab::clip {

// The largest float <= x and the smallest float >= x, for a finite double within float range.
inline float floatDown(double x) {
  float f = static_cast<float>(x);  // round to nearest
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
inline float floatUp(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

// Coordinate `i` of the point where the segment p -> q crosses the plane x[k] = s, as a float range
// [lo, hi] that contains the exact value. Precondition: p[k] and q[k] lie strictly on opposite sides
// of s (so q[k] - p[k] != 0 and the exact parameter t lies in (0, 1): nothing here can divide by
// zero or produce a NaN).
//
// Error bound. Inputs are floats, hence exact doubles; u = 2^-53 is the unit roundoff of double.
// With the standard model fl(x op y) = (x op y)(1 + d), |d| <= u (no overflow: float differences
// and products of such stay far inside double's range; no underflow: |t| >= 2^-149 / 2^129 and
// |q[i] - p[i]| >= 2^-149 when nonzero, so |m| >= 2^-427, still a normal double):
//   d1 = fl(s - p[k]), d2 = fl(q[k] - p[k]), t = fl(d1 / d2)   -> t carries relative error <= 3u(1+u)
//   m = fl(t * fl(q[i] - p[i]))                                 -> relative error <= 5u(1+3u)
//   x = fl(p[i] + m)            -> |x - exact| <= u|p[i] + m| + 5.01u|m| <= 7u (|p[i]| + |m|).
// Widening by err = 16u (|p[i]| + |m|) leaves room for the rounding of err itself and of x -+ err
// (each at most u times a value <= 2(|p[i]| + |m|)), so fl(x - err) <= exact <= fl(x + err). The
// crossing also lies on the segment, so the range is clamped to [min, max] of p[i], q[i] (floats:
// exact), which makes it exact whenever p[i] == q[i] (axis-parallel edges). 16u = 2^-49 relative is
// far below a float step (2^-23), so the widening costs at most one float step, usually none.
//
// When every operation happens to be exact (checked with error-free transformations: Knuth's TwoSum
// for the sums, an FMA for the product and the division's remainder), x is the exact value and no
// widening is needed: the common case of coordinates on a coarse grid, and crossings at vertices.
inline double sumError(double a, double b, double sum) {  // (a + b) - sum, exactly (TwoSum)
  const double bb = sum - a;
  return (a - (sum - bb)) + (b - bb);
}

inline void crossingRange(const glm::vec3& p, const glm::vec3& q, int k, float s, int i, float& lo, float& hi) {
  constexpr double u = std::numeric_limits<double>::epsilon() / 2.0;
  const double d1 = double(s) - double(p[k]);
  const double d2 = double(q[k]) - double(p[k]);
  const double t = d1 / d2;
  const double e = double(q[i]) - double(p[i]);
  const double m = t * e;
  const double x = double(p[i]) + m;
  const bool exact = sumError(double(s), -double(p[k]), d1) == 0.0 && sumError(double(q[k]), -double(p[k]), d2) == 0.0 &&
                     std::fma(-t, d2, d1) == 0.0 && sumError(double(q[i]), -double(p[i]), e) == 0.0 &&
                     std::fma(t, e, -m) == 0.0 && sumError(double(p[i]), m, x) == 0.0;
  const double err = exact ? 0.0 : 16.0 * u * (std::abs(double(p[i])) + std::abs(m));
  const double segLo = std::min(double(p[i]), double(q[i])), segHi = std::max(double(p[i]), double(q[i]));
  lo = floatDown(std::max(x - err, segLo));
  hi = floatUp(std::min(x + err, segHi));
}

// A float box containing the exact bounds of T ∩ {lo <= x[axis] <= hi} (see the top of the file);
// empty when the closed slab misses the triangle. lo/hi may be infinite (a half-space); NaN never
// reaches a comparison that decides anything (the caller passes finite vertices and lo <= hi).
inline Aabb clipTriangleToSlab(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, int axis, float lo,
                               float hi) {
  Aabb box;
  const glm::vec3* v[3] = {&a, &b, &c};
  for (const glm::vec3* p : v)
    if (lo <= (*p)[axis] && (*p)[axis] <= hi) box.grow(*p);
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  for (int e = 0; e < 3; ++e) {
    const glm::vec3& p = *v[e];
    const glm::vec3& q = *v[(e + 1) % 3];
    for (float s : {lo, hi}) {
      // Strictly on opposite sides; an infinite s never separates two finite values.
      if (!((p[axis] < s && s < q[axis]) || (q[axis] < s && s < p[axis]))) continue;
      glm::vec3 pmin, pmax;
      pmin[axis] = pmax[axis] = s;
      crossingRange(p, q, axis, s, i, pmin[i], pmax[i]);
      crossingRange(p, q, axis, s, j, pmin[j], pmax[j]);
      box.grow(Aabb{pmin, pmax});
    }
  }
  return box;
}

// a ∩ b (empty when they do not meet; closed boxes, so touching boxes give a flat box).
inline Aabb intersect(const Aabb& a, const Aabb& b) {
  Aabb r{glm::max(a.min, b.min), glm::min(a.max, b.max)};
  return r.empty() ? Aabb{} : r;
}

// The part of a reference (current box `box`, standing for a part of triangle (a, b, c)) inside the
// slab lo <= x[axis] <= hi: the clipped triangle's box ∩ the reference's box ∩ the slab.
inline Aabb clipReference(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const Aabb& box, int axis,
                          float lo, float hi) {
  Aabb slab = box;
  slab.min[axis] = std::max(slab.min[axis], lo);
  slab.max[axis] = std::min(slab.max[axis], hi);
  if (slab.empty()) return {};
  return intersect(clipTriangleToSlab(a, b, c, axis, lo, hi), slab);
}

// The same for a primitive known only by its box: the primitive is its box, clipped exactly.
inline Aabb clipBox(const Aabb& box, int axis, float lo, float hi) {
  Aabb r = box;
  r.min[axis] = std::max(r.min[axis], lo);
  r.max[axis] = std::min(r.max[axis], hi);
  return r.empty() ? Aabb{} : r;
}

}  // namespace bvhlab::clip
