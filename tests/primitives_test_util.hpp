// Shared by test_primitives.cpp (the C++ mirrors of the analytic ray-primitive intersections,
// shaders/primitives.hpp) and test_primitives_glsl.cpp (the GLSL, shaders/prim_*.glsl, run on the GL
// device): the shapes, a double-precision reference written independently of the mirrors (per-surface
// candidates for the quadrics and the box, dense sign sampling + bisection for the torus), the check of
// one ray's result against it, and the random rays of the property test.
//
// Error model (what the bounds below are stated in). Positions are float, so the hit point cannot be
// better than a few ulps of the largest of the object's size S (bounding radius), the origin's distance |o|
// and the hit's distance: L = max(S, |o|, t |d|). With eps = 2^-23 (float epsilon):
//   position error  |t - t_ref| |d|        <= kPositionBound * eps * L / max(|cos i|, kMinCos)
//   normal error    angle(n, n_ref) * rho  <= kNormalBound   * eps * L / max(|cos i|, kMinCos)
// where i is the angle of incidence (error grows as 1/cos i for grazing hits, and is only checked for
// |cos i| >= kMinCos, i.e. incidence below ~87 degrees) and rho the smallest radius of curvature at the
// hit (the torus's minor radius; on the cone's side r sqrt(5) / 2 at distance r from the axis, at most 1;
// else 1). Near the cone's apex see kApexZone. Hit/miss (and which root) may differ
// from the reference only for GRAZING rays: the ray passes within kGrazeBand * eps * L of touching the
// surface without crossing it (a tangent, an edge, a spindle torus's pinch), or its hit lies within that
// distance of tMin/tMax.
// Measured (random rays, all kinds, origins at 2-4 S, inside, and at 1e4 S; |d| from 5e-4 to 2e3): position
// error <= 2.2 (15.7 for a torus with r = R/100 seen from 1e4), normal error <= 12, disagreements explained
// by grazing within 0.1 eps*L, <= 0.4% of rays. The bounds leave a margin of >= 4x.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>

#include "datasets/random_draws.hpp"
#include "shaders/primitives.hpp"

