// test_robust.cpp — the robust variants (watertight ray/triangle, Ize's conservative slab
// test, the ULP origin offset) against the fast ones on the hard-case suite (datasets/hard_cases.hpp),
// with CGAL's exact kernel as the oracle (datasets/cgal_oracle.hpp). Measured counts are printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <unistd.h>

#include "builders/builder.hpp"
#include "datasets/cgal_oracle.hpp"
#include "datasets/hard_cases.hpp"
#include "experiments/process.hpp"
#include "layout/layout.hpp"
#include "layout/layouts.hpp"
#include "render/hard_cases_command.hpp"
#include "shaders/assemble.hpp"
#include "shaders/offset_ulp.hpp"
#include "shaders/tracer.hpp"
#include "traversal/kernels.hpp"
#include "traversal/ray_box.hpp"
#include "traversal/ray_box_robust.hpp"
#include "traversal/ray_triangle.hpp"
#include "traversal/ray_triangle_watertight.hpp"
#include "require.hpp"

namespace {

using namespace bvhlab;
using bvhlab::hard::HardCase;
using bvhlab::hard::HardRay;
using glm::vec2;
using glm::vec3;

const char* name(TriangleTest v) { return v == TriangleTest::MollerTrumbore ? "fast (Moller-Trumbore)" : "watertight"; }

bool intersect(TriangleTest v, glsl::Ray ray, vec3 a, vec3 b, vec3 c, float tMin, float tMax, float& t, vec2& bary) {
  return v == TriangleTest::MollerTrumbore ? glsl::intersectTriangle(ray, a, b, c, tMin, tMax, t, bary)
                                 : glsl::watertight::intersectTriangle(ray, a, b, c, tMin, tMax, t, bary);
}

struct BruteHit {
  bool hit = false;
  int tri = -1;
  float t = 0.0f;
  vec2 bary{0.0f};
};

// Closest hit over all triangles, in index order, shrinking tMax like the kernels do.
BruteHit closest(TriangleTest v, const HardCase& c, glsl::Ray ray, float tMin, float tMax) {
  BruteHit h;
  h.t = tMax;
  for (size_t i = 0; i < c.triangles.size(); ++i) {
    const glm::uvec3 tri = c.triangles[i];
    float t;
    vec2 bary;
    if (intersect(v, ray, c.positions[tri.x], c.positions[tri.y], c.positions[tri.z], tMin, h.t, t, bary))
      h = BruteHit{true, int(i), t, bary};
  }
  return h;
}

const std::vector<HardCase>& suite() {
  static const std::vector<HardCase> cases = hard::makeHardCases();
  return cases;
}

// ---- the generators ------------------------------------------------------------------------------

// "Closed" is a property of the data, not of intent: after welding equal positions, every edge is used
// by exactly two triangles, once in each direction (a consistently oriented closed surface).
TEST(HardCases, ClosedCasesAreClosedAndEveryCaseIsDocumented) {
  for (const HardCase& c : suite()) {
    EXPECT_FALSE(c.description.empty()) << c.name;
    EXPECT_FALSE(c.rays.empty()) << c.name;
    for (const glm::uvec3& t : c.triangles)
      for (int k = 0; k < 3; ++k) ASSERT_LT(t[k], c.positions.size()) << c.name;
    if (!c.closed) continue;
    std::map<std::tuple<float, float, float>, int> weld;
    auto id = [&](unsigned i) {
      vec3 p = c.positions[i];
      return weld.emplace(std::make_tuple(p.x, p.y, p.z), int(weld.size())).first->second;
    };
    std::map<std::pair<int, int>, int> directed;
    for (const glm::uvec3& t : c.triangles)
      for (int k = 0; k < 3; ++k) directed[{id(t[k]), id(t[(k + 1) % 3])}]++;
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1) << c.name << ": directed edge used " << count << " times";
      auto reverse = directed.find({edge.second, edge.first});
      EXPECT_TRUE(reverse != directed.end() && reverse->second == 1) << c.name << ": an edge without a twin";
    }
  }
}

// ---- leaks ---------------------------------------------------------------------------------------

