// kernel_cwbvh_groups.hpp — C++ mirror of kernel_cwbvh_groups.glsl (node groups, lazy triangle groups
// and quantised plane tests over layout cwbvh, as Ylitie, Karras & Laine 2017 traverse it; the order,
// the plane arithmetic, the NaN argument, the stack bound and the counters are documented there).
// BVH_BOX_ROBUST is the robust box test of the Tests pair (if constexpr below).
#pragma once
#include <type_traits>

#include "traversal/intersectors.hpp"
#include "traversal/layout_cwbvh.hpp"

namespace bvhlab::glsl::cwbvh_groups {

// Bytes fetched (Counters::nodeBytes, triangleBytes, stackBytes), counted where the GLSL reads:
// - node: the root's grid box reads the root's first texel (cwbvhGridBox), then every visited node is
//   read whole by loadCwNode, five texels; so nodeBytes = 16 + 80 x nodeVisits;
// - triangle: every triangle test fetches the record in the tree's format (triangleTestBytes);
// - stack: an entry is one node group, a uvec2 (8 bytes), counted when pushed and when popped. The
//   current node group and the triangle group live in registers and are not counted.
constexpr uint kRootBoxBytes = 1u * kTexelBytes;
constexpr uint kNodeBytes = bvhlab::kCwbvhNodeTexels * kTexelBytes;
constexpr uint kStackEntryBytes = uint(sizeof(uvec2));
static_assert(kStackEntryBytes == 8, "a node group is two uints");

constexpr float kCwbvhMaxScaledInverse = 0x1p119f;  // 2^119: 255 * 2^119 < FLT_MAX

template <class T>
struct UsesRobustBox : std::false_type {};
template <TriangleTest Triangle>
struct UsesRobustBox<Tests<Triangle, BoxTest::Robust>> : std::true_type {};

inline uint cwbvhOctant(vec3 invDir) {
  return (invDir.x < 0.0f ? 1u : 0u) | (invDir.y < 0.0f ? 2u : 0u) | (invDir.z < 0.0f ? 4u : 0u);
}

inline uint cwbvhHitBit(uint slot, uint octInv) { return slot ^ octInv; }
inline uint cwbvhSlotOfBit(uint bit, uint octInv) { return bit ^ octInv; }

inline uint cwbvhEnterBits(float t) {
  uint b = floatBitsToUint(t);
  return (b & 0x80000000u) != 0u ? (b + 0xFFFFu) >> 16 : b >> 16;
}
inline float cwbvhEnterBound(uint bits16) { return uintBitsToFloat(bits16 << 16); }

inline void cwbvhScaledInverse(vec3 scale, vec3 invDir, vec3& sLo, vec3& sHi) {
  vec3 s = clamp(scale * invDir, vec3(-kCwbvhMaxScaledInverse), vec3(kCwbvhMaxScaledInverse));
  uvec3 b = floatBitsToUint(s);
  sLo = uintBitsToFloat(b & 0xFFFFFF00u);
  sHi = uintBitsToFloat((b + 0xFFu) & 0xFFFFFF00u);
}

inline uvec2 cwbvhPlaneBytes(const CwNode& n, uint a) {
  return a == 0u   ? uvec2(n.q0.x, n.q0.y)
         : a == 1u ? uvec2(n.q0.z, n.q0.w)
         : a == 2u ? uvec2(n.q1.x, n.q1.y)
         : a == 3u ? uvec2(n.q1.z, n.q1.w)
         : a == 4u ? uvec2(n.q2.x, n.q2.y)
                   : uvec2(n.q2.z, n.q2.w);
}

inline uint cwbvhLeafFirst(const CwNode& n, uint c) {
  uint first = n.triBase;
  for (uint j = 0u; j < c; ++j) {
    uint meta = cwbvhMeta(n, j);
    if (meta != kCwbvhMetaInner) first += meta;
  }
  return first;
}

template <class Tests>
inline bool traverseCwbvhGroups(const Storage& s, Ray ray, float tMin, float tMax, bool anyHit, MeshHit& hit,
                                Counters& c) {
  constexpr bool robustBox = UsesRobustBox<Tests>::value;
  hit = MeshHit{tMax, -1, vec2(0.0f)};
  vec3 invDir = Tests::rayInverseDirection(ray.dir);
  uint octInv = 7u - cwbvhOctant(invDir);
  bvec3 negative = lessThan(invDir, vec3(0.0f));
  bvec3 parallel = greaterThanEqual(abs(invDir), vec3(kParallelInverse));
  bool anyParallel = any(parallel);
  StackArray<uvec2> stack(s.stackSize);
  int sp = 0;

  vec3 bmin, bmax;
  float tEnter;
  c.nodeBytes += kRootBoxBytes;
  cwbvhGridBox(s, 0u, bmin, bmax);
  c.boxTests++;
  if (!Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  uvec2 group = uvec2(0u, (1u << cwbvhHitBit(0u, octInv)) | (1u << 8) | (cwbvhEnterBits(tEnter) << 16));
  uint bit = cwbvhHitBit(0u, octInv);  // the child the next step takes from the group
  while (true) {
    group.y &= ~(1u << bit);
    uint slot = cwbvhSlotOfBit(bit, octInv);
    uint imask = (group.y >> 8) & 0xFFu;
    uint child = group.x + uint(bitCount(imask & ((1u << slot) - 1u)));
    if ((group.y & 0xFFu) != 0u) {
      if (sp == s.stackSize) {
        c.stackOverflow = true;
        return hit.tri >= 0;
      }
      stack[sp] = group;  // CW_STACK_PUSH (kernel_cwbvh_groups.glsl: a local or a short shared stack)
      sp++;
      c.stackBytes += kStackEntryBytes;
    }
    c.nodeVisits++;
    c.nodeBytes += kNodeBytes;
    CwNode node = loadCwNode(s, child);
    vec3 sLo, sHi;
    cwbvhScaledInverse(node.scale, invDir, sLo, sHi);
    vec3 off = (node.p - ray.origin) * invDir;
    vec3 sNear = mix(sLo, sHi, negative);
    vec3 sFar = mix(sHi, sLo, negative);
    uvec2 nearX = cwbvhPlaneBytes(node, negative.x ? 3u : 0u), farX = cwbvhPlaneBytes(node, negative.x ? 0u : 3u);
    uvec2 nearY = cwbvhPlaneBytes(node, negative.y ? 4u : 1u), farY = cwbvhPlaneBytes(node, negative.y ? 1u : 4u);
    uvec2 nearZ = cwbvhPlaneBytes(node, negative.z ? 5u : 2u), farZ = cwbvhPlaneBytes(node, negative.z ? 2u : 5u);
    uint nodeHits = 0u, innerSlots = 0u, triHits = 0u;
    float groupEnter = INF;
    uint nearestBit = 0u;
    uvec4 leafEnter = uvec4(0u);
    for (uint i = 0u; i < 8u; ++i) {
      uint meta = cwbvhMeta(node, i);
      if (meta == 0u) continue;
      bool inner = meta == kCwbvhMetaInner;
      if (inner) innerSlots |= 1u << i;
      c.boxTests++;
      bool met;
      float enter;
      if constexpr (robustBox) {
        cwbvhChildBox(node, i, bmin, bmax);
        met = Tests::intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, enter);
      } else {
        vec3 tNear = vec3(uvec3(cwbvhByte(nearX, i), cwbvhByte(nearY, i), cwbvhByte(nearZ, i))) * sNear + off;
        vec3 tFar = vec3(uvec3(cwbvhByte(farX, i), cwbvhByte(farY, i), cwbvhByte(farZ, i))) * sFar + off;
        if (anyParallel) {
          cwbvhChildBox(node, i, bmin, bmax);
          bvec3 inSlab = equal(clamp(ray.origin, bmin, bmax), ray.origin);
          tNear = mix(tNear, mix(vec3(INF), vec3(-INF), inSlab), parallel);
          tFar = mix(tFar, mix(vec3(-INF), vec3(INF), inSlab), parallel);
        }
        enter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
        float exit = min(min(tFar.x, tFar.y), min(tFar.z, hit.t));
        met = enter <= exit;
      }
      if (met) {
        if (inner) {
          nodeHits |= 1u << cwbvhHitBit(i, octInv);
          if (enter < groupEnter) nearestBit = cwbvhHitBit(i, octInv);
          groupEnter = min(groupEnter, enter);
        } else {
          triHits |= 1u << cwbvhHitBit(i, octInv);
          leafEnter[int(i >> 1)] |= cwbvhEnterBits(enter) << (16u * (i & 1u));
        }
      }
    }
    group = uvec2(node.childBase, nodeHits | (innerSlots << 8) | (cwbvhEnterBits(groupEnter) << 16));
    while (triHits != 0u) {
      uint tbit = uint(findMSB(triHits));
      triHits &= ~(1u << tbit);
      uint leaf = cwbvhSlotOfBit(tbit, octInv);
      if (cwbvhEnterBound((leafEnter[int(leaf >> 1)] >> (16u * (leaf & 1u))) & 0xFFFFu) > hit.t) continue;
      uint first = cwbvhLeafFirst(node, leaf);
      uint count = cwbvhMeta(node, leaf);
      for (uint i = 0u; i < count; ++i) {
        int tri = int(first + i);
        float t;
        vec2 bary;
        c.triTests++;
        c.triangleBytes += triangleTestBytes(s);
        if (Tests::testTriangle(s, ray, tri, tMin, hit.t, t, bary)) {
          hit = MeshHit{t, tri, bary};
          if (anyHit) return true;
        }
      }
    }
    bit = nearestBit;
    while ((group.y & 0xFFu) == 0u || cwbvhEnterBound(group.y >> 16) > hit.t) {
      if (sp == 0) return hit.tri >= 0;
      group = stack[sp - 1];  // CW_STACK_POP
      sp--;
      c.stackBytes += kStackEntryBytes;
      bit = uint(findMSB(group.y & 0xFFu));
    }
  }
  return hit.tri >= 0;
}

template <class Tests = FastTests>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, MeshHit& hit, Counters& c) {
  return traverseCwbvhGroups<Tests>(s, ray, tMin, tMax, false, hit, c);
}

template <class Tests = FastTests>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, Counters& c) {
  MeshHit hit;
  return traverseCwbvhGroups<Tests>(s, ray, tMin, tMax, true, hit, c);
}

}  // namespace bvhlab::glsl::cwbvh_groups
