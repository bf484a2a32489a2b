// kernel_stack_unordered.hpp — C++ mirror of kernel_stack_unordered.glsl (the report's
// Algorithm 2; stack bound and counter definitions are documented there).
#pragma once
#include "traversal/layout.hpp"
#include "traversal/intersectors.hpp"
#include "traversal/leaf_test.hpp"

namespace bvhlab::glsl::stack_unordered {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: every loadNode reads a v1 node's two texels (layout.glsl), once per node visit, so
//   nodeBytes = 32 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is one int (4 bytes); the root's push, each child's push and each pop count it.
constexpr uint kNodeBytes = bvhlab::kNodeTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(sizeof(int));

// root: the node the walk starts at (GLSL's `root`: 0 for a flat tree); leaf: the test of the leaves'
// primitives (GLSL's KERNEL_LEAF_TEST: traversal/leaf_test.hpp).
template <class Tests, class Leaf>
inline bool traverseUnordered(const Storage& s, Ray ray, int root, float tMin, float tMax, bool anyHit, MeshHit& hit,
                              Counters& c, const Leaf& leaf) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  StackArray<int> stack(s.stackSize);
  int sp = 0;
  stack[sp++] = root;
  c.stackBytes += kStackEntryBytes;
  while (sp > 0) {
    int node = stack[--sp];
    c.stackBytes += kStackEntryBytes;
    vec3 bmin, bmax;
    uint a, escape, count;
    c.nodeVisits++;
    c.nodeBytes += kNodeBytes;
    loadNode(s, node, bmin, bmax, a, escape, count);
    if (count > 0u) {
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
      continue;
    }
    int children[2] = {int(a), node + 1};  // second child pushed first
    for (int k = 0; k < 2; ++k) {
      uint childA, childEscape, childCount;
      float tEnter;
      c.nodeVisits++;
      c.nodeBytes += kNodeBytes;
      loadNode(s, children[k], bmin, bmax, childA, childEscape, childCount);
      c.boxTests++;
      if (!Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) continue;
      if (sp == s.stackSize) {
        c.stackOverflow = true;
        return hit.tri >= 0;
      }
      stack[sp++] = children[k];
      c.stackBytes += kStackEntryBytes;
    }
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseUnordered<Tests>(s, ray, 0, tMin, tMax, false, hit, c, TriangleLeaf<Tests>{s});
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseUnordered<Tests>(s, ray, 0, tMin, tMax, true, hit, c, TriangleLeaf<Tests>{s});
}

}  // namespace bvhlab::glsl::stack_unordered