namespace bvhlab::primtest {

using bvhlab::glsl::Ray;
using glm::dvec2;
using glm::dvec3;
using glm::vec2;
using glm::vec3;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kEps = std::numeric_limits<float>::epsilon();  // 2^-23

// Bounds of the error model above, in units of eps * L (see the header comment).
constexpr double kPositionBound = 64.0;
constexpr double kNormalBound = 64.0;
constexpr double kGrazeBand = 16.0;
constexpr double kMinCos = 0.05;
// Within kApexZone of the cone's apex the two roots (one per nappe) nearly coincide, and a double root of
// a float quadratic is only good to ~sqrt(eps): there the position bound is kApexBound * sqrt(eps) * L and
// the normal (undefined at the apex) is not checked.
constexpr double kApexZone = 0.01;
constexpr double kApexBound = 4.0;

// ---------------------------------------------------------------------------------------------------------
// Shapes and the float functions under test
// ---------------------------------------------------------------------------------------------------------
enum class Kind { Sphere, Box, Cylinder, Cone, Torus, Plane, InfinitePlane };
inline const char* kindName(Kind k) {
  switch (k) {
    case Kind::Sphere: return "sphere";
    case Kind::Box: return "box";
    case Kind::Cylinder: return "cylinder";
    case Kind::Cone: return "cone";
    case Kind::Torus: return "torus";
    case Kind::Plane: return "plane";
    case Kind::InfinitePlane: return "infinite plane";
  }
  return "?";
}

struct Shape {
  Kind kind = Kind::Sphere;
  vec2 radii{1.0f, 0.25f};  // torus only
  // Radius of a sphere about the origin that holds the shape (for the infinite plane: its unit tile).
  double boundingRadius() const {
    switch (kind) {
      case Kind::Sphere: return 1.0;
      case Kind::Box: return std::sqrt(3.0);
      case Kind::Torus: return double(radii.x) + double(radii.y);
      default: return std::sqrt(2.0);
    }
  }
  // Smallest radius of curvature at the surface point p, away from edges: a position error dp tilts the
  // normal by about dp / curvatureRadius. The cone's side curves around its axis with radius
  // r / cos(half angle) = r sqrt(5) / 2 at distance r from the axis (half angle atan(1/2)), which goes
  // to 0 at the apex: a hit 0.011 from the axis tilts its normal ~90x more per unit of position error
  // than one on the base rim.
  double curvatureRadius(dvec3 p) const {
    if (kind == Kind::Torus) return double(radii.y);
    if (kind == Kind::Cone) return std::min(1.0, 0.5 * std::sqrt(5.0) * std::hypot(p.x, p.z));
    return 1.0;
  }
};

struct Hit {
  bool hit = false;
  float t = 0.0f;
  vec3 normal{0.0f};
  vec2 uv{0.0f};
};

inline Hit trace(const Shape& shape, const Ray& ray, float tMin, float tMax) {
  namespace g = bvhlab::glsl;
  Hit h;
  switch (shape.kind) {
    case Kind::Sphere: h.hit = g::intersectSphere(ray, tMin, tMax, h.t, h.normal, h.uv); break;
    case Kind::Box: h.hit = g::intersectBox(ray, tMin, tMax, h.t, h.normal, h.uv); break;
    case Kind::Cylinder: h.hit = g::intersectCylinder(ray, tMin, tMax, h.t, h.normal, h.uv); break;
    case Kind::Cone: h.hit = g::intersectCone(ray, tMin, tMax, h.t, h.normal, h.uv); break;
    case Kind::Torus: h.hit = g::intersectTorus(ray, shape.radii, tMin, tMax, h.t, h.normal, h.uv); break;
    case Kind::Plane: h.hit = g::intersectPlane(ray, false, tMin, tMax, h.t, h.normal, h.uv); break;
    case Kind::InfinitePlane: h.hit = g::intersectPlane(ray, true, tMin, tMax, h.t, h.normal, h.uv); break;
  }
  return h;
}

// ---------------------------------------------------------------------------------------------------------
// Double-precision reference: every surface piece is intersected on its own and the nearest valid
// candidate wins (a different method from the interval logic under test). `feature` is the distance of the
// hit point to an edge/rim/apex of the surface (infinity on smooth surfaces); near one the face choice is
// ambiguous, so normals are compared only away from them.
// ---------------------------------------------------------------------------------------------------------
struct RefRay {
  dvec3 o, d;
  double tMin, tMax;
};
struct RefHit {
  bool hit = false;
  double t = 0.0;
  dvec3 normal{0.0};
  double feature = INFINITY;
  double apex = INFINITY;  // distance to the cone's apex, a singular point of the surface
};

inline void consider(RefHit& best, const RefRay& ray, double t, dvec3 normal, double feature,
              double apex = INFINITY) {
  if (t > ray.tMin && t < ray.tMax && (!best.hit || t < best.t)) best = {true, t, normal, feature, apex};
}

// Real roots of a t^2 + 2 b t + c = 0 by the textbook formula (double has the digits to spare);
// a == 0: the linear root. Returns the count.
inline int refQuadratic(double a, double b, double c, double roots[2]) {
  if (a == 0.0) {
    if (b == 0.0) return 0;
    roots[0] = -c / (2.0 * b);
    return 1;
  }
  double disc = b * b - a * c;
  if (disc < 0.0) return 0;
  roots[0] = (-b - std::sqrt(disc)) / a;
  roots[1] = (-b + std::sqrt(disc)) / a;
  return 2;
}

inline RefHit refSphere(const RefRay& ray) {
  RefHit best;
  double roots[2];
  int n = refQuadratic(dot(ray.d, ray.d), dot(ray.o, ray.d), dot(ray.o, ray.o) - 1.0, roots);
  for (int i = 0; i < n; ++i) consider(best, ray, roots[i], ray.o + roots[i] * ray.d, INFINITY);
  return best;
}

inline RefHit refBox(const RefRay& ray) {
  RefHit best;
  for (int axis = 0; axis < 3; ++axis) {
    if (ray.d[axis] == 0.0) continue;
    for (double side : {-1.0, 1.0}) {
      double t = (side - ray.o[axis]) / ray.d[axis];
      dvec3 p = ray.o + t * ray.d;
      int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      if (std::abs(p[a1]) > 1.0 || std::abs(p[a2]) > 1.0) continue;
      dvec3 n(0.0);
      n[axis] = side;
      consider(best, ray, t, n, std::min(1.0 - std::abs(p[a1]), 1.0 - std::abs(p[a2])));
    }
  }
  return best;
}

// The caps y = -1 (and y = +1 when `top`): disc of radius `radius`.
inline void refCaps(RefHit& best, const RefRay& ray, bool top) {
  if (ray.d.y == 0.0) return;
  for (double side : {-1.0, 1.0}) {
    if (side > 0.0 && !top) continue;
    double t = (side - ray.o.y) / ray.d.y;
    dvec3 p = ray.o + t * ray.d;
    double r = std::hypot(p.x, p.z);
    if (r <= 1.0) consider(best, ray, t, dvec3(0.0, side, 0.0), 1.0 - r);
  }
}

inline RefHit refCylinder(const RefRay& ray) {
  RefHit best;
  double roots[2];
  const dvec3 &o = ray.o, &d = ray.d;
  int n = refQuadratic(d.x * d.x + d.z * d.z, o.x * d.x + o.z * d.z, o.x * o.x + o.z * o.z - 1.0, roots);
  for (int i = 0; i < n; ++i) {
    dvec3 p = o + roots[i] * d;
    if (std::abs(p.y) <= 1.0) consider(best, ray, roots[i], dvec3(p.x, 0.0, p.z), 1.0 - std::abs(p.y));
  }
  refCaps(best, ray, true);
  return best;
}

inline RefHit refCone(const RefRay& ray) {
  RefHit best;
  double roots[2];
  const dvec3 &o = ray.o, &d = ray.d;
  double w = 1.0 - o.y;
  int n = refQuadratic(4.0 * (d.x * d.x + d.z * d.z) - d.y * d.y, 4.0 * (o.x * d.x + o.z * d.z) + w * d.y,
                       4.0 * (o.x * o.x + o.z * o.z) - w * w, roots);
  for (int i = 0; i < n; ++i) {
    dvec3 p = o + roots[i] * d;
    if (p.y < -1.0 || p.y > 1.0) continue;  // the other nappe, or below the base
    double r = std::hypot(p.x, p.z);
    dvec3 normal = r > 0.0 ? dvec3(2.0 * p.x / r, 1.0, 2.0 * p.z / r) : dvec3(0.0, 1.0, 0.0);
    consider(best, ray, roots[i], normal, std::min(1.0 - p.y, p.y + 1.0), length(p - dvec3(0.0, 1.0, 0.0)));
  }
  refCaps(best, ray, false);
  return best;
}

inline double torusImplicit(dvec3 p, double R, double r) {
  double k = dot(p, p) + R * R - r * r;
  return k * k - 4.0 * R * R * (p.x * p.x + p.z * p.z);
}

// The ray's parameter interval inside the sphere |p| <= radius, clipped to (tMin, tMax). False if empty.
inline bool refSphereInterval(const RefRay& ray, double radius, double& tA, double& tB) {
  double a = dot(ray.d, ray.d), b = dot(ray.o, ray.d), c = dot(ray.o, ray.o) - radius * radius;
  double disc = b * b - a * c;
  if (disc <= 0.0) return false;
  tA = std::max(ray.tMin, (-b - std::sqrt(disc)) / a);
  tB = std::min(ray.tMax, (-b + std::sqrt(disc)) / a);
  return tA < tB;
}

// Torus: sign changes of the implicit function at kTorusSamples points along the ray inside the bounding
// sphere (enlarged by 1%), each refined by bisection to double precision. Two roots closer than the
// sample spacing h (~2 S / 4096) are missed; such a chord dips at most h^2 / (8 r) ~ 1e-7 S into the tube, far inside the
// grazing band, so the property test treats those rays as grazing.
inline RefHit refTorus(const RefRay& ray, double R, double r) {
  constexpr int kTorusSamples = 4096;
  RefHit best;
  double tA, tB;
  if (!refSphereInterval(ray, (R + r) * 1.01, tA, tB)) return best;  // enlarged: the torus touches it
  auto f = [&](double t) { return torusImplicit(ray.o + t * ray.d, R, r); };
  double t0 = tA, f0 = f(tA);
  for (int i = 1; i <= kTorusSamples; ++i) {
    double t1 = tA + (tB - tA) * i / kTorusSamples, f1 = f(t1);
    if ((f0 < 0.0) != (f1 < 0.0)) {
      double lo = t0, hi = t1;
      for (int k = 0; k < 200; ++k) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        if ((f(mid) < 0.0) == (f0 < 0.0)) lo = mid; else hi = mid;
      }
      double t = 0.5 * (lo + hi);
      dvec3 p = ray.o + t * ray.d;
      dvec3 normal = (dot(p, p) + R * R - r * r) * p - 2.0 * R * R * dvec3(p.x, 0.0, p.z);
      consider(best, ray, t, normal, INFINITY);
      if (best.hit) return best;
    }
    t0 = t1;
    f0 = f1;
  }
  return best;
}