// Every mustHit ray must hit; a miss is a leak. Watertight: none on any case. The fast test's leaks are
// measured and printed, not asserted (they are the point of the comparison).
TEST(Robust, WatertightNeverLeaksFastLeaksAreCounted) {
  size_t totalRays = 0, totalFast = 0, totalWatertight = 0;
  std::printf("%-36s %7s %10s %10s\n", "case", "rays", "fast", "watertight");
  for (const HardCase& c : suite()) {
    size_t rays = 0, leaks[2] = {0, 0};
    for (const HardRay& r : c.rays) {
      if (!r.mustHit) continue;
      ++rays;
      for (TriangleTest v : {TriangleTest::MollerTrumbore, TriangleTest::Watertight})
        if (!closest(v, c, {r.origin, r.dir}, r.tMin, r.tMax).hit) ++leaks[int(v)];
    }
    if (rays == 0) continue;
    std::printf("%-36s %7zu %10zu %10zu\n", c.name.c_str(), rays, leaks[0], leaks[1]);
    EXPECT_EQ(leaks[int(TriangleTest::Watertight)], 0u) << c.name;
    totalRays += rays;
    totalFast += leaks[0];
    totalWatertight += leaks[1];
  }
  std::printf("%-36s %7zu %10zu %10zu\n", "total", totalRays, totalFast, totalWatertight);
  EXPECT_GT(totalRays, 10000u);  // the suite really exercises the closed cases
}

// No hit reports a non-finite t or barycentric, on any ray of any case, in either variant; the box
// tests' entry distances are never NaN.
TEST(Robust, NoNanOrInfOnAnyHardCase) {
  size_t hits = 0;
  for (const HardCase& c : suite())
    for (const HardRay& r : c.rays) {
      for (TriangleTest v : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
        BruteHit h = closest(v, c, {r.origin, r.dir}, r.tMin, r.tMax);
        if (!h.hit) continue;
        ++hits;
        EXPECT_TRUE(std::isfinite(h.t) && std::isfinite(h.bary.x) && std::isfinite(h.bary.y))
            << c.name << " " << name(v) << " t=" << h.t;
      }
      vec3 invFast = glsl::rayInverseDirection(r.dir), invRobust = glsl::robust::rayInverseDirection(r.dir);
      for (const glm::uvec3& tri : c.triangles) {
        vec3 lo = glm::min(c.positions[tri.x], glm::min(c.positions[tri.y], c.positions[tri.z]));
        vec3 hi = glm::max(c.positions[tri.x], glm::max(c.positions[tri.y], c.positions[tri.z]));
        float tEnter;
        glsl::robust::intersectAabb(r.origin, invRobust, lo, hi, r.tMin, r.tMax, tEnter);
        ASSERT_FALSE(std::isnan(tEnter)) << c.name;
        glsl::intersectAabb(r.origin, invFast, lo, hi, r.tMin, r.tMax, tEnter);
        ASSERT_FALSE(std::isnan(tEnter)) << c.name;
      }
    }
  EXPECT_GT(hits, 0u);
}

// Watertight and Moller-Trumbore agree on t and barycentrics for a plain interior hit (the mapping of
// the edge functions to (u, v) is the kernels' convention).
TEST(Robust, WatertightBarycentricsMatchTheFastTest) {
  const vec3 v0(0.5f, -1.0f, 2.0f), v1(3.0f, 0.25f, 2.5f), v2(-0.5f, 2.0f, 1.5f);
  for (vec3 dir : {vec3(0.1f, 0.2f, 1.0f), vec3(0.3f, -0.1f, 0.9f), vec3(-0.05f, 0.1f, 1.0f)}) {
    glsl::Ray ray{vec3(0.4f, 0.3f, -1.0f), dir};
    float tf, tw;
    vec2 bf, bw;
    ASSERT_TRUE(glsl::intersectTriangle(ray, v0, v1, v2, 0.0f, glsl::INF, tf, bf));
    ASSERT_TRUE(glsl::watertight::intersectTriangle(ray, v0, v1, v2, 0.0f, glsl::INF, tw, bw));
    EXPECT_NEAR(tw, tf, 1e-5f * tf);
    EXPECT_NEAR(bw.x, bf.x, 1e-5f);
    EXPECT_NEAR(bw.y, bf.y, 1e-5f);
    // Reversed winding and a reversed ray are hits too (no culling), the reversed ray only behind.
    EXPECT_TRUE(glsl::watertight::intersectTriangle(ray, v0, v2, v1, 0.0f, glsl::INF, tw, bw));
    EXPECT_FALSE(glsl::watertight::intersectTriangle({ray.origin, -dir}, v0, v1, v2, 0.0f, glsl::INF, tw, bw));
  }
  float t;
  vec2 b;
  EXPECT_FALSE(glsl::watertight::intersectTriangle({vec3(0.0f), vec3(0.0f)}, v0, v1, v2, 0.0f, glsl::INF, t, b));
}

