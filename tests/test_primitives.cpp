// Tests of the analytic ray–primitive intersections: the C++ mirrors (shaders/primitives.hpp) against
// hand-computed cases and a double-precision reference written here independently (per-surface candidates
// for the quadrics and box, dense sign sampling + bisection for the torus); the GLSL (shaders/prim_*.glsl)
// compiled offline by glslangValidator, checked statement by statement against the mirror, and run on the
// GL device (a compute shader; llvmpipe here) through the same random property test.
//
// Error model (what the bounds below are stated in). Positions are float, so the hit point cannot be
// better than a few ulps of the largest of the object's size S (bounding radius), the origin's distance |o|
// and the hit's distance: L = max(S, |o|, t |d|). With eps = 2^-23 (float epsilon):
//   position error  |t - t_ref| |d|        <= kPositionBound * eps * L / max(|cos i|, kMinCos)
//   normal error    angle(n, n_ref) * rho  <= kNormalBound   * eps * L / max(|cos i|, kMinCos)
// where i is the angle of incidence (error grows as 1/cos i for grazing hits, and is only checked for
// |cos i| >= kMinCos, i.e. incidence below ~87 degrees) and rho the smallest radius of curvature (the
// torus's minor radius, else 1). Near the cone's apex see kApexZone. Hit/miss (and which root) may differ
// from the reference only for GRAZING rays: the ray passes within kGrazeBand * eps * L of touching the
// surface without crossing it (a tangent, an edge, a spindle torus's pinch), or its hit lies within that
// distance of tMin/tMax.
// Measured (random rays, all kinds, origins at 2-4 S, inside, and at 1e4 S; |d| from 5e-4 to 2e3): position
// error <= 2.2 (15.7 for a torus with r = R/100 seen from 1e4), normal error <= 12, disagreements explained
// by grazing within 0.1 eps*L, <= 0.4% of rays. The bounds leave a margin of >= 4x.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>

#include <glad/gl.h>

#include "gl_compute.hpp"
#include "render/gl_context.hpp"
#include "shaders/primitives.hpp"
#include "require.hpp"

