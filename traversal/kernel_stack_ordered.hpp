// kernel_stack_ordered.hpp — C++ mirror of kernel_stack_ordered.glsl (nearest child first; stack
// bound and counter definitions are documented there).
#pragma once
#include "traversal/layout.hpp"
#include "traversal/intersectors.hpp"
#include "traversal/leaf_test.hpp"

namespace bvhlab::glsl::stack_ordered {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: every loadNode reads a v1 node's two texels (layout.glsl), once per node visit (the root,
//   both children of each inner node, each popped node), so nodeBytes = 32 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is a node index and its entry distance (int + float, 8 bytes); each push counts
//   it, and so does each entry leaving the stack, whether popped to be visited or dropped because
//   its entry distance lies beyond the closest hit.
constexpr uint kNodeBytes = bvhlab::kNodeTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(sizeof(int) + sizeof(float));

// root: the node the walk starts at (GLSL's `root`: 0 for a flat tree); leaf: the test of the leaves'
// primitives (GLSL's KERNEL_LEAF_TEST: traversal/leaf_test.hpp).
template <class Tests, class Leaf>
inline bool traverseOrdered(const Storage& s, Ray ray, int root, float tMin, float tMax, bool anyHit, MeshHit& hit,
                            Counters& c, const Leaf& leaf) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  StackArray<int> stackNode(s.stackSize);
  StackArray<float> stackEnter(s.stackSize);
  int sp = 0;

  int node = root;
  vec3 bmin, bmax;
  uint a, escape, count;
  float tEnter;
  c.nodeVisits++;
  c.nodeBytes += kNodeBytes;
  loadNode(s, node, bmin, bmax, a, escape, count);
  c.boxTests++;
  if (!Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  while (true) {
    // Inner loop: descend while the current node is inner and a child is met.
    bool met = true;
    while (count == 0u && met) {
      int left = node + 1;
      int right = int(a);
      uint leftA, leftCount, rightA, rightCount;
      float leftEnter, rightEnter;
      c.nodeVisits++;
      c.nodeBytes += kNodeBytes;
      loadNode(s, left, bmin, bmax, leftA, escape, leftCount);
      c.boxTests++;
      bool hitLeft = Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, leftEnter);
      c.nodeVisits++;
      c.nodeBytes += kNodeBytes;
      loadNode(s, right, bmin, bmax, rightA, escape, rightCount);
      c.boxTests++;
      bool hitRight = Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, rightEnter);
      if (hitLeft && hitRight) {
        if (sp == s.stackSize) {
          c.stackOverflow = true;
          return hit.tri >= 0;
        }
        bool leftFirst = leftEnter <= rightEnter;
        stackNode[sp] = leftFirst ? right : left;
        stackEnter[sp] = leftFirst ? rightEnter : leftEnter;
        sp++;
        c.stackBytes += kStackEntryBytes;
        node = leftFirst ? left : right;
        a = leftFirst ? leftA : rightA;
        count = leftFirst ? leftCount : rightCount;
      } else {
        // Neither child met: count 0 ends this loop with no triangles; node and a are not read again
        // before the pop reloads them.
        met = hitLeft || hitRight;
        node = hitLeft ? left : right;
        a = hitLeft ? leftA : rightA;
        count = hitLeft ? leftCount : hitRight ? rightCount : 0u;
      }
    }
    // Leaf: its triangles (none when the inner loop ended on a node whose children both miss).
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
    while (sp > 0 && stackEnter[sp - 1] > hit.t) {
      sp--;
      c.stackBytes += kStackEntryBytes;
    }
    if (sp == 0) break;
    node = stackNode[--sp];
    c.stackBytes += kStackEntryBytes;
    c.nodeVisits++;
    c.nodeBytes += kNodeBytes;
    loadNode(s, node, bmin, bmax, a, escape, count);
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseOrdered<Tests>(s, ray, 0, tMin, tMax, false, hit, c, TriangleLeaf<Tests>{s});
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseOrdered<Tests>(s, ray, 0, tMin, tMax, true, hit, c, TriangleLeaf<Tests>{s});
}

}  // namespace bvhlab::glsl::stack_ordered