// ---- the exact oracle ------------------------------------------------------------------------------

// Hit/miss and first hit against CGAL's exact kernel on every unit-scale case. Rates printed for both
// variants; watertight must agree wherever the exact answer is decisive (not a tie).
TEST(Robust, AgreesWithTheExactOracle) {
  struct Tally {
    size_t hitDecisive = 0, hitAgree = 0, firstDecisive = 0, firstAgree = 0;
  } tally[2];
  size_t ties = 0, rays = 0, nearTies = 0;
  for (const HardCase& c : suite()) {
    if (c.farOrScaled) continue;
    for (const HardRay& r : c.rays) {
      ++rays;
      const oracle::ExactFirstHit exact = oracle::exactFirstHit(c.positions, c.triangles, r.origin, r.dir, r.tMin, r.tMax);
      if (exact.hit == oracle::Decision::Tie) ++ties;
      for (TriangleTest v : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
        const BruteHit h = closest(v, c, {r.origin, r.dir}, r.tMin, r.tMax);
        Tally& s = tally[int(v)];
        if (exact.hit != oracle::Decision::Tie) {
          ++s.hitDecisive;
          const bool agree = h.hit == (exact.hit == oracle::Decision::Hit);
          s.hitAgree += agree;
          if (v == TriangleTest::Watertight) {
            EXPECT_TRUE(agree) << c.name << ": origin " << r.origin.x << "," << r.origin.y << "," << r.origin.z
                               << " dir " << r.dir.x << "," << r.dir.y << "," << r.dir.z;
          }
        }
        if (exact.firstDecisive) {
          ++s.firstDecisive;
          const bool agree = std::find(exact.firstTriangles.begin(), exact.firstTriangles.end(), h.tri) !=
                             exact.firstTriangles.end();
          s.firstAgree += agree;
          // A float test rounds the (sheared) coordinates: a hit within a few ulps of an edge, relative to
          // the coordinates' magnitude over the edge length (<= 2 / (1/8) = 16 in the unit cases), may go to
          // the neighbour. 2^-16 (256 u, u = 2^-24) bounds that with a factor ~16 to spare; hits closer
          // to an edge are float near-ties, counted but not asserted (measured worst: 2.5e-7).
          if (v == TriangleTest::Watertight && exact.firstMargin >= 0x1p-16) {
            EXPECT_TRUE(agree) << c.name << ": first hit " << h.tri << ", margin " << exact.firstMargin;
          }
          if (v == TriangleTest::Watertight && exact.firstMargin < 0x1p-16) ++nearTies;
        }
      }
    }
  }
  std::printf("oracle: %zu rays on unit-scale cases, %zu exact ties (boundary-only touches), %zu decisive first "
              "hits within 2^-16 of an edge (float near-ties)\n", rays, ties, nearTies);
  for (TriangleTest v : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
    const Tally& s = tally[int(v)];
    std::printf("  %-24s hit/miss %zu/%zu agree (%.2f%%), first hit %zu/%zu agree (%.2f%%)\n", name(v), s.hitAgree,
                s.hitDecisive, 100.0 * double(s.hitAgree) / double(s.hitDecisive), s.firstAgree, s.firstDecisive,
                100.0 * double(s.firstAgree) / double(s.firstDecisive));
  }
  EXPECT_GT(tally[1].hitDecisive, 1000u);
  EXPECT_GT(tally[1].firstDecisive, 1000u);
}

