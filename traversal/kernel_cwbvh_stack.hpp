// kernel_cwbvh_stack.hpp — C++ mirror of kernel_cwbvh_stack.glsl (ordered stack over layout cwbvh;
// root entry, stack bound, NaN handling and counter definitions are documented there).
#pragma once
#include "traversal/intersectors.hpp"
#include "traversal/layout_cwbvh.hpp"

namespace bvhlab::glsl::cwbvh_stack {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: the root's grid box reads the root's first texel (cwbvhGridBox), then every visited node
//   is read whole by loadCwNode, five texels (origin and scales, bases and meta bytes, three texels
//   of quantised child planes: layout_cwbvh.glsl); decoding its child boxes reads no more. So
//   nodeBytes = 16 + 80 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is a link, a count and an entry distance (uint + uint + float, 12 bytes); each
//   push counts it, each entry the insertion sort shifts up counts it twice (read and written; the
//   comparisons' reads of stackEnter are not counted apart), and each entry leaving the stack counts
//   it, popped or dropped beyond the hit.
constexpr uint kRootBoxBytes = 1u * kTexelBytes;
constexpr uint kNodeBytes = bvhlab::kCwbvhNodeTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(2 * sizeof(uint) + sizeof(float));

constexpr uint kCwbvhInner = 0x80000000u;

template <class Tests>
inline bool traverseCwbvh(const Storage& s, Ray ray, float tMin, float tMax, bool anyHit, MeshHit& hit, Counters& c) {
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  StackArray<uint> stackLink(s.stackSize);
  StackArray<uint> stackCount(s.stackSize);
  StackArray<float> stackEnter(s.stackSize);
  int sp = 0;

  vec3 bmin, bmax;
  float tEnter;
  c.nodeBytes += kRootBoxBytes;
  cwbvhGridBox(s, 0u, bmin, bmax);
  c.boxTests++;
  if (!Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  uint link = 0u;
  uint count = kCwbvhInner;
  while (true) {
    if (count == kCwbvhInner) {
      c.nodeVisits++;
      c.nodeBytes += kNodeBytes;
      CwNode node = loadCwNode(s, link);
      int first = sp;
      uint nearLink = 0u, nearCount = 0u;
      float nearEnter = 0.0f;
      bool met = false;
      uint innerRank = 0u, triOffset = 0u;
      for (uint i = 0u; i < 8u; ++i) {  // the 8 slots; an empty one (meta 0) is skipped untested
        uint meta = cwbvhMeta(node, i);
        if (meta == 0u) continue;
        uint childLink, childCount;
        if (meta == kCwbvhMetaInner) {
          childLink = node.childBase + innerRank;
          childCount = kCwbvhInner;
          innerRank++;
        } else {
          childLink = node.triBase + triOffset;
          childCount = meta;
          triOffset += meta;
        }
        float enter;
        cwbvhChildBox(node, i, bmin, bmax);
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
    if (count != kCwbvhInner) {
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
  return traverseCwbvh<Tests>(s, ray, tMin, tMax, false, hit, c);
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseCwbvh<Tests>(s, ray, tMin, tMax, true, hit, c);
}

}  // namespace bvhlab::glsl::cwbvh_stack
