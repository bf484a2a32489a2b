// kernel_wide_stack.hpp — C++ mirror of kernel_wide_stack.glsl (ordered stack over layouts bvh4 and
// bvh8; stack bound, NaN handling and counter definitions are documented there).
#pragma once
#include <algorithm>

#include "traversal/intersectors.hpp"
#include "traversal/layout_wide.hpp"

namespace bvhlab::glsl::wide_stack {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: every loadSlot reads one child slot's two texels (box, link, count: layout_wide.glsl): the
//   root's slot once, then each child slot of each visited node, once per box test, so
//   nodeBytes = 32 x boxTests;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is a link, a count and an entry distance (uint + uint + float, 12 bytes); each
//   push counts it, each entry the insertion sort shifts up counts it twice (read and written; the
//   comparisons' reads of stackEnter are not counted apart), and each entry leaving the stack counts
//   it, popped or dropped beyond the hit.
constexpr uint kSlotBytes = bvhlab::kWideSlotTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(2 * sizeof(uint) + sizeof(float));

// FetchWhole = 0: kernel_wide_stack.glsl as it is; = W: with WIDE_FETCH_WHOLE = W (the record's slots
// fetched before its tests; the same walk and counts).
template <class Tests, uint FetchWhole = 0>
inline bool traverseWide(const Storage& s, Ray ray, float tMin, float tMax, bool anyHit, MeshHit& hit,
                         Counters& c) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  StackArray<uint> stackLink(s.stackSize);
  StackArray<uint> stackCount(s.stackSize);
  StackArray<float> stackEnter(s.stackSize);
  int sp = 0;

  vec3 bmin, bmax;
  uint link, count;
  float tEnter;
  c.nodeBytes += kSlotBytes;
  loadSlot(s, 0u, bmin, bmax, link, count);
  c.boxTests++;
  if (!Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  while (true) {
    if (count >= kWideInner) {
      c.nodeVisits++;
      int first = sp;
      uint children = count - kWideInner;
      uint nearLink = 0u, nearCount = 0u;
      float nearEnter = 0.0f;
      bool met = false;
      uvec4 slotLo[FetchWhole > 0 ? FetchWhole : 1], slotHi[FetchWhole > 0 ? FetchWhole : 1];
      if constexpr (FetchWhole > 0) {
        children = std::min(children, FetchWhole);
        for (uint i = 0u; i < children; ++i) {
          slotLo[i] = fetchNode(s, int(link + 2u * i));
          slotHi[i] = fetchNode(s, int(link + 2u * i) + 1);
        }
      }
      for (uint i = 0u; i < children; ++i) {
        uint childLink, childCount;
        float enter;
        c.nodeBytes += kSlotBytes;  // fetched before the loop or here: once per child either way
        if constexpr (FetchWhole > 0)
          decodeSlot(slotLo[i], slotHi[i], bmin, bmax, childLink, childCount);
        else
          loadSlot(s, link + 2u * i, bmin, bmax, childLink, childCount);
        c.boxTests++;
        if (Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, enter)) {
          if (!met) {
            nearLink = childLink;
            nearCount = childCount;
            nearEnter = enter;
            met = true;
            continue;
          }
          if (sp == s.stackSize) {
            c.stackOverflow = true;
            return hit.tri >= 0;
          }
          bool childNearer = enter < nearEnter;
          uint pushLink = childNearer ? nearLink : childLink;
          uint pushCount = childNearer ? nearCount : childCount;
          float pushEnter = childNearer ? nearEnter : enter;
          nearLink = childNearer ? childLink : nearLink;
          nearCount = childNearer ? childCount : nearCount;
          nearEnter = childNearer ? enter : nearEnter;
          int j = sp;
          while (j > first && stackEnter[j - 1] <= pushEnter) {
            stackLink[j] = stackLink[j - 1];
            stackCount[j] = stackCount[j - 1];
            stackEnter[j] = stackEnter[j - 1];
            c.stackBytes += 2u * kStackEntryBytes;  // the shifted entry read and written
            j--;
          }
          stackLink[j] = pushLink;
          stackCount[j] = pushCount;
          stackEnter[j] = pushEnter;
          sp++;
          c.stackBytes += kStackEntryBytes;
        }
      }
      link = nearLink;
      count = met ? nearCount : 0u;
    }
    if (count < kWideInner) {
      for (uint i = 0u; i < count; ++i) {
        int tri = int(link + i);
        float t;
        vec2 bary;
        c.triTests++;
        c.triangleBytes += triangleTestBytes(s);
        if (Tests::testTriangle(s, ray, tri, tMin, hit.t, t, bary)) {
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
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseWide<Tests>(s, ray, tMin, tMax, false, hit, c);
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseWide<Tests>(s, ray, tMin, tMax, true, hit, c);
}

}  // namespace bvhlab::glsl::wide_stack

// bvh4-fetch-whole and bvh8-fetch-whole (WideWhole<4>, WideWhole<8>): kernel_wide_stack.glsl with
// WIDE_FETCH_WHOLE = W.
namespace bvhlab::glsl {
template <uint W>
struct WideWhole {
  template <class Tests = FastTests>
  static bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
    return wide_stack::traverseWide<Tests, W>(s, ray, tMin, tMax, false, hit, c);
  }
  template <class Tests = FastTests>
  static bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
    MeshHit hit;
    return wide_stack::traverseWide<Tests, W>(s, ray, tMin, tMax, true, hit, c);
  }
};
}  // namespace bvhlab::glsl
