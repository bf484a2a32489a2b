// hard_cases.hpp — the hard-case suite for ray/triangle and ray/box robustness: small
// triangle soups with ray lists aimed at the places where floating-point tests fail (shared edges and
// vertices, slab planes, degenerate triangles, far offsets, extreme scales). Pure functions of their
// arguments: the same call gives bit-identical data everywhere. Each case documents itself in
// `description`; the list is in makeHardCases().
#pragma once
#include <limits>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab::hard {

struct HardRay {
  glm::vec3 origin;
  glm::vec3 dir;  // not normalised
  float tMin = 0.0f;
  float tMax = std::numeric_limits<float>::infinity();
  // True when the exact answer is "hit" for every consistent (watertight) test: the ray starts inside a
  // closed surface, or passes through the inside of an open surface (an interior edge or vertex
  // included). A miss on such a ray is a leak.
  bool mustHit = false;
};

struct HardCase {
  std::string name;
  std::string description;
  std::vector<glm::vec3> positions;
  std::vector<glm::uvec3> triangles;  // indices into positions (a soup where vertices are duplicated)
  std::vector<HardRay> rays;
  bool closed = false;  // the triangles bound a closed volume (after welding equal positions)
  bool farOrScaled = false;  // a transformed copy of a unit-scale case (oracle runs only at unit scale)
};

// The closed cube [-1,1]^3, every face an n x n grid, vertices shared between faces (n >= 1).
HardCase closedCube(int n);
// The closed unit UV sphere, `segments` around z, `rings` pole to pole, no seam duplicates: every
// vertex is shared by all its triangles, the poles are single vertices.
HardCase closedSphere(int segments, int rings);
// c with every position mapped to offset + scale * p (rays' origins likewise, directions scaled).
HardCase transformed(const HardCase& c, glm::vec3 offset, float scale);

// The whole suite, unit-scale cases first, then the far/scaled copies of the closed ones.
std::vector<HardCase> makeHardCases();

}  // namespace bvhlab::hard
