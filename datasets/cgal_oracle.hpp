// cgal_oracle.hpp — exact ground truth for the hard-case suite: ray/triangle and ray/box
// decisions in CGAL's Exact_predicates_exact_constructions_kernel on the exact values of the float
// inputs. CGAL stays inside cgal_oracle.cpp (compile-heavy); this header has no CGAL in it.
#pragma once
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab::oracle {

enum class Decision { Miss, Hit, Tie };

struct ExactFirstHit {
  // Hit: some triangle is met strictly inside (all three barycentrics > 0) at tMin < t < tMax.
  // Miss: nothing is touched at all. Tie: only boundaries are touched (an edge or vertex, a zero-area
  // triangle, a triangle whose plane contains the ray, or a hit exactly at tMin or tMax), where a
  // float test may go either way.
  Decision hit = Decision::Miss;
  // Every triangle met at the smallest exact t (more than one: shared edges, coplanar overlaps,
  // duplicates; any of them is a correct first hit). Empty unless hit == Hit.
  std::vector<int> firstTriangles;
  double firstT = 0.0;  // that t, rounded to double
  // The first hit is decided exactly: hit == Hit, no boundary-only touch anywhere along the ray, and
  // the smallest t is attained by an interior hit.
  bool firstDecisive = false;
  // The smallest barycentric (min of u, v, 1 - u - v) of the first interior hit, rounded to double: how
  // far inside its triangle the exact first hit lies. A float test rounds the vertex coordinates and may
  // put a hit this close to an edge into the neighbour: callers judge "decisive for floats" with it.
  double firstMargin = 0.0;
};

// positions/triangles: an indexed soup; (origin, dir): the ray origin + t dir for tMin < t < tMax
// (tMax may be +inf; tMin >= 0).
ExactFirstHit exactFirstHit(const std::vector<glm::vec3>& positions, const std::vector<glm::uvec3>& triangles,
                            glm::vec3 origin, glm::vec3 dir, float tMin, float tMax);

// Does the closed ray origin + t dir, t >= 0, meet the closed box [bmin, bmax] (which may be flat)?
bool exactRayMeetsBox(glm::vec3 origin, glm::vec3 dir, glm::vec3 bmin, glm::vec3 bmax);

// Does it meet the closed triangle (any point of it, edges, a zero-area triangle's segment and a ray
// in its plane included)?
bool exactRayMeetsTriangle(glm::vec3 origin, glm::vec3 dir, glm::vec3 v0, glm::vec3 v1, glm::vec3 v2);

}  // namespace bvhlab::oracle
