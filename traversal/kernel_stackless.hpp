// kernel_stackless.hpp — C++ mirror of kernel_stackless.glsl (escape links; counter definitions
// are documented there).
#pragma once
#include "traversal/layout.hpp"
#include "traversal/intersectors.hpp"
#include "traversal/leaf_test.hpp"

namespace bvhlab::glsl::stackless {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: every loadNode reads a v1 node's two texels (layout.glsl), once per node visit, so
//   nodeBytes = 32 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: none (escape links); stackBytes stays 0.
constexpr uint kNodeBytes = bvhlab::kNodeTexels * kTexelBytes;

// root: the node the walk starts at (GLSL's `root`: 0 for a flat tree); leaf: the test of the leaves'
// primitives (GLSL's KERNEL_LEAF_TEST: traversal/leaf_test.hpp).
template <class Tests, class Leaf>
inline bool traverseStackless(const Storage& s, Ray ray, int root, float tMin, float tMax, bool anyHit, MeshHit& hit,
                              Counters& c, const Leaf& leaf) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  uint node = uint(root);
  while (true) {
    uint a, escape, count;
    // Box steps: follow child and escape links until a leaf whose box the ray meets, or the end.
    bool atLeaf = false;
    while (!atLeaf && node != kEscapeEnd) {
      vec3 bmin, bmax;
      float tEnter;
      c.nodeVisits++;
      c.nodeBytes += kNodeBytes;
      loadNode(s, int(node), bmin, bmax, a, escape, count);
      c.boxTests++;
      if (!Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) {
        // A valid tree's escape link points past its node (every step moves to a higher index); a
        // record whose link does not ends the walk (kEscapeEnd) instead of looping. In a fragment
        // shader llvmpipe hands helper invocations zeros from storage buffers (--storage ssbo;
        // docs/layouts.md), and a record of zeros would spin until the driver's loop limit cut the
        // whole quad short.
        node = escape <= node ? kEscapeEnd : escape;
      } else if (count == 0u) {
        node = node + 1u;
      } else {
        atLeaf = true;
      }
    }
    if (!atLeaf) break;
    for (uint i = 0u; i < count; ++i) {
      int tri = int(a + i);
      float t;
      vec2 bary;
      c.triTests++;
      c.triangleBytes += leaf.bytes();
      if (leaf.test(ray, tri, tMin, hit.t, t, bary)) {
        hit = MeshHit{t, tri, bary};
        if (anyHit) return true;
      }
    }
    node = escape <= node ? kEscapeEnd : escape;
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseStackless<Tests>(s, ray, 0, tMin, tMax, false, hit, c, TriangleLeaf<Tests>{s});
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseStackless<Tests>(s, ray, 0, tMin, tMax, true, hit, c, TriangleLeaf<Tests>{s});
}

}  // namespace bvhlab::glsl::stackless
