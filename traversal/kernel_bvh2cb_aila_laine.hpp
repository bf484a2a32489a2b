// kernel_bvh2cb_aila_laine.hpp — C++ mirror of kernel_bvh2cb_aila_laine.glsl (Aila & Laine's
// while-while traversal with postponed leaves over layout bvh2-cb; the walk, the per-ray vote, the
// stack bound, NaN handling and the counter definitions are documented there).
#pragma once
#include "traversal/intersectors.hpp"
#include "traversal/leaf_test.hpp"
#include "traversal/layout_bvh2cb.hpp"

namespace bvhlab::glsl::bvh2cb_aila_laine {

// GLSL's kAlDone: the count of the entry past the stack's bottom (the walk is over).
constexpr uint kAlDone = 0xFFFFFFFEu;
static_assert(kAlDone != bvhlab::kBvh2cbInner);

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads, as
// bvh2cb-stack-ordered counts them:
// - node: every loadRecord reads the record's four texels, so nodeBytes = 64 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is a link, a count and an entry distance (12 bytes); each push counts it, and so
//   does each entry leaving the stack, popped or dropped beyond the hit. The postponed leaf is held in
//   registers and costs no stack bytes.
constexpr uint kNodeBytes = bvhlab::kBvh2cbRecordTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(2 * sizeof(uint) + sizeof(float));

// root: the node the walk starts at (GLSL's `root`: 0 for a flat tree); leaf: the test of the leaves'
// primitives (GLSL's KERNEL_LEAF_TEST: traversal/leaf_test.hpp).
template <class Tests, class Leaf>
inline bool traverseBvh2cbAilaLaine(const Storage& s, Ray ray, int root, float tMin, float tMax, bool anyHit,
                                    MeshHit& hit, Counters& c, const Leaf& leaf) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  StackArray<uint> stackLink(s.stackSize);
  StackArray<uint> stackCount(s.stackSize);
  StackArray<float> stackEnter(s.stackSize);
  int sp = 0;

  uint link = uint(root);
  uint count = kBvh2cbInner;
  uint leafLink = 0u;
  uint leafCount = kAlDone;
  // AL_TAKE_NEXT_ENTRY: entries beyond the closest hit dropped, then the top popped into (link, count),
  // or count = kAlDone when none is left; each entry leaving the stack counted.
  auto takeNextEntry = [&] {
    while (sp > 0 && stackEnter[sp - 1] > hit.t) {
      sp--;
      c.stackBytes += kStackEntryBytes;
    }
    if (sp == 0) {
      count = kAlDone;
    } else {
      sp--;
      c.stackBytes += kStackEntryBytes;
      link = stackLink[sp];
      count = stackCount[sp];
    }
  };
  while (count != kAlDone) {
    bool searchingLeaf = true;
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
          count = kAlDone;  // stop: no loop goes on
          leafCount = kAlDone;
          break;
        }
        bool bFirst = bEnter < aEnter;
        stackLink[sp] = bFirst ? aLink : bLink;
        stackCount[sp] = bFirst ? aCount : bCount;
        stackEnter[sp] = bFirst ? aEnter : bEnter;
        sp++;
        c.stackBytes += kStackEntryBytes;
        link = bFirst ? bLink : aLink;
        count = bFirst ? bCount : aCount;
      } else if (hitA || hitB) {
        link = hitA ? aLink : bLink;
        count = hitA ? aCount : bCount;
      } else {  // neither: pop (entries entered beyond the closest hit would fail their box test now: dropped)
        takeNextEntry();  // AL_TAKE_NEXT_ENTRY
      }
      // The first leaf (reached or popped): postpone it and go on with the next entry.
      if (count < kAlDone && leafCount == kAlDone) {
        searchingLeaf = false;
        leafLink = link;
        leafCount = count;
        takeNextEntry();  // AL_TAKE_NEXT_ENTRY
      }
      if (!searchingLeaf) break;
    }
    while (leafCount != kAlDone) {
      for (uint i = 0u; i < leafCount; ++i) {
        int tri = int(leafLink + i);
        float t;
        vec2 bary;
        c.triTests++;
        c.triangleBytes += leaf.bytes();
        if (leaf.test(ray, tri, tMin, hit.t, t, bary)) {
          hit = MeshHit{t, tri, bary};
          if (anyHit) {
            count = kAlDone;
            break;
          }
        }
      }
      bool isLeaf = count < kAlDone;
      leafLink = link;
      leafCount = isLeaf ? count : kAlDone;
      if (isLeaf) {
        takeNextEntry();  // AL_TAKE_NEXT_ENTRY
      }
    }
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseBvh2cbAilaLaine<Tests>(s, ray, 0, tMin, tMax, false, hit, c, TriangleLeaf<Tests>{s});
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseBvh2cbAilaLaine<Tests>(s, ray, 0, tMin, tMax, true, hit, c, TriangleLeaf<Tests>{s});
}

}  // namespace bvhlab::glsl::bvh2cb_aila_laine
