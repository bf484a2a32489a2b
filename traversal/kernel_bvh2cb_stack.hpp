// kernel_bvh2cb_stack.hpp — C++ mirror of kernel_bvh2cb_stack.glsl (ordered stack over layout
// bvh2-cb; stack bound, NaN handling and counter definitions are documented there).
#pragma once
#include "traversal/intersectors.hpp"
#include "traversal/leaf_test.hpp"
#include "traversal/layout_bvh2cb.hpp"

namespace bvhlab::glsl::bvh2cb_stack {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: every loadRecord reads a bvh2-cb record's four texels (both children's boxes, links and
//   counts: layout_bvh2cb.glsl), once per node visit, so nodeBytes = 64 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is a link, a count and an entry distance (uint + uint + float, 12 bytes); each
//   push counts it, and so does each entry leaving the stack, popped or dropped beyond the hit.
constexpr uint kNodeBytes = bvhlab::kBvh2cbRecordTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(2 * sizeof(uint) + sizeof(float));

// root: the node the walk starts at (GLSL's `root`: 0 for a flat tree); leaf: the test of the leaves'
// primitives (GLSL's KERNEL_LEAF_TEST: traversal/leaf_test.hpp).
template <class Tests, class Leaf>
inline bool traverseBvh2cb(const Storage& s, Ray ray, int root, float tMin, float tMax, bool anyHit, MeshHit& hit,
                           Counters& c, const Leaf& leaf) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  StackArray<uint> stackLink(s.stackSize);
  StackArray<uint> stackCount(s.stackSize);
  StackArray<float> stackEnter(s.stackSize);
  int sp = 0;

  uint link = uint(root);
  uint count = kBvh2cbInner;
  while (true) {
    while (count == kBvh2cbInner) {
      vec3 aMin, aMax, bMin, bMax;
      uint aLink, aCount, bLink, bCount;
      float aEnter, bEnter;
      c.nodeVisits++;
      c.nodeBytes += kNodeBytes;
      loadRecord(s, int(link), aMin, aMax, aLink, aCount, bMin, bMax, bLink, bCount);
      c.boxTests++;
      bool hitA = Tests::intersectAabb(ray.origin, invDir, aMin, aMax, tMin, hit.t, aEnter);
      c.boxTests++;
      bool hitB = Tests::intersectAabb(ray.origin, invDir, bMin, bMax, tMin, hit.t, bEnter);
      if (hitA && hitB) {
        if (sp == s.stackSize) {
          c.stackOverflow = true;
          return hit.tri >= 0;
        }
        bool bFirst = bEnter < aEnter;
        stackLink[sp] = bFirst ? aLink : bLink;
        stackCount[sp] = bFirst ? aCount : bCount;
        stackEnter[sp] = bFirst ? aEnter : bEnter;
        sp++;
        c.stackBytes += kStackEntryBytes;
        link = bFirst ? bLink : aLink;
        count = bFirst ? bCount : aCount;
      } else {
        link = hitA ? aLink : bLink;
        count = hitA ? aCount : hitB ? bCount : 0u;
      }
    }
    for (uint i = 0u; i < count; ++i) {
      int tri = int(link + i);
      float t;
      vec2 bary;
      c.triTests++;
      c.triangleBytes += leaf.bytes();
      if (leaf.test(ray, tri, tMin, hit.t, t, bary)) {
        hit = MeshHit{t, tri, bary};
        if (anyHit) return true;
      }
    }
    while (sp > 0 && stackEnter[sp - 1] > hit.t) {
      sp--;
      c.stackBytes += kStackEntryBytes;
    }
    if (sp == 0) break;
    sp--;
    c.stackBytes += kStackEntryBytes;
    link = stackLink[sp];
    count = stackCount[sp];
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseBvh2cb<Tests>(s, ray, 0, tMin, tMax, false, hit, c, TriangleLeaf<Tests>{s});
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseBvh2cb<Tests>(s, ray, 0, tMin, tMax, true, hit, c, TriangleLeaf<Tests>{s});
}

}  // namespace bvhlab::glsl::bvh2cb_stack