inline RefHit refPlane(const RefRay& ray, bool infinite) {
  RefHit best;
  if (ray.d.y == 0.0) return best;
  double t = -ray.o.y / ray.d.y;
  dvec3 p = ray.o + t * ray.d;
  double feature = infinite ? INFINITY : std::min(1.0 - std::abs(p.x), 1.0 - std::abs(p.z));
  if (feature >= 0.0) consider(best, ray, t, dvec3(0.0, 1.0, 0.0), feature);
  return best;
}

inline RefHit reference(const Shape& shape, const RefRay& ray) {
  switch (shape.kind) {
    case Kind::Sphere: return refSphere(ray);
    case Kind::Box: return refBox(ray);
    case Kind::Cylinder: return refCylinder(ray);
    case Kind::Cone: return refCone(ray);
    case Kind::Torus: return refTorus(ray, shape.radii.x, shape.radii.y);
    case Kind::Plane: return refPlane(ray, false);
    case Kind::InfinitePlane: return refPlane(ray, true);
  }
  return {};
}

inline RefRay toRef(const Ray& ray, float tMin, float tMax) {
  return {dvec3(ray.origin), dvec3(ray.dir), double(tMin), double(tMax)};
}

// Signed distance to the solid (exact for sphere, box, cylinder and ring torus; for the cone the larger of
// the distances to the base plane and to the infinite cone, and for a spindle torus the larger of the
// distances to its two sheets: these have the right sign and are within a small factor of the distance).
inline double signedDistance(const Shape& shape, dvec3 p) {
  switch (shape.kind) {
    case Kind::Sphere: return length(p) - 1.0;
    case Kind::Box: {
      dvec3 q = abs(p) - 1.0;
      return length(max(q, 0.0)) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
    }
    case Kind::Cylinder: {
      dvec2 q(std::hypot(p.x, p.z) - 1.0, std::abs(p.y) - 1.0);
      return std::min(std::max(q.x, q.y), 0.0) + length(max(q, 0.0));
    }
    case Kind::Cone: return std::max(-(p.y + 1.0), (2.0 * std::hypot(p.x, p.z) - (1.0 - p.y)) / std::sqrt(5.0));
    case Kind::Torus: {
      // Inside the tube and outside the inner "lemon" sheet that f = 0 also has when r > R (the points
      // within r of the core circle mirrored through the axis); for a ring torus the second term never wins.
      const double R = shape.radii.x, r = shape.radii.y, rho = std::hypot(p.x, p.z);
      return std::max(std::hypot(rho - R, p.y) - r, r - std::hypot(rho + R, p.y));
    }
    case Kind::Plane:
    case Kind::InfinitePlane: break;
  }
  return INFINITY;
}