// The oracle itself on cases whose answer is known by construction.
TEST(Robust, OracleKnownAnswers) {
  const std::vector<vec3> p = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  const std::vector<glm::uvec3> quad = {{0, 1, 2}, {0, 2, 3}};
  auto inside = oracle::exactFirstHit(p, quad, vec3(0.5f, -0.25f, -1), vec3(0, 0, 1), 0.0f, glsl::INF);
  EXPECT_EQ(inside.hit, oracle::Decision::Hit);
  EXPECT_EQ(inside.firstTriangles, std::vector<int>{0});
  EXPECT_EQ(inside.firstT, 1.0);
  EXPECT_TRUE(inside.firstDecisive);
  auto seam = oracle::exactFirstHit(p, quad, vec3(0.25f, 0.25f, -1), vec3(0, 0, 1), 0.0f, glsl::INF);
  EXPECT_EQ(seam.hit, oracle::Decision::Tie);  // on the diagonal: both triangles' boundary
  auto outside = oracle::exactFirstHit(p, quad, vec3(2, 0, -1), vec3(0, 0, 1), 0.0f, glsl::INF);
  EXPECT_EQ(outside.hit, oracle::Decision::Miss);
  EXPECT_TRUE(oracle::exactRayMeetsBox(vec3(0, 0.5f, 0.5f), vec3(0, 1, 0), vec3(0), vec3(1)));  // on a slab plane
  EXPECT_FALSE(oracle::exactRayMeetsBox(vec3(-1e-30f, 0.5f, 0.5f), vec3(0, 1, 0), vec3(0), vec3(1)));
  EXPECT_TRUE(oracle::exactRayMeetsBox(vec3(0.5f, 0.5f, -1), vec3(0, 0, 1), vec3(0, 0, 0.5f), vec3(1, 1, 0.5f)));
}

// ---- boxes ---------------------------------------------------------------------------------------

// Conservative: whenever the exact ray meets a triangle's (possibly flat) box, the robust test accepts
// it. The fast test's false misses are counted and printed.
TEST(Robust, RobustBoxTestNeverCullsABoxTheRayMeets) {
  size_t tests = 0, meets = 0, falseMiss[2] = {0, 0}, extraHits = 0;
  for (const HardCase& c : suite()) {
    if (c.farOrScaled && c.name.find("sphere") != std::string::npos) continue;  // the cube copies suffice
    for (const HardRay& r : c.rays) {
      vec3 invFast = glsl::rayInverseDirection(r.dir), invRobust = glsl::robust::rayInverseDirection(r.dir);
      for (const glm::uvec3& tri : c.triangles) {
        vec3 lo = glm::min(c.positions[tri.x], glm::min(c.positions[tri.y], c.positions[tri.z]));
        vec3 hi = glm::max(c.positions[tri.x], glm::max(c.positions[tri.y], c.positions[tri.z]));
        float tEnter;
        bool fast = glsl::intersectAabb(r.origin, invFast, lo, hi, 0.0f, glsl::INF, tEnter);
        bool robust = glsl::robust::intersectAabb(r.origin, invRobust, lo, hi, 0.0f, glsl::INF, tEnter);
        ++tests;
        if (fast == robust && !robust) {
          // Both reject: the exact answer must be a miss for the robust one (checked below only where needed).
          if (oracle::exactRayMeetsBox(r.origin, r.dir, lo, hi)) {
            ++meets;
            ++falseMiss[0];
            ++falseMiss[1];
            ADD_FAILURE() << c.name << ": robust box test culls a box the ray meets";
          }
          continue;
        }
        const bool exact = oracle::exactRayMeetsBox(r.origin, r.dir, lo, hi);
        meets += exact;
        if (exact && !fast) ++falseMiss[0];
        if (exact && !robust) {
          ++falseMiss[1];
          ADD_FAILURE() << c.name << ": robust box test culls a box the ray meets";
        }
        if (!exact && robust) ++extraHits;
      }
    }
  }
  std::printf("boxes: %zu ray/box tests, %zu exact meets; false misses fast %zu, robust %zu; robust near-miss "
              "accepts %zu\n", tests, meets, falseMiss[0], falseMiss[1], extraHits);
  EXPECT_EQ(falseMiss[1], 0u);
}

