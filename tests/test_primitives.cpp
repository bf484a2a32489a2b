// Tests of the analytic ray-primitive intersections' C++ mirrors (shaders/primitives.hpp): hand-computed
// cases, cross-cutting properties (NaN and degenerate inputs, unnormalised directions, tangent and grazing
// rays) and a random property test, each against the double-precision reference and within the error
// model of tests/primitives_test_util.hpp. test_primitives_glsl.cpp runs the GLSL through the same checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "datasets/random_draws.hpp"
#include "primitives_test_util.hpp"

namespace {

using namespace bvhlab::primtest;

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
      vec3 origin = 4.0f * normalize(bvhlab::draw3<vec3>(u, rng) + vec3(0, 0.01f, 0));
      vec3 dir = normalize(bvhlab::draw3<vec3>(u, rng) * 0.8f - origin);
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

}  // namespace