// How close the ray comes to touching a closed shape without crossing its surface: the smallest |value| of
// a local minimum of the signed distance along the ray, over (tMin, tMax) inside the bounding sphere.
// Near 0 for tangent rays (either side) and for rays passing an edge; large for rays that cross cleanly.
inline double grazingMargin(const Shape& shape, const RefRay& ray) {
  constexpr int kSamples = 2048;
  double tA, tB;
  if (!refSphereInterval(ray, shape.boundingRadius() * 1.01, tA, tB)) return INFINITY;
  auto g = [&](double t) { return signedDistance(shape, ray.o + t * ray.d); };
  double margin = INFINITY;
  double h = (tB - tA) / kSamples;
  double gPrev = g(tA), gCur = g(tA + h);
  for (int i = 1; i < kSamples; ++i) {
    double gNext = g(tA + (i + 1) * h);
    if (gCur <= gPrev && gCur <= gNext) {  // a local minimum lies in (t_{i-1}, t_{i+1}): golden section
      double lo = tA + (i - 1) * h, hi = tA + (i + 1) * h;
      const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
      for (int k = 0; k < 80; ++k) {
        double m1 = hi - phi * (hi - lo), m2 = lo + phi * (hi - lo);
        if (g(m1) < g(m2)) hi = m2; else lo = m1;
      }
      margin = std::min(margin, std::abs(g(0.5 * (lo + hi))));
    }
    gPrev = gCur;
    gCur = gNext;
  }
  return margin;
}