// Axis-parallel rays with their origin exactly on a slab plane, and flat boxes: closed-slab answers.
TEST(Robust, SlabPlanesAndFlatBoxes) {
  const vec3 lo(0.0f), hi(1.0f);
  float tEnter;
  auto hit = [&](vec3 o, vec3 d, vec3 bmin, vec3 bmax) {
    return glsl::robust::intersectAabb(o, glsl::robust::rayInverseDirection(d), bmin, bmax, 0.0f, glsl::INF, tEnter);
  };
  EXPECT_TRUE(hit(vec3(0.0f, 0.5f, -1.0f), vec3(0, 0, 1), lo, hi));   // on the x = 0 plane
  EXPECT_TRUE(hit(vec3(1.0f, 1.0f, 2.0f), vec3(0, 0, -1), lo, hi));   // on an edge line
  EXPECT_FALSE(hit(vec3(1.0f, 1.5f, 2.0f), vec3(0, 0, -1), lo, hi));  // on x = 1, outside in y
  EXPECT_TRUE(hit(vec3(0.5f, 0.5f, -1.0f), vec3(0, 0, 1), vec3(0, 0, 0.5f), vec3(1, 1, 0.5f)));  // flat box
  EXPECT_EQ(tEnter, 1.5f);
  EXPECT_TRUE(hit(vec3(0.0f, 0.5f, 0.5f), vec3(0, 0, 1), vec3(0, 0, 0.5f), vec3(1, 1, 0.5f)));  // origin on it
  EXPECT_EQ(tEnter, 0.0f);
  EXPECT_TRUE(hit(vec3(0.5f, 0.5f, 0.5f), vec3(-0.0f, 0.0f, 1.0f), lo, hi));  // negative zero component
}

// ---- secondary-ray origins -------------------------------------------------------------------------