namespace {

using bvhlab::glsl::Ray;
using bvhlab::test::compileCompute;
using bvhlab::test::dispatchCompute;
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
const char* kindName(Kind k) {
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
  // Smallest radius of curvature away from edges and the cone's apex: a position error dp tilts the normal
  // by about dp / curvatureRadius.
  double curvatureRadius() const { return kind == Kind::Torus ? double(radii.y) : 1.0; }
};

struct Hit {
  bool hit = false;
  float t = 0.0f;
  vec3 normal{0.0f};
  vec2 uv{0.0f};
};

Hit trace(const Shape& shape, const Ray& ray, float tMin, float tMax) {
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

void consider(RefHit& best, const RefRay& ray, double t, dvec3 normal, double feature,
              double apex = INFINITY) {
  if (t > ray.tMin && t < ray.tMax && (!best.hit || t < best.t)) best = {true, t, normal, feature, apex};
}

// Real roots of a t^2 + 2 b t + c = 0 by the textbook formula (double has the digits to spare);
// a == 0: the linear root. Returns the count.
int refQuadratic(double a, double b, double c, double roots[2]) {
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

RefHit refSphere(const RefRay& ray) {
  RefHit best;
  double roots[2];
  int n = refQuadratic(dot(ray.d, ray.d), dot(ray.o, ray.d), dot(ray.o, ray.o) - 1.0, roots);
  for (int i = 0; i < n; ++i) consider(best, ray, roots[i], ray.o + roots[i] * ray.d, INFINITY);
  return best;
}

RefHit refBox(const RefRay& ray) {
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
void refCaps(RefHit& best, const RefRay& ray, bool top) {
  if (ray.d.y == 0.0) return;
  for (double side : {-1.0, 1.0}) {
    if (side > 0.0 && !top) continue;
    double t = (side - ray.o.y) / ray.d.y;
    dvec3 p = ray.o + t * ray.d;
    double r = std::hypot(p.x, p.z);
    if (r <= 1.0) consider(best, ray, t, dvec3(0.0, side, 0.0), 1.0 - r);
  }
}

RefHit refCylinder(const RefRay& ray) {
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

RefHit refCone(const RefRay& ray) {
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

double torusImplicit(dvec3 p, double R, double r) {
  double k = dot(p, p) + R * R - r * r;
  return k * k - 4.0 * R * R * (p.x * p.x + p.z * p.z);
}

// The ray's parameter interval inside the sphere |p| <= radius, clipped to (tMin, tMax). False if empty.
bool refSphereInterval(const RefRay& ray, double radius, double& tA, double& tB) {
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
RefHit refTorus(const RefRay& ray, double R, double r) {
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

RefHit refPlane(const RefRay& ray, bool infinite) {
  RefHit best;
  if (ray.d.y == 0.0) return best;
  double t = -ray.o.y / ray.d.y;
  dvec3 p = ray.o + t * ray.d;
  double feature = infinite ? INFINITY : std::min(1.0 - std::abs(p.x), 1.0 - std::abs(p.z));
  if (feature >= 0.0) consider(best, ray, t, dvec3(0.0, 1.0, 0.0), feature);
  return best;
}

RefHit reference(const Shape& shape, const RefRay& ray) {
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

RefRay toRef(const Ray& ray, float tMin, float tMax) {
  return {dvec3(ray.origin), dvec3(ray.dir), double(tMin), double(tMax)};
}

// Signed distance to the solid (exact for sphere, box, cylinder and ring torus; for the cone the larger of
// the distances to the base plane and to the infinite cone, and for a spindle torus the larger of the
// distances to its two sheets: these have the right sign and are within a small factor of the distance).
double signedDistance(const Shape& shape, dvec3 p) {
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
double grazingMargin(const Shape& shape, const RefRay& ray) {
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

std::string fmt(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", x);
  return text;
}

bool finite(vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Checks the result `h` of one ray (from the C++ mirror or from the GLSL run on the GPU); returns an empty
// string when it passes, else a description of the failure.
std::string checkHit(const Shape& shape, const Ray& ray, float tMin, float tMax, const Hit& h, Stats& stats) {
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
  const double normalErr = angle * shape.curvatureRadius() / scaleErr;
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

std::string checkRay(const Shape& shape, const Ray& ray, float tMin, float tMax, Stats& stats) {
  return checkHit(shape, ray, tMin, tMax, trace(shape, ray, tMin, tMax), stats);
}

// ---------------------------------------------------------------------------------------------------------
// Directed cases
// ---------------------------------------------------------------------------------------------------------
const Shape kSphere{Kind::Sphere};
const Shape kBox{Kind::Box};
const Shape kCylinder{Kind::Cylinder};
const Shape kCone{Kind::Cone};
const Shape kTorus{Kind::Torus, vec2(1.0f, 0.25f)};
const Shape kPlane{Kind::Plane};
const Shape kInfinitePlane{Kind::InfinitePlane};
const Shape kAllShapes[] = {kSphere, kBox, kCylinder, kCone, kTorus, kPlane, kInfinitePlane};

// The hit must exist with t within `tol` of `t` and the unit normal within `tol` of `normal` (unit).
void expectHit(const Shape& shape, Ray ray, float tMin, float tMax, float t, vec3 normal, float tol = 1e-5f) {
  Hit h = trace(shape, ray, tMin, tMax);
  SCOPED_TRACE(kindName(shape.kind));
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.t, t, tol * std::max(1.0f, std::abs(t)));
  vec3 n = normalize(h.normal);
  EXPECT_NEAR(n.x, normal.x, tol);
  EXPECT_NEAR(n.y, normal.y, tol);
  EXPECT_NEAR(n.z, normal.z, tol);
  EXPECT_TRUE(h.uv.x >= 0.0f && h.uv.x <= 1.0f && h.uv.y >= 0.0f && h.uv.y <= 1.0f);
  // The reference agrees (a cross-check of the hand-computed expectation too).
  RefHit r = reference(shape, toRef(ray, tMin, tMax));
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, t, 1e-7 * std::max(1.0, std::abs(double(t))));  // t is a float
}

void expectMiss(const Shape& shape, Ray ray, float tMin = 0.0f, float tMax = kInf) {
  SCOPED_TRACE(kindName(shape.kind));
  EXPECT_FALSE(trace(shape, ray, tMin, tMax).hit);
  EXPECT_FALSE(reference(shape, toRef(ray, tMin, tMax)).hit);
}

TEST(Sphere, HeadOnMissInsideAndInterval) {
  expectHit(kSphere, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, kInf, 4.0f, vec3(0, 0, 1));
  expectHit(kSphere, {vec3(0, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf, 4.0f, vec3(0, 1, 0));  // pole: atan(0,0)
  expectMiss(kSphere, {vec3(0, 2, 5), vec3(0, 0, -1)});
  expectMiss(kSphere, {vec3(0, 0, 5), vec3(0, 0, 1)});  // pointing away
  // From inside: the far side, normal still outward.
  expectHit(kSphere, {vec3(0, 0, 0), vec3(1, 0, 0)}, 0.0f, kInf, 1.0f, vec3(1, 0, 0));
  expectHit(kSphere, {vec3(0.5f, 0, 0), vec3(-1, 0, 0)}, 0.0f, kInf, 1.5f, vec3(-1, 0, 0));
  // tMin skips the near root; tMax cuts the far one.
  expectHit(kSphere, {vec3(0, 0, 5), vec3(0, 0, -1)}, 4.5f, kInf, 6.0f, vec3(0, 0, -1));
  expectMiss(kSphere, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, 3.9f);
  expectMiss(kSphere, {vec3(0, 0, 5), vec3(0, 0, -1)}, 6.1f, kInf);
}

TEST(Sphere, UvIsLongitudeLatitude) {
  Hit h = trace(kSphere, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, kInf);  // +Z: the centre of the map
  EXPECT_NEAR(h.uv.x, 0.5f, 1e-6f);
  EXPECT_NEAR(h.uv.y, 0.5f, 1e-6f);
  h = trace(kSphere, {vec3(5, 0, 0), vec3(-1, 0, 0)}, 0.0f, kInf);  // +X: a quarter turn to the right
  EXPECT_NEAR(h.uv.x, 0.75f, 1e-6f);
  h = trace(kSphere, {vec3(0, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf);  // north pole
  EXPECT_NEAR(h.uv.y, 1.0f, 1e-6f);
  h = trace(kSphere, {vec3(0, -5, 0), vec3(0, 1, 0)}, 0.0f, kInf);  // south pole
  EXPECT_NEAR(h.uv.y, 0.0f, 1e-6f);
}

TEST(Sphere, FarOriginKeepsPrecision) {
  // 1e4 radii away (a 1e-3-scaled sphere seen from 10 units): t is within a few float ulps of the truth.
  for (vec3 offset : {vec3(0, 0, 0), vec3(0.5f, 0.3f, 0), vec3(0.7f, -0.7f, 0)}) {
    Ray ray{vec3(offset.x, offset.y, 1e4f), vec3(0, 0, -1)};
    Hit h = trace(kSphere, ray, 0.0f, kInf);
    ASSERT_TRUE(h.hit);
    double exact = 1e4 - std::sqrt(1.0 - double(offset.x) * offset.x - double(offset.y) * offset.y);
    EXPECT_LE(std::abs(h.t - exact) / exact, 4.0 * kEps) << "offset " << offset.x << "," << offset.y;
  }
}

// The textbook float solution (b^2 - a c from the raw origin) for contrast: at 1e4 it loses every digit of
// the discriminant, which is what the closest-approach shift in prim_sphere.glsl avoids.
TEST(Sphere, NaiveQuadraticFailsWhereTheShiftDoesNot) {
  Ray ray{vec3(0.6f, 0.0f, 1e4f), vec3(0, 0, -1)};
  float a = dot(ray.dir, ray.dir), b = dot(ray.origin, ray.dir), c = dot(ray.origin, ray.origin) - 1.0f;
  float naive = (-b - std::sqrt(b * b - a * c)) / a;
  double exact = 1e4 - 0.8;
  Hit h = trace(kSphere, ray, 0.0f, kInf);
  ASSERT_TRUE(h.hit);
  double naiveErr = std::abs(naive - exact), err = std::abs(h.t - exact);
  std::printf("far sphere (1e4): |t - exact| naive %.3g, shifted %.3g\n", naiveErr, err);
  EXPECT_GT(naiveErr, 100.0 * err);
}

TEST(Box, HeadOnFacesEdgesAndInside) {
  expectHit(kBox, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, kInf, 4.0f, vec3(0, 0, 1));
  expectHit(kBox, {vec3(-5, 0.5f, 0.5f), vec3(1, 0, 0)}, 0.0f, kInf, 4.0f, vec3(-1, 0, 0));
  expectHit(kBox, {vec3(0.3f, -5, 0.2f), vec3(0, 1, 0)}, 0.0f, kInf, 4.0f, vec3(0, -1, 0));
  expectHit(kBox, {vec3(0, 0, 0), vec3(0, 1, 0)}, 0.0f, kInf, 1.0f, vec3(0, 1, 0));  // inside
  expectHit(kBox, {vec3(0, 0, 5), vec3(0, 0, -1)}, 4.5f, kInf, 6.0f, vec3(0, 0, -1));
  expectMiss(kBox, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, 3.5f);
  expectMiss(kBox, {vec3(0, 1.5f, 5), vec3(0, 0, -1)});
  expectMiss(kBox, {vec3(3, 0, 0), vec3(0, 1, 1)});
}

TEST(Box, ParallelToFacesHasNoNaNTrap) {
  // Direction components of exactly 0 with the origin exactly on the slab plane: 1/0 * 0 would be NaN.
  expectHit(kBox, {vec3(-5, 1, 0), vec3(1, 0, 0)}, 0.0f, kInf, 4.0f, vec3(-1, 0, 0));
  expectHit(kBox, {vec3(-5, -1, 1), vec3(1, 0, 0)}, 0.0f, kInf, 4.0f, vec3(-1, 0, 0));
  expectMiss(kBox, {vec3(-5, 1.0001f, 0), vec3(1, 0, 0)});
  expectMiss(kBox, {vec3(1.5f, 5, 0), vec3(0, -1, 0)});
  // Along the face plane from inside the plane of the top face: leaves through the +X face.
  expectHit(kBox, {vec3(0, 1, 0), vec3(1, 0, 0)}, 0.0f, kInf, 1.0f, vec3(1, 0, 0));
}

TEST(Box, UvPerFace) {
  // Every face seen from outside head-on through its centre maps to (0.5, 0.5); off-centre points move u
  // to the right and v up.
  const vec3 axes[] = {vec3(1, 0, 0), vec3(-1, 0, 0), vec3(0, 1, 0), vec3(0, -1, 0), vec3(0, 0, 1), vec3(0, 0, -1)};
  for (vec3 n : axes) {
    Hit h = trace(kBox, {5.0f * n, -n}, 0.0f, kInf);
    ASSERT_TRUE(h.hit);
    EXPECT_NEAR(h.uv.x, 0.5f, 1e-6f);
    EXPECT_NEAR(h.uv.y, 0.5f, 1e-6f);
  }
  Hit h = trace(kBox, {vec3(0.5f, 0.5f, 5), vec3(0, 0, -1)}, 0.0f, kInf);  // +Z face, upper right
  EXPECT_NEAR(h.uv.x, 0.75f, 1e-6f);
  EXPECT_NEAR(h.uv.y, 0.75f, 1e-6f);
  h = trace(kBox, {vec3(0.5f, 0.5f, -5), vec3(0, 0, 1)}, 0.0f, kInf);  // -Z face seen from behind: x is left
  EXPECT_NEAR(h.uv.x, 0.25f, 1e-6f);
}

TEST(Cylinder, SideCapsAxisParallelAndInside) {
  expectHit(kCylinder, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, kInf, 4.0f, vec3(0, 0, 1));
  expectHit(kCylinder, {vec3(0, 0, 5), vec3(0, 0, -1)}, 4.5f, kInf, 6.0f, vec3(0, 0, -1));
  // Parallel to the axis (a == 0): caps only, decided without dividing by a.
  expectHit(kCylinder, {vec3(0, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf, 4.0f, vec3(0, 1, 0));
  expectHit(kCylinder, {vec3(0.5f, -5, 0.5f), vec3(0, 1, 0)}, 0.0f, kInf, 4.0f, vec3(0, -1, 0));
  expectHit(kCylinder, {vec3(0.5f, -5, 0.5f), vec3(0, 1, 0)}, 4.5f, kInf, 6.0f, vec3(0, 1, 0));
  expectHit(kCylinder, {vec3(1, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf, 4.0f, vec3(0, 1, 0));  // on the wall
  expectMiss(kCylinder, {vec3(1.01f, 5, 0), vec3(0, -1, 0)});
  // Parallel to the caps.
  expectHit(kCylinder, {vec3(-5, 0.9f, 0), vec3(1, 0, 0)}, 0.0f, kInf, 4.0f, vec3(-1, 0, 0));
  expectMiss(kCylinder, {vec3(-5, 1.1f, 0), vec3(1, 0, 0)});
  // From inside: side and caps, normals outward.
  expectHit(kCylinder, {vec3(0, 0, 0), vec3(1, 0, 0)}, 0.0f, kInf, 1.0f, vec3(1, 0, 0));
  expectHit(kCylinder, {vec3(0, 0, 0), vec3(0, -2, 0)}, 0.0f, kInf, 0.5f, vec3(0, -1, 0));
  expectMiss(kCylinder, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, 3.9f);
}

TEST(Cone, SideBaseApexAndInside) {
  // Side at y = 0 (radius 0.5): the normal leans up by the slope (radius/height = 1/2).
  expectHit(kCone, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, kInf, 4.5f, normalize(vec3(0, 1, 2)));
  expectHit(kCone, {vec3(0, 0, 5), vec3(0, 0, -1)}, 5.0f, kInf, 5.5f, normalize(vec3(0, 1, -2)));
  expectHit(kCone, {vec3(0, -5, 0), vec3(0, 1, 0)}, 0.0f, kInf, 4.0f, vec3(0, -1, 0));
  expectMiss(kCone, {vec3(0, 0.5f, 5), vec3(0.2f, 0, -1)});
  expectMiss(kCone, {vec3(0, 1.0001f, 5), vec3(0, 0, -1)});  // just above the apex
  // Down the axis through the apex (A < 0, a double root at the apex): hit at the apex, normal +Y; then
  // the base from inside.
  expectHit(kCone, {vec3(0, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf, 4.0f, vec3(0, 1, 0));
  expectHit(kCone, {vec3(0, 5, 0), vec3(0, -1, 0)}, 4.5f, kInf, 6.0f, vec3(0, -1, 0));
  // Up the axis from below: base, then the apex from inside.
  expectHit(kCone, {vec3(0, -5, 0), vec3(0, 1, 0)}, 4.5f, kInf, 6.0f, vec3(0, 1, 0));
  // A steep ray through the apex at an angle, leaving through the base.
  expectHit(kCone, {vec3(-0.5f, 3, 0), vec3(0.5f, -2, 0)}, 0.0f, kInf, 1.0f, vec3(0, 1, 0));
  expectHit(kCone, {vec3(-0.5f, 3, 0), vec3(0.5f, -2, 0)}, 1.5f, kInf, 2.0f, vec3(0, -1, 0));
  // From inside.
  expectHit(kCone, {vec3(0, -0.5f, 0), vec3(1, 0, 0)}, 0.0f, kInf, 0.75f, normalize(vec3(2, 1, 0)));
}

TEST(Cone, ParallelToAGenerator) {
  // A == 0: the quadratic degenerates to a line (the branch that avoids q / A). The generator through
  // (0.5, 0, 0) has direction (1, -2, 0). Shifted inwards by 0.1 in x the line enters through the opposite
  // side (x = -(1 - y) / 2 at s = 1.05) and leaves through the base (s = 2); shifted outwards it misses.
  Ray inner{vec3(-1.1f, 3, 0), vec3(1, -2, 0)};  // x = -1.1 + s, y = 3 - 2 s
  Hit h = trace(kCone, inner, 0.0f, kInf);
  RefHit r = reference(kCone, toRef(inner, 0.0f, kInf));
  ASSERT_TRUE(h.hit);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(h.t, r.t, 1e-5);
  EXPECT_GT(h.normal.y, 0.0f);  // the side, seen from above
  Hit exit = trace(kCone, inner, h.t + 0.01f, kInf);
  ASSERT_TRUE(exit.hit);
  EXPECT_NEAR(exit.t, 2.0f, 1e-5f);  // y = -1
  EXPECT_EQ(normalize(exit.normal), vec3(0, -1, 0));
  EXPECT_NEAR(h.t, 1.05f, 1e-5f);
  expectMiss(kCone, {vec3(-0.9f, 3, 0), vec3(1, -2, 0)});   // outside, parallel
  expectMiss(kCone, {vec3(-1.1f, 3, 0), vec3(-1, 2, 0)});   // inner line, moving away
}

TEST(Torus, AxisAndTheFourRoots) {
  // Down the axis: through the hole.
  expectMiss(kTorus, {vec3(0, 5, 0), vec3(0, -1, 0)});
  // Down the axis offset to the tube's centre line: top, then bottom (from inside).
  expectHit(kTorus, {vec3(1, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf, 4.75f, vec3(0, 1, 0));
  expectHit(kTorus, {vec3(1, 5, 0), vec3(0, -1, 0)}, 5.0f, kInf, 5.25f, vec3(0, -1, 0));
  // Across the plane through the centre: four roots in order, with alternating outward normals.
  Ray across{vec3(-5, 0, 0), vec3(1, 0, 0)};
  const float roots[] = {3.75f, 4.25f, 5.75f, 6.25f};
  const vec3 normals[] = {vec3(-1, 0, 0), vec3(1, 0, 0), vec3(-1, 0, 0), vec3(1, 0, 0)};
  float tMin = 0.0f;
  for (int i = 0; i < 4; ++i) {
    expectHit(kTorus, across, tMin, kInf, roots[i], normals[i]);
    tMin = roots[i] + 0.1f;
  }
  expectMiss(kTorus, across, tMin, kInf);
  expectMiss(kTorus, across, 0.0f, 3.7f);
  // Parallel to the axis just outside the tube: miss.
  expectMiss(kTorus, {vec3(1.26f, 5, 0), vec3(0, -1, 0)});
}

TEST(Torus, ThroughTheHoleToTheFarSide) {
  // From the centre of the hole outward: the inner equator, normal pointing into the hole.
  expectHit(kTorus, {vec3(0, 0, 0), vec3(0, 0, 1)}, 0.0f, kInf, 0.75f, vec3(0, 0, -1));
  // From above the hole's plane, slanting down through the hole (crossing y = 0 at x = 0.5) to the inside
  // of the far tube below the plane (x ~ 0.763, y ~ -0.079).
  Ray slant{vec3(-0.5f, 0.3f, 0), vec3(1, -0.3f, 0)};
  Hit h = trace(kTorus, slant, 0.0f, kInf);
  RefHit r = reference(kTorus, toRef(slant, 0.0f, kInf));
  ASSERT_TRUE(r.hit);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.t, r.t, 1e-5 * r.t);
  vec3 p = slant.origin + h.t * slant.dir;
  EXPECT_GT(p.x, 0.5f);   // the far tube...
  EXPECT_LT(p.y, 0.0f);   // ...below the hole's plane
  EXPECT_LT(normalize(h.normal).y, 0.0f);
  // A thin torus and a spindle torus (r > R, self-intersecting) through the centre.
  for (vec2 radii : {vec2(2.0f, 0.01f), vec2(0.5f, 1.0f)}) {
    Shape shape{Kind::Torus, radii};
    Ray ray{vec3(-5, 0.001f, 0), vec3(1, 0, 0)};
    RefHit ref = reference(shape, toRef(ray, 0.0f, kInf));
    ASSERT_TRUE(ref.hit);
    expectHit(shape, ray, 0.0f, kInf, float(ref.t), normalize(vec3(ref.normal)), 1e-4f);
  }
}

TEST(Torus, UvAngles) {
  Hit h = trace(kTorus, {vec3(0, 0, 5), vec3(0, 0, -1)}, 0.0f, kInf);  // outer equator at +Z
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.uv.x, 0.5f, 1e-6f);
  EXPECT_NEAR(h.uv.y, 0.5f, 1e-6f);
  h = trace(kTorus, {vec3(1, 5, 0), vec3(0, -1, 0)}, 0.0f, kInf);  // top of the tube at +X
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.uv.x, 0.75f, 1e-6f);
  EXPECT_NEAR(h.uv.y, 0.75f, 1e-5f);
}

TEST(Plane, FiniteAndInfinite) {
  expectHit(kPlane, {vec3(0.2f, 5, -0.3f), vec3(0, -1, 0)}, 0.0f, kInf, 5.0f, vec3(0, 1, 0));
  expectHit(kPlane, {vec3(0.2f, -5, -0.3f), vec3(0, 2, 0)}, 0.0f, kInf, 2.5f, vec3(0, 1, 0));  // from below
  Hit h = trace(kPlane, {vec3(0.2f, 5, -0.3f), vec3(0, -1, 0)}, 0.0f, kInf);
  EXPECT_NEAR(h.uv.x, 0.6f, 1e-6f);
  EXPECT_NEAR(h.uv.y, 0.35f, 1e-6f);
  expectMiss(kPlane, {vec3(1.5f, 5, 0), vec3(0, -1, 0)});
  expectMiss(kPlane, {vec3(0, 0, 0), vec3(1, 0, 0)});  // in the plane, parallel
  expectMiss(kPlane, {vec3(0, 5, 0), vec3(0, -1, 0)}, 0.0f, 4.9f);
  expectMiss(kPlane, {vec3(0, 5, 0), vec3(0, -1, 0)}, 5.1f, kInf);
  // The infinite plane repeats the unit tile: x = 1.5 -> fract(1.25) = 0.25.
  expectHit(kInfinitePlane, {vec3(1.5f, 5, -2.5f), vec3(0, -1, 0)}, 0.0f, kInf, 5.0f, vec3(0, 1, 0));
  h = trace(kInfinitePlane, {vec3(1.5f, 5, -2.5f), vec3(0, -1, 0)}, 0.0f, kInf);
  EXPECT_NEAR(h.uv.x, 0.25f, 1e-6f);
  EXPECT_NEAR(h.uv.y, 0.25f, 1e-6f);  // z = -2.5 -> fract(-0.75) = 0.25
  expectMiss(kInfinitePlane, {vec3(0, 1, 0), vec3(1, 0, 0)});
}

// ---------------------------------------------------------------------------------------------------------
// Cross-cutting properties
// ---------------------------------------------------------------------------------------------------------
TEST(AllKinds, NanAndDegenerateInputsMiss) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Ray bad[] = {
      {vec3(nan, 0, 5), vec3(0, 0, -1)}, {vec3(0, 0, 5), vec3(0, nan, -1)}, {vec3(0, 0, 5), vec3(0, 0, 0)},
      {vec3(0, 0, kInf), vec3(0, 0, -1)}, {vec3(0, 0, 5), vec3(0, 0, -kInf)},
  };
  for (const Shape& shape : kAllShapes) {
    for (const Ray& ray : bad) EXPECT_FALSE(trace(shape, ray, 0.0f, kInf).hit) << kindName(shape.kind);
    // A NaN interval end makes every comparison fail.
    EXPECT_FALSE(trace(shape, {vec3(0.1f, 5, 0.1f), vec3(0, -1, 0)}, nan, kInf).hit) << kindName(shape.kind);
    EXPECT_FALSE(trace(shape, {vec3(0.1f, 5, 0.1f), vec3(0, -1, 0)}, 0.0f, nan).hit) << kindName(shape.kind);
  }
  // Torus radii: a zero or negative minor radius is no torus.
  Hit h;
  EXPECT_FALSE(bvhlab::glsl::intersectTorus({vec3(1, 5, 0), vec3(0, -1, 0)}, vec2(1, 0), 0.0f, kInf, h.t,
                                            h.normal, h.uv));
  EXPECT_FALSE(bvhlab::glsl::intersectTorus({vec3(1, 5, 0), vec3(0, -1, 0)}, vec2(1, nan), 0.0f, kInf, h.t,
                                            h.normal, h.uv));
}

TEST(AllKinds, UnnormalisedDirectionGivesTheSameHitPoint) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int hits = 0;
  for (const Shape& shape : kAllShapes) {
    for (int i = 0; i < 200; ++i) {
      vec3 origin = 4.0f * normalize(vec3(u(rng), u(rng), u(rng)) + vec3(0, 0.01f, 0));
      vec3 dir = normalize(vec3(u(rng), u(rng), u(rng)) * 0.8f - origin);
      Hit unit = trace(shape, {origin, dir}, 0.0f, kInf);
      for (float scale : {1e-3f, 0.37f, 3.0f, 1e3f}) {
        Hit scaled = trace(shape, {origin, dir * scale}, 0.0f, kInf);
        RefHit ref = reference(shape, toRef({origin, dir * scale}, 0.0f, kInf));
        if (unit.hit != scaled.hit) {  // allowed only where the reference says the ray grazes
          ASSERT_LE(grazingMargin(shape, toRef({origin, dir}, 0.0f, kInf)), kGrazeBand * kEps * 4.0)
              << kindName(shape.kind) << " scale " << scale;
          continue;
        }
        if (!unit.hit || ref.t * scale < 0.0) continue;
        ++hits;
        vec3 a = origin + unit.t * dir, b = origin + scaled.t * (dir * scale);
        double cosI = std::abs(dot(normalize(ref.normal), dvec3(dir)));
        if (cosI < kMinCos) continue;
        EXPECT_LE(length(a - b), kPositionBound * kEps * 4.0 / cosI) << kindName(shape.kind) << " scale " << scale;
      }
    }
  }
  EXPECT_GT(hits, 1000);
}

// Grazing families: rays tangent to each shape (or along its edges) offset by 0 and +-10^-k. No NaN, and
// agreement with the reference wherever the ray is outside the grazing band.
TEST(AllKinds, TangentAndGrazingRays) {
  struct Family {
    Shape shape;
    vec3 origin, dir, offsetAxis;
  };
  const Family families[] = {
      {kSphere, vec3(0, 1, 5), vec3(0, 0, -1), vec3(0, 1, 0)},           // tangent at the top
      {kBox, vec3(-5, 1, 1), vec3(1, 0, 0), vec3(0, 1, 0)},              // along an edge
      {kBox, vec3(-5, 4, 1), vec3(1, -1, 0), vec3(0, 1, 0)},             // through an edge, diagonally
      {kCylinder, vec3(1, 0, 5), vec3(0, 0, -1), vec3(1, 0, 0)},         // tangent to the side
      {kCylinder, vec3(-5, 1, 0), vec3(1, 0, 0), vec3(0, 1, 0)},         // along the top cap
      {kCylinder, vec3(1, 5, 0), vec3(0, -1, 0), vec3(1, 0, 0)},         // down the wall, axis-parallel
      {kCone, vec3(0, 1, 5), vec3(0, 0, -1), vec3(0, 1, 0)},             // over the apex
      {kCone, vec3(-0.5f, 3, 0), vec3(0.5f, -2, 0), vec3(1, 0, 0)},      // through the apex
      {kCone, vec3(-2.5f, 5, 0), vec3(1, -2, 0), vec3(1, 0, 0)},         // along a generator (A = 0)
      {kTorus, vec3(0, 0.25f, 5), vec3(0, 0, -1), vec3(0, 1, 0)},        // tangent to the top of the tube
      {kTorus, vec3(0.75f, 5, 0), vec3(0, -1, 0), vec3(1, 0, 0)},        // tangent to the inner equator
      {kTorus, vec3(1.25f, 0, 5), vec3(0, 0, -1), vec3(1, 0, 0)},        // tangent to the outer equator
      {kPlane, vec3(1, 5, 0), vec3(0, -1, 0), vec3(1, 0, 0)},            // the square's border
  };
  Stats stats;
  for (const Family& f : families) {
    for (float offset : {0.0f, 1e-7f, -1e-7f, 1e-5f, -1e-5f, 1e-3f, -1e-3f}) {
      for (float tilt : {0.0f, 1e-4f}) {
        Ray ray{f.origin + offset * f.offsetAxis, f.dir + tilt * vec3(0.3f, 0.5f, 0.7f)};
        std::string failure = checkRay(f.shape, ray, 0.0f, kInf, stats);
        EXPECT_TRUE(failure.empty()) << failure;
        // From the far side of the first hit too (the exit or a second contact).
        Hit h = trace(f.shape, ray, 0.0f, kInf);
        if (h.hit) {
          failure = checkRay(f.shape, ray, h.t * 1.0001f + 1e-4f, kInf, stats);
          EXPECT_TRUE(failure.empty()) << failure;
        }
      }
    }
  }
  std::printf("grazing families: %d rays, %d hits, %d explained by grazing (margin <= %.1f eps*L); max errors: "
              "position %.2f, normal %.2f (eps*L/cos), near the cone's apex %.2f (sqrt(eps)*L)\n",
              stats.rays, stats.hits, stats.graze, stats.maxGrazing, stats.maxPosition, stats.maxNormal,
              stats.maxApex);
  EXPECT_GT(stats.hits, 50);
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

std::vector<Case> randomCases(const Shape& shape, const RandomConfig& config, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  const double S = shape.boundingRadius();
  auto randomDirection = [&]() {
    dvec3 v;
    do v = dvec3(u(rng), u(rng), u(rng)); while (dot(v, v) > 1.0 || dot(v, v) < 1e-4);
    return normalize(v);
  };
  // Points near the shape (its bounding box slightly enlarged; for the torus a shell around the tube): the
  // aim points of outside rays and the origins of "inside" rays, so rays hit, miss and graze.
  const bool flat = shape.kind == Kind::Plane || shape.kind == Kind::InfinitePlane;
  auto nearPoint = [&](double yHalf) {
    if (shape.kind != Kind::Torus) return dvec3(1.05 * u(rng), yHalf * u(rng), 1.05 * u(rng));
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

std::vector<Shape> randomShapes(Kind kind) {
  if (kind != Kind::Torus) return {Shape{kind}};
  // Ring tori from fat to thin (r = R / 100), and a spindle torus (r > R).
  return {Shape{kind, vec2(1.0f, 0.25f)}, Shape{kind, vec2(1.0f, 0.6f)}, Shape{kind, vec2(3.0f, 0.1f)},
          Shape{kind, vec2(1.0f, 0.01f)}, Shape{kind, vec2(0.4f, 0.5f)}};
}

void printStats(const Shape& shape, const char* config, const Stats& stats) {
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

class RandomRays : public ::testing::TestWithParam<Kind> {};

TEST_P(RandomRays, AgreeWithDoublePrecisionReference) {
  const Kind kind = GetParam();
  const int count = kind == Kind::Torus ? 1000 : 4000;
  uint32_t seed = 1;
  for (const Shape& shape : randomShapes(kind)) {
    for (const RandomConfig& config : kRandomConfigs) {
      Stats stats;
      int failures = 0;
      for (const Case& c : randomCases(shape, config, count, seed++)) {
        std::string failure = checkRay(shape, c.ray, c.tMin, c.tMax, stats);
        if (!failure.empty() && ++failures <= 5) ADD_FAILURE() << config.name << ": " << failure;
      }
      EXPECT_EQ(failures, 0) << kindName(shape.kind) << " " << config.name;
      printStats(shape, config.name, stats);
      EXPECT_GT(stats.hits, stats.rays / 10) << "too few hits for the test to mean anything";
      EXPECT_LT(stats.graze, stats.rays / 50) << "grazing explains too much";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Primitives, RandomRays,
                         ::testing::Values(Kind::Sphere, Kind::Box, Kind::Cylinder, Kind::Cone, Kind::Torus,
                                           Kind::Plane, Kind::InfinitePlane),
                         [](const ::testing::TestParamInfo<Kind>& info) {
                           std::string name = kindName(info.param);
                           name.erase(std::remove(name.begin(), name.end(), ' '), name.end());
                           return name;
                         });

// ---------------------------------------------------------------------------------------------------------
// The GLSL itself: it compiles (glslangValidator), and run on the GPU (llvmpipe here) it passes the same
// property test as the mirror.
// ---------------------------------------------------------------------------------------------------------
std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const char* const kPrimitiveModules[] = {"prim_sphere.glsl", "prim_box.glsl", "prim_cylinder.glsl",
                                         "prim_cone.glsl",   "prim_torus.glsl", "prim_plane.glsl"};

// common.glsl + every prim_*.glsl, without #version.
std::string primitiveSources() {
  const std::filesystem::path shaders = std::filesystem::path(BVHLAB_SOURCE_DIR) / "shaders";
  std::string source = readText(shaders / "common.glsl");
  for (const char* name : kPrimitiveModules) {
    if (!std::filesystem::exists(shaders / name)) throw std::runtime_error(std::string("missing ") + name);
    source += '\n';
    source += readText(shaders / name);
  }
  return source;
}

TEST(Glsl, PrimitivesCompileWithGlslang) {
  if (std::system("glslangValidator --version > /dev/null 2>&1") != 0)
    BVHLAB_SKIP_OR_FAIL("glslangValidator is not on PATH (Debian: glslang-tools); GLSL not validated");
  namespace fs = std::filesystem;
  std::string source = "#version 450 core\n" + primitiveSources();
  source += R"(
layout(location = 0) out vec4 fragColor;
void main() {
  Ray ray = Ray(vec3(gl_FragCoord.xy * 0.01 - 1.0, 3.0), vec3(0.0, 0.0, -1.0));
  float t;
  vec3 n;
  vec2 uv;
  vec4 sum = vec4(0.0);
  if (intersectSphere(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectBox(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectCylinder(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectCone(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectTorus(ray, vec2(1.0, 0.25), 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectPlane(ray, false, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectPlane(ray, true, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  fragColor = sum;
}
)";
  const fs::path dir = fs::temp_directory_path() / ("bvhlab_prims_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "primitives.frag", log = dir / "glslang.log";
  std::ofstream(file) << source;
  const std::string command = "glslangValidator -S frag \"" + file.string() + "\" > \"" + log.string() + "\" 2>&1";
  const int rc = std::system(command.c_str());
  EXPECT_EQ(rc, 0) << readText(log);
  fs::remove_all(dir);
}

// The mirror reads like the GLSL: with comments dropped and the purely syntactic differences normalised
// (float suffixes, `inline`/`constexpr`, out parameters as references, swizzles as constructors, array
// initialisers), primitives.hpp holds the prim_*.glsl statements in the same order.
TEST(Glsl, MirrorMatchesTheGlslStatementByStatement) {
  const std::filesystem::path shaders = std::filesystem::path(BVHLAB_SOURCE_DIR) / "shaders";
  auto normalise = [](std::string line) {
    line = std::regex_replace(line, std::regex("//.*"), "");
    line = std::regex_replace(line, std::regex("(\\d)f\\b"), "$1");
    line = std::regex_replace(line, std::regex("\\binline "), "");
    line = std::regex_replace(line, std::regex("\\bconstexpr "), "const ");
    line = std::regex_replace(line, std::regex("(float|vec2|vec3)& (\\w+)"), "out $1 $2");
    line = std::regex_replace(line, std::regex("([\\w.]+)\\.xz\\b"), "vec2($1.x, $1.z)");
    line = std::regex_replace(line, std::regex("float\\[4\\]\\((.*)\\);"), "{$1};");
    line = std::regex_replace(line, std::regex("^\\s+|\\s+$"), "");
    return line;
  };
  auto statements = [&](const std::string& text, const std::string& from) {
    std::vector<std::string> out;
    std::istringstream in(text);
    bool started = from.empty();
    for (std::string line; std::getline(in, line);) {
      if (line.find("// namespace") != std::string::npos) continue;
      line = normalise(line);
      if (!started && line.rfind(from, 0) == 0) started = true;
      if (started && !line.empty()) out.push_back(line);
    }
    return out;
  };
  std::vector<std::string> glsl;
  for (const char* name : kPrimitiveModules) {
    std::vector<std::string> module = statements(readText(shaders / name), "");
    glsl.insert(glsl.end(), module.begin(), module.end());
  }
  std::vector<std::string> cpp = statements(readText(shaders / "primitives.hpp"), "bool intersectSphere(");
  ASSERT_GT(glsl.size(), 300u);
  for (size_t i = 0; i < std::min(glsl.size(), cpp.size()); ++i)
    ASSERT_EQ(cpp[i], glsl[i]) << "statement " << i << " differs (GLSL first, then the mirror)";
  EXPECT_EQ(cpp.size(), glsl.size());
}

// One compute-shader invocation per ray: in, 3 vec4 (origin + tMin, dir + tMax, kind + radii + infinite);
// out, 2 vec4 (hit + t + uv, normal).
const char* const kCrossCheckMain = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer HitBuffer { vec4 hits[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  vec4 a = rays[3 * i];
  vec4 b = rays[3 * i + 1];
  vec4 c = rays[3 * i + 2];
  Ray ray = Ray(a.xyz, b.xyz);
  float t = 0.0;
  vec3 n = vec3(0.0);
  vec2 uv = vec2(0.0);
  bool hit = false;
  int kind = int(c.x);
  if (kind == 0) hit = intersectSphere(ray, a.w, b.w, t, n, uv);
  if (kind == 1) hit = intersectBox(ray, a.w, b.w, t, n, uv);
  if (kind == 2) hit = intersectCylinder(ray, a.w, b.w, t, n, uv);
  if (kind == 3) hit = intersectCone(ray, a.w, b.w, t, n, uv);
  if (kind == 4) hit = intersectTorus(ray, c.yz, a.w, b.w, t, n, uv);
  if (kind == 5) hit = intersectPlane(ray, c.w > 0.5, a.w, b.w, t, n, uv);
  hits[2 * i] = vec4(hit ? 1.0 : 0.0, t, uv);
  hits[2 * i + 1] = vec4(n, 0.0);
}
)";


// Runs the GLSL functions on the GPU for every case (shape per case) and returns their results.
std::vector<Hit> traceOnGpu(const std::vector<Shape>& shapes, const std::vector<Case>& cases) {
  static const GLuint program = compileCompute("#version 450 core\n" + primitiveSources() + kCrossCheckMain);
  std::vector<glm::vec4> in;
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const Shape& s = shapes[i];
    const int kind = s.kind == Kind::InfinitePlane ? 5 : int(s.kind);
    in.emplace_back(c.ray.origin, c.tMin);
    in.emplace_back(c.ray.dir, c.tMax);
    in.emplace_back(float(kind), s.radii.x, s.radii.y, s.kind == Kind::InfinitePlane ? 1.0f : 0.0f);
  }
  const std::vector<glm::vec4> out =
      dispatchCompute<glm::vec4>(program, in, cases.size() * 2, cases.size(), "primitive cross-check dispatch");
  std::vector<Hit> hits(cases.size());
  for (size_t i = 0; i < cases.size(); ++i) {
    hits[i].hit = out[2 * i].x > 0.5f;
    hits[i].t = out[2 * i].y;
    hits[i].uv = vec2(out[2 * i].z, out[2 * i].w);
    hits[i].normal = vec3(out[2 * i + 1]);
  }
  return hits;
}

// The GLSL, compiled by the driver and run on its hardware, passes the random property test of the mirror
// and agrees with the mirror on nearly every ray. OSMesa (llvmpipe) by default; BVHLAB_GL_BACKEND=egl runs
// it through EGL (the NVIDIA driver on a GPU machine).
TEST(Glsl, GpuResultsPassThePropertyTest) {
  std::unique_ptr<bvhlab::GlContext> context;
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    context = bvhlab::createContext(backend && *backend ? bvhlab::parseBackend(backend) : bvhlab::Backend::OSMesa);
  } catch (const std::exception& e) {
    BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context (" << e.what() << "): GLSL not run");
  }
  std::vector<Shape> shapes;
  std::vector<Case> cases;
  uint32_t seed = 1000;
  for (Kind kind : {Kind::Sphere, Kind::Box, Kind::Cylinder, Kind::Cone, Kind::Torus, Kind::Plane,
                    Kind::InfinitePlane}) {
    for (const Shape& shape : randomShapes(kind)) {
      for (const RandomConfig& config : kRandomConfigs) {
        for (const Case& c : randomCases(shape, config, 500, seed++)) {
          shapes.push_back(shape);
          cases.push_back(c);
        }
      }
    }
  }
  std::vector<Hit> gpu = traceOnGpu(shapes, cases);
  Stats stats;
  int failures = 0, sameHit = 0, sameT = 0;
  double maxUvDiff = 0.0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    std::string failure = checkHit(shapes[i], c.ray, c.tMin, c.tMax, gpu[i], stats);
    if (!failure.empty() && ++failures <= 10) ADD_FAILURE() << "GLSL: " << failure;
    Hit cpu = trace(shapes[i], c.ray, c.tMin, c.tMax);
    if (cpu.hit != gpu[i].hit) continue;
    ++sameHit;
    if (!cpu.hit) continue;
    if (cpu.t == gpu[i].t) ++sameT;
    // uv: compared where both found the same point of the same face near the object (from far away the
    // float hit points themselves differ by ~eps |o|), away from the sphere's poles where u is singular.
    const double S = shapes[i].boundingRadius();
    const bool samePoint = std::abs(double(cpu.t) - double(gpu[i].t)) * length(dvec3(c.ray.dir)) <= 1e-6 * S;
    const double sameFace = dot(normalize(dvec3(cpu.normal)), normalize(dvec3(gpu[i].normal)));
    const bool pole = shapes[i].kind == Kind::Sphere && std::abs(normalize(cpu.normal).y) > 0.999f;
    if (samePoint && sameFace > 0.9999 && length(dvec3(c.ray.origin)) <= 10.0 * S && !pole) {
      for (int k = 0; k < 2; ++k) {  // the seams (u = 0 ~ 1, and the torus's v) may land either side
        double du = std::abs(double(cpu.uv[k]) - double(gpu[i].uv[k]));
        maxUvDiff = std::max(maxUvDiff, std::min(du, 1.0 - du));
      }
    }
  }
  std::printf("GLSL on %s: %zu rays, %d hits, %d grazing; same hit/miss as the mirror on %d, bit-identical t on "
              "%d of the hits; max position err %.2f, normal err %.2f (eps*L/cos); max uv difference %.2g\n",
              context->renderer().c_str(), cases.size(), stats.hits, stats.graze, sameHit, sameT,
              stats.maxPosition, stats.maxNormal, maxUvDiff);
  EXPECT_EQ(failures, 0);
  EXPECT_GE(sameHit, int(cases.size()) - int(cases.size()) / 200);  // disagreements only on grazing rays
  // GLSL's atan is an approximation, the mirror's is libm's: measured 1e-5 on llvmpipe.
  EXPECT_LE(maxUvDiff, 1e-4);
}

}  // namespace