// ---------------------------------------------------------------------------------------------------------
// Property checking against the reference
// ---------------------------------------------------------------------------------------------------------
struct Stats {
  int rays = 0, hits = 0, graze = 0, checkedT = 0;
  double maxPosition = 0.0, maxNormal = 0.0;  // in units of eps * L / max(|cos i|, kMinCos)
  double maxApex = 0.0;                        // in units of sqrt(eps) * L
  double maxGrazing = 0.0;  // largest grazing margin that explained a disagreement, in units of eps * L
};

inline std::string fmt(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", x);
  return text;
}

inline bool finite(vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Checks the result `h` of one ray (from the C++ mirror or from the GLSL run on the GPU); returns an empty
// string when it passes, else a description of the failure.
inline std::string checkHit(const Shape& shape, const Ray& ray, float tMin, float tMax, const Hit& h, Stats& stats) {
  ++stats.rays;
  RefRay ref = toRef(ray, tMin, tMax);
  RefHit r = reference(shape, ref);
  const double S = shape.boundingRadius();
  const double dLen = length(ref.d);
  const double L = std::max({S, length(ref.o), r.hit ? std::abs(r.t) * dLen : 0.0});
  const double band = kGrazeBand * kEps * L;
  std::ostringstream what;
  what.precision(9);
  what << kindName(shape.kind) << " o=(" << ray.origin.x << ", " << ray.origin.y << ", " << ray.origin.z
       << ") d=(" << ray.dir.x << ", " << ray.dir.y << ", " << ray.dir.z << ") tMin=" << tMin << " tMax=" << tMax
       << ": got " << (h.hit ? "hit t=" + fmt(h.t) : std::string("miss")) << ", reference "
       << (r.hit ? "hit t=" + fmt(r.t) : std::string("miss"));

  if (h.hit) {
    ++stats.hits;
    if (!std::isfinite(h.t) || !finite(h.normal) || !(dot(h.normal, h.normal) > 0.0f))
      return what.str() + ": non-finite t or bad normal";
    if (!(h.uv.x >= 0.0f && h.uv.x <= 1.0f && h.uv.y >= 0.0f && h.uv.y <= 1.0f))
      return what.str() + ": uv out of [0,1]^2";
    if (!(h.t > tMin && h.t < tMax)) return what.str() + ": t outside (tMin, tMax)";
  }
  // Is a disagreement with the reference explained by grazing?
  auto grazing = [&]() {
    for (const double t : {double(h.t), r.t}) {  // a root within the band of tMin or tMax
      if (std::abs(t - ref.tMin) * dLen <= band || std::abs(t - ref.tMax) * dLen <= band) return true;
    }
    if (shape.kind == Kind::Plane || shape.kind == Kind::InfinitePlane) {
      // An open surface: the only grazing is the crossing point lying near the square's border.
      dvec3 p = ref.o + (-ref.o.y / ref.d.y) * ref.d;
      return shape.kind == Kind::Plane &&
             std::abs(std::max(std::abs(p.x), std::abs(p.z)) - 1.0) <= band / S;
    }
    const double margin = grazingMargin(shape, ref);
    if (!(margin <= band)) return false;
    stats.maxGrazing = std::max(stats.maxGrazing, margin / (kEps * L));
    return true;
  };
  if (h.hit != r.hit) {
    if (!grazing()) return what.str() + ": hit/miss differs and the ray is not grazing";
    ++stats.graze;
    return {};
  }
  if (!h.hit) return {};
  const double cosI = std::abs(dot(normalize(r.normal), ref.d / dLen));
  const double scaleErr = kEps * L / std::max(cosI, kMinCos);
  const double position = std::abs(double(h.t) - r.t) * dLen / scaleErr;
  const double angle = std::acos(std::clamp(dot(normalize(dvec3(h.normal)), normalize(r.normal)), -1.0, 1.0));
  const double normalErr = angle * shape.curvatureRadius(ref.o + r.t * ref.d) / scaleErr;
  if (r.apex < kApexZone) {  // the cone's apex: a near-double root, good to ~sqrt(eps) only
    const double apexErr = std::abs(double(h.t) - r.t) * dLen / (std::sqrt(kEps) * L);
    stats.maxApex = std::max(stats.maxApex, apexErr);
    if (apexErr > kApexBound && !grazing()) {
      what << ": position error near the apex " << apexErr << " sqrt(eps)*L (bound " << kApexBound << ")";
      return what.str();
    }
    return {};
  }
  if (position > kPositionBound) {  // a different root (or face) than the reference
    if (!grazing()) {
      what << ": position error " << position << " eps*L/cos (bound " << kPositionBound << ")";
      return what.str();
    }
    ++stats.graze;
    return {};
  }
  if (cosI < kMinCos) return {};  // grazing incidence: only hit/miss and the root choice are checked
  ++stats.checkedT;
  stats.maxPosition = std::max(stats.maxPosition, position);
  if (r.feature > band / S * 4.0) {  // away from edges, where either face's normal is right
    stats.maxNormal = std::max(stats.maxNormal, normalErr);
    if (normalErr > kNormalBound) {
      what << ": normal error " << normalErr << " eps*L/(rho cos) (bound " << kNormalBound << ")";
      return what.str();
    }
  }
  return {};
}

inline std::string checkRay(const Shape& shape, const Ray& ray, float tMin, float tMax, Stats& stats) {
  return checkHit(shape, ray, tMin, tMax, trace(shape, ray, tMin, tMax), stats);
}

// ---------------------------------------------------------------------------------------------------------
// Randomised property test against the double-precision reference
// ---------------------------------------------------------------------------------------------------------
struct RandomConfig {
  const char* name;
  double distance;  // origin distance from the centre in bounding radii (0: inside the bounding box)
  double scale;     // direction length (the object transform's inverse scale)
};

struct Case {
  Ray ray;
  float tMin, tMax;
};

inline std::vector<Case> randomCases(const Shape& shape, const RandomConfig& config, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  const double S = shape.boundingRadius();
  auto randomDirection = [&]() {
    dvec3 v;
    do v = draw3<dvec3>(u, rng); while (dot(v, v) > 1.0 || dot(v, v) < 1e-4);
    return normalize(v);
  };
  // Points near the shape (its bounding box slightly enlarged; for the torus a shell around the tube): the
  // aim points of outside rays and the origins of "inside" rays, so rays hit, miss and graze.
  const bool flat = shape.kind == Kind::Plane || shape.kind == Kind::InfinitePlane;
  auto nearPoint = [&](double yHalf) {
    if (shape.kind != Kind::Torus) return dvec3(1.05, yHalf, 1.05) * draw3<dvec3>(u, rng);
    double phi = 2.0 * glm::pi<double>() * u01(rng);
    return double(shape.radii.x) * dvec3(std::cos(phi), 0.0, std::sin(phi)) +
           1.3 * double(shape.radii.y) * u01(rng) * randomDirection();
  };
  std::vector<Case> cases;
  for (int i = 0; i < count; ++i) {
    dvec3 aim = nearPoint(flat ? 0.0 : 1.05);
    dvec3 origin = config.distance > 0.0 ? config.distance * S * (1.0 + u01(rng)) * randomDirection()
                                         : nearPoint(1.05);
    dvec3 dir = config.distance > 0.0 ? normalize(aim - origin) : randomDirection();
    dir *= config.scale * std::exp(std::log(2.0) * u(rng));  // length in [scale/2, 2 scale]
    // Mostly (0, inf); sometimes an interval starting or ending somewhere along the way.
    float tMin = 0.0f, tMax = kInf;
    const double tAim = length(aim - origin) / length(dir);
    if (u01(rng) < 0.2) tMin = float(tAim * u01(rng) * 1.5);
    if (u01(rng) < 0.2) tMax = float(tAim * (0.5 + u01(rng)));
    cases.push_back({Ray{vec3(origin), vec3(dir)}, tMin, tMax});
  }
  return cases;
}

const RandomConfig kRandomConfigs[] = {
    {"near", 2.0, 1.0},       {"inside", 0.0, 1.0},    {"far 1e4", 1e4, 1.0},
    {"scale 1e-3", 2.0, 1e3}, {"scale 1e3", 2.0, 1e-3}, {"far 1e4 scale 1e-3", 1e4, 1e3},
};

inline std::vector<Shape> randomShapes(Kind kind) {
  if (kind != Kind::Torus) return {Shape{kind}};
  // Ring tori from fat to thin (r = R / 100), and a spindle torus (r > R).
  return {Shape{kind, vec2(1.0f, 0.25f)}, Shape{kind, vec2(1.0f, 0.6f)}, Shape{kind, vec2(3.0f, 0.1f)},
          Shape{kind, vec2(1.0f, 0.01f)}, Shape{kind, vec2(0.4f, 0.5f)}};
}

inline void printStats(const Shape& shape, const char* config, const Stats& stats) {
  char label[48];
  if (shape.kind == Kind::Torus) {
    std::snprintf(label, sizeof label, "torus %.2f/%.2f", shape.radii.x, shape.radii.y);
  } else {
    std::snprintf(label, sizeof label, "%s", kindName(shape.kind));
  }
  std::printf("%-16s %-20s rays %5d hits %5d grazing %3d (margin <= %5.1f eps*L) | max errors: position "
              "%5.2f, normal %5.2f (eps*L/cos)\n",
              label, config, stats.rays, stats.hits, stats.graze, stats.maxGrazing, stats.maxPosition,
              stats.maxNormal);
}

}  // namespace bvhlab::primtest