TEST(Robust, UlpOffsetMovesEveryCoordinateTowardsN) {
  for (vec3 p : {vec3(1.0f, -2.0f, 1e6f), vec3(-3e-3f, 5e4f, -7e5f), vec3(0.0f, -0.0f, 1e-20f)}) {
    const vec3 n = glm::normalize(vec3(0.6f, -0.48f, 0.64f));
    for (float s : {1.0f, -1.0f}) {
      // As the hit of a ray from the origin: hitMagnitude = max|p|, at least 1 (the chapter's scale).
      const float magnitude = std::max({1.0f, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
      const vec3 q = glsl::offsetRayOriginUlp(p, s * n, magnitude);
      for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(std::isfinite(q[k]));
        EXPECT_GT((q[k] - p[k]) * s * n[k], 0.0f) << "component " << k << " of " << p[k];
        // At most 256 ulps (plus the absolute offset near 0): a tiny move, not a jump.
        EXPECT_LE(std::abs(q[k] - p[k]), 256.0f * std::abs(p[k]) * 1.2e-7f + magnitude / 65536.0f);
      }
    }
  }
}

// Acne: from every hit inside the closed cases (all offsets and scales), a reflected ray starting at the
// offset origin must not hit the triangle it starts on (watertight test). Counted for no offset, the
// fixed epsilon and the ULP offset; the ULP offset must have none.
TEST(Robust, UlpOffsetAvoidsSelfIntersectionAtEveryScale) {
  size_t spawned = 0, selfHits[3] = {0, 0, 0};
  for (const HardCase& c : suite()) {
    if (!c.closed) continue;
    for (const HardRay& r : c.rays) {
      const BruteHit h = closest(TriangleTest::Watertight, c, {r.origin, r.dir}, r.tMin, r.tMax);
      if (!h.hit) continue;
      const glm::uvec3 tri = c.triangles[size_t(h.tri)];
      const vec3 a = c.positions[tri.x], b = c.positions[tri.y], d = c.positions[tri.z];
      vec3 n = glm::normalize(glm::cross(b - a, d - a));
      if (glm::dot(n, r.dir) > 0.0f) n = -n;  // facing the ray
      const vec3 p = (1.0f - h.bary.x - h.bary.y) * a + h.bary.x * b + h.bary.y * d;
      const vec3 dir = glm::reflect(glm::normalize(r.dir), n);
      const float magnitude = std::max({std::abs(r.origin.x), std::abs(r.origin.y), std::abs(r.origin.z)}) +
                              h.t * glm::length(r.dir);  // shade.glsl's hitMagnitude
      const vec3 origins[3] = {p, offsetRayOrigin(p, n, magnitude, OriginOffset::Epsilon),
                               glsl::offsetRayOriginUlp(p, n, magnitude)};
      ++spawned;
      for (int k = 0; k < 3; ++k) {
        float t;
        vec2 bary;
        if (glsl::watertight::intersectTriangle({origins[k], dir}, a, b, d, 0.0f, glsl::INF, t, bary)) ++selfHits[k];
      }
    }
  }
  std::printf("acne: %zu reflected rays; self-hits: no offset %zu, fixed epsilon %zu, ulp offset %zu\n", spawned,
              selfHits[0], selfHits[1], selfHits[2]);
  EXPECT_GT(spawned, 10000u);
  EXPECT_EQ(selfHits[2], 0u);
}

// ---- the variants ----------------------------------------------------------------------------------

TEST(Variants, EveryKnobCombinationHasOneNameThatParsesBack) {
  const std::vector<std::string>& names = robustnessNames();
  ASSERT_EQ(names.size(), 8u);
  EXPECT_EQ(names.front(), "fast");
  EXPECT_EQ(names.back(), "watertight");
  std::set<std::tuple<int, int, int>> combinations;
  for (size_t i = 0; i < names.size(); ++i) {
    const Robustness r = parseRobustness(names[i]);
    EXPECT_EQ(r, robustnessVariants()[i]);
    EXPECT_EQ(robustnessName(r), names[i]);
    combinations.insert({int(r.triangle), int(r.box), int(r.offset)});
  }
  EXPECT_EQ(combinations.size(), 8u);  // all 2 x 2 x 2
  EXPECT_EQ(parseRobustness("fast"), Robustness::Fast);
  EXPECT_EQ(parseRobustness("watertight"), Robustness::Watertight);
  const Robustness triUlp = parseRobustness("tri+ulp");
  EXPECT_EQ(triUlp.triangle, TriangleTest::Watertight);
  EXPECT_EQ(triUlp.box, BoxTest::Slab);
  EXPECT_EQ(triUlp.offset, OriginOffset::Ulp);
  try {
    parseRobustness("ulp+tri");  // one spelling per variant: the canonical order only
    ADD_FAILURE() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    for (const std::string& n : names) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
  }
}

// Closest hit through a BVH, one function per (triangle test, box test) pair.
struct CaseBvh {
  PackedBvh packed;
  explicit CaseBvh(const HardCase& c) {
    Scene s;
    Mesh m;
    m.positions = c.positions;
    m.triangles = c.triangles;
    s.meshes.push_back(m);
    Object o;
    o.kind = ObjectKind::Mesh;
    s.objects.push_back(o);
    s.materials.push_back(Material{});
    const TriangleSoup soup = gatherTriangles(s);
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<vec3> centroids = triangleCentroids(soup);
    packed = packBvh(buildBvh("sah-binned", BuildInput{boxes, centroids}, BuildOptions{}), soup);
  }
};

// Each kernel mirror, for every (triangle test, box test) pair, against brute force with the same
// triangle test over every ray of the suite. With Ize's box test the BVH culls no box the exact ray
// meets: found equals brute force, and t too up to rounding (two triangles hit within rounding at an
// edge, where the float t of one lies below the float entry of its box, may swap).
// With the plain slab test the BVH may cull a hit (the box leaks): never a hit brute force lacks, never
// a nearer one; the culled ones are counted and printed.
TEST(Variants, KernelMirrorsMatchBruteForceForEveryTestPair) {
  for (const KernelInfo& k : kernels()) {
    size_t rays = 0, boxCulled[4] = {0, 0, 0, 0}, nearTies = 0;
    double worstTie = 0.0;
    for (const HardCase& c : suite()) {
      const CaseBvh bvh(c);
      float scale = 0.0f;  // the case's coordinate magnitude: what a float t is accurate relative to
      for (const vec3& p : c.positions) scale = std::max({scale, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
      const glsl::Storage storage(bvh.packed);
      for (Robustness r : robustnessVariants()) {
        if (r.offset == OriginOffset::Ulp) continue;  // the offset is not the kernel's: 4 pairs suffice
        for (const HardRay& ray : c.rays) {
          const BruteHit brute = closest(r.triangle, c, {ray.origin, ray.dir}, ray.tMin, ray.tMax);
          glsl::MeshHit hit;
          glsl::Counters counters;
          const bool found = k.closest(r)(storage, {ray.origin, ray.dir}, ray.tMin, ray.tMax, hit, counters);
          const bool any = k.any(r)(storage, {ray.origin, ray.dir}, ray.tMin, ray.tMax, counters);
          ++rays;
          ASSERT_EQ(found, any) << k.name << " " << robustnessName(r) << " " << c.name;
          if (found) {
            ASSERT_TRUE(brute.hit) << k.name << " " << robustnessName(r) << " " << c.name;
            ASSERT_GE(hit.t, brute.t) << k.name << " " << robustnessName(r) << " " << c.name;
          }
          if (r.box == BoxTest::Robust) {
            ASSERT_EQ(found, brute.hit) << k.name << " " << robustnessName(r) << " " << c.name;
            if (found && hit.t != brute.t) {
              ++nearTies;
              worstTie = std::max(worstTie, double(hit.t - brute.t) * double(glm::length(ray.dir)) / scale);
            }
          } else {
            boxCulled[r.testsIndex()] += brute.hit && (!found || hit.t > brute.t);
          }
        }
      }
    }
    std::printf("%-16s %zu ray traces; hits lost (or found further) with the slab box test: moller-trumbore %zu, watertight %zu; "
                "robust box: %zu near-ties, worst %.3g\n",
                k.name.c_str(), rays, boxCulled[Robustness{}.testsIndex()],
                boxCulled[Robustness{TriangleTest::Watertight, BoxTest::Slab, OriginOffset::Epsilon}.testsIndex()],
                nearTies, worstTie);
    // A float t is good to a few roundings of the coordinates: the conservative box keeps every box the
    // exact ray meets, not every one a float t rounded below its entry would need, so two triangles hit
    // within rounding (an edge) may swap. 2^-20 = 16 u of the case's coordinate magnitude bounds that
    // (measured worst ~7 u).
    EXPECT_LE(worstTie, 0x1p-20) << k.name;
  }
}

// `bvhlab hard-cases` (CPU part): the table and JSON for two variants; watertight leaks nothing and
// agrees with the oracle on every decisive ray, the fast variant's leaks are there to see.
TEST(Variants, HardCasesCommandWritesItsJson) {
  const std::filesystem::path json =
      std::filesystem::temp_directory_path() / ("bvhlab_hard_cases_" + std::to_string(::getpid()) + ".json");
  const ProcessResult p = runProcess({BVHLAB_BINARY, "hard-cases", "--robust", "fast", "--robust", "watertight",
                                      "--json", json.string()});
  ASSERT_TRUE(p.ok()) << p.status() << "\n" << p.err;
  EXPECT_NE(p.out.find("watertight"), std::string::npos) << p.out;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  std::filesystem::remove(json);
  ASSERT_EQ(j["variants"].size(), 2u);
  const nlohmann::json& fast = j["variants"][0];
  const nlohmann::json& watertight = j["variants"][1];
  EXPECT_EQ(fast["robust"], "fast");
  EXPECT_EQ(watertight["origin_offset"], "ulp");
  EXPECT_EQ(watertight["total"]["leaks"], 0);
  EXPECT_EQ(watertight["total"]["oracle_hit_disagree"], 0);
  EXPECT_EQ(watertight["total"]["oracle_first_clear_disagree"], 0);
  EXPECT_GT(fast["total"]["leaks"].get<size_t>(), 0u);
  EXPECT_EQ(fast["total"]["must_hit"], j["suite"]["must_hit"]);
  EXPECT_EQ(fast["cases"].size(), j["suite"]["cases"]);
  for (const nlohmann::json& v : j["variants"]) {
    EXPECT_EQ(v["total"]["nan_box_entries"], 0) << v["robust"];
    EXPECT_EQ(v["total"]["nonfinite_hits"], 0) << v["robust"];
    EXPECT_EQ(v["total"]["secondary_self_hits"], 0) << v["robust"];
  }
  const ProcessResult bad = runProcess({BVHLAB_BINARY, "hard-cases", "--robust", "tri+nope"});
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.err.find("box+ulp"), std::string::npos) << bad.err;  // the error lists the valid names
  EXPECT_EQ(j["layout"], "v1");
  EXPECT_EQ(j["kernel"], "stack-ordered");
}

// `bvhlab hard-cases --layout`: the suite's trees packed in another layout and walked by its kernel;
// watertight leaks nothing and agrees with the oracle there too; a kernel of another layout is refused
// naming the layout's own.
TEST(Variants, HardCasesCommandRunsEveryLayout) {
  for (const LayoutInfo& l : layouts()) {
    SCOPED_TRACE(l.name);
    const ProcessResult p =
        runProcess({BVHLAB_BINARY, "hard-cases", "--layout", l.name, "--robust", "watertight", "--json", "-"});
    ASSERT_TRUE(p.ok()) << p.status() << "\n" << p.err;
    const nlohmann::json j = nlohmann::json::parse(p.out);
    EXPECT_EQ(j["layout"], l.name);
    EXPECT_EQ(j["kernel"], l.defaultKernel);
    const nlohmann::json& total = j["variants"][0]["total"];
    EXPECT_GT(total["must_hit"].get<size_t>(), 100u);
    EXPECT_EQ(total["leaks"], 0);
    EXPECT_EQ(total["oracle_hit_disagree"], 0);
    EXPECT_EQ(total["oracle_first_clear_disagree"], 0);
    EXPECT_EQ(total["nonfinite_hits"], 0);
  }
  const ProcessResult bad = runProcess({BVHLAB_BINARY, "hard-cases", "--layout", "bvh2-cb", "--kernel", "stackless"});
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.err.find("bvh2cb-stack-ordered"), std::string::npos) << bad.err;
}

// ---- the GLSL ------------------------------------------------------------------------------------

// Every variant assembles its own modules (each knob on its own) and the whole tracer compiles with
// glslang, in every kernel, for a scene that spawns every kind of secondary ray.
TEST(RobustGlsl, EveryVariantAssemblesItsModulesAndCompilesWithGlslang) {
  SceneFeatures f;  // a mesh, a light with shadows, reflection and refraction: every offset call site
  f.mesh = f.lights = f.shadows = f.reflection = f.refraction = true;
  f.kinds[0] = true;  // a sphere
  f.numObjects = f.numLights = 1;
  f.numMaterials = 2;
  const bool haveGlslang = std::system("command -v glslangValidator > /dev/null 2>&1") == 0;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bvhlab_test_robust_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (Robustness r : robustnessVariants()) {
    const std::string variant = robustnessName(r);
    for (const KernelInfo& k : kernels()) {
      ShaderOptions o;
      o.kernel = k.name;
      o.robust = r;
      const AssembledShader s = assembleTracer(f, o);
      const bool tri = r.triangle == TriangleTest::Watertight, box = r.box == BoxTest::Robust,
                 ulp = r.offset == OriginOffset::Ulp;
      EXPECT_EQ(s.hasModule("ray_triangle_watertight.glsl"), tri) << variant;
      EXPECT_EQ(s.hasModule("ray_triangle.glsl"), !tri) << variant;
      EXPECT_EQ(s.hasModule("ray_box_robust.glsl"), box) << variant;
      EXPECT_EQ(s.hasModule("ray_box.glsl"), !box) << variant;
      EXPECT_EQ(s.hasModule("offset_ulp.glsl"), ulp) << variant;
      EXPECT_EQ(s.source.find("#define RAY_OFFSET_ULP") != std::string::npos, ulp) << variant;
      if (!haveGlslang) continue;
      const std::filesystem::path file = dir / (variant + "-" + k.name + ".frag"), log = dir / "log.txt";
      std::ofstream(file) << s.source;
      const std::string cmd = "glslangValidator -S frag '" + file.string() + "' > '" + log.string() + "' 2>&1";
      const int rc = std::system(cmd.c_str());
      std::stringstream text;
      text << std::ifstream(log).rdbuf();
      EXPECT_EQ(rc, 0) << variant << " " << k.name << ":\n" << s.mapLog(text.str());
    }
  }
  std::filesystem::remove_all(dir);
  if (!haveGlslang) BVHLAB_SKIP_OR_FAIL("glslangValidator not found (Debian package glslang-tools): assembly checked only");
}

}  // namespace
