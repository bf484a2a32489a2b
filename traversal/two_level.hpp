// two_level.hpp — C++ mirror of two_level.glsl: traceClosest / traceAny over a two-level tree
// (layout/pack_two_level.hpp), the TLAS walk being the kernel's own walk with instances at its
// leaves, each instance test the kernel's walk over the instance's BLAS with the ray in object space.
// Same operations in the same order as the GLSL (its comments give the reasons).
#pragma once
#include <stdexcept>
#include <string>

#include "layout/pack_two_level.hpp"
#include "traversal/kernel_bvh2cb_aila_laine.hpp"
#include "traversal/kernel_bvh2cb_stack.hpp"
#include "traversal/kernel_stack_ordered.hpp"
#include "traversal/kernel_stack_unordered.hpp"
#include "traversal/kernel_stackless.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab::glsl::two_level {

// GLSL's counters: blas = g_nodeVisits, g_triTests, g_boxTests (summed over the BLAS walks); tlas =
// g_tlasNodeVisits, g_instanceTests (tlas.triTests), g_tlasBoxTests. stackOverflow: either walk's.
// The byte counters follow each kernel's definitions; tlas.triangleBytes counts the instance
// records' texels an instance test reads (kInstanceTestTexels).
struct TwoLevelCounters {
  Counters tlas, blas;
};

// A closest hit: hit.tri the TRIANGLE-stream triangle (-1: none), record its instance's record (GLSL
// g_instance; -1: none).
struct TwoLevelHit {
  MeshHit hit{0.0f, -1, vec2(0.0f)};
  int record = -1;
};

// Each kernel's walk under one name, for the templates below (GLSL: KERNEL_WALK).
#define BVHLAB_TWO_LEVEL_WALK(Name, ns, fn)                                                                       \
  struct Name {                                                                                                 \
    template <class Tests, class Leaf>                                                                          \
    static bool walk(const Storage& s, Ray ray, int root, float tMin, float tMax, bool anyHit, MeshHit& hit,  \
                     Counters& c, const Leaf& leaf) {                                                           \
      return ns::fn<Tests>(s, ray, root, tMin, tMax, anyHit, hit, c, leaf);                                     \
    }                                                                                                           \
  };
BVHLAB_TWO_LEVEL_WALK(OrderedWalk, stack_ordered, traverseOrdered)
BVHLAB_TWO_LEVEL_WALK(UnorderedWalk, stack_unordered, traverseUnordered)
BVHLAB_TWO_LEVEL_WALK(StacklessWalk, stackless, traverseStackless)
BVHLAB_TWO_LEVEL_WALK(Bvh2cbWalk, bvh2cb_stack, traverseBvh2cb)
BVHLAB_TWO_LEVEL_WALK(Bvh2cbAilaLaineWalk, bvh2cb_aila_laine, traverseBvh2cbAilaLaine)
#undef BVHLAB_TWO_LEVEL_WALK

// instanceRay of two_level.glsl.
inline Ray instanceRay(const Storage& s, Ray ray, int record, int& root) {
  int base = int(kInstanceTexels) * record;
  vec3 r0 = uintBitsToFloat(uvec3(fetchNode(s, base + 0)));
  vec3 r1 = uintBitsToFloat(uvec3(fetchNode(s, base + 1)));
  vec3 r2 = uintBitsToFloat(uvec3(fetchNode(s, base + 2)));
  uvec4 place = fetchNode(s, base + 6);
  root = int(place.w);
  vec3 p = ray.origin - uintBitsToFloat(uvec3(place));
  vec3 o = vec3(r0.x * p.x + r0.y * p.y + r0.z * p.z, r1.x * p.x + r1.y * p.y + r1.z * p.z,
                r2.x * p.x + r2.y * p.y + r2.z * p.z);
  vec3 d = ray.dir;
  vec3 od = vec3(r0.x * d.x + r0.y * d.y + r0.z * d.z, r1.x * d.x + r1.y * d.y + r1.z * d.z,
                 r2.x * d.x + r2.y * d.y + r2.z * d.z);
  return Ray{o, od};
}

// testInstance of two_level.glsl, as the TLAS walk's leaf test (traversal/leaf_test.hpp).
template <class Tests, class Walk>
struct InstanceLeaf {
  const Storage& s;
  Counters& blas;
  bool anyHit;
  int& blasTri;  // GLSL g_blasTri
  bool test(Ray ray, int record, float tMin, float tMax, float& t, vec2& bary) const {
    int root;
    Ray objectRay = instanceRay(s, ray, record, root);
    MeshHit hit;
    bool found = Walk::template walk<Tests>(s, objectRay, root, tMin, tMax, anyHit, hit, blas, TriangleLeaf<Tests>{s});
    t = hit.t;
    bary = hit.bary;
    if (found) blasTri = hit.tri;
    return found;
  }
  uint bytes() const { return kInstanceTestTexels * kTexelBytes; }
};

template <class Tests, class Walk>
inline bool traceClosest(const Storage& s, Ray ray, float tMin, float tMax, TwoLevelHit& out, TwoLevelCounters& c) {
  int blasTri = -1;
  int root = int(fetchNode(s, 0).x);
  MeshHit hit;
  bool found = Walk::template walk<Tests>(s, ray, root, tMin, tMax, false, hit, c.tlas,
                                          InstanceLeaf<Tests, Walk>{s, c.blas, false, blasTri});
  out.record = found ? hit.tri : -1;
  hit.tri = found ? blasTri : -1;
  out.hit = hit;
  return found;
}

template <class Tests, class Walk>
inline bool traceAny(const Storage& s, Ray ray, float tMin, float tMax, TwoLevelCounters& c) {
  int blasTri = -1;
  MeshHit hit;
  return Walk::template walk<Tests>(s, ray, int(fetchNode(s, 0).x), tMin, tMax, true, hit, c.tlas,
                                    InstanceLeaf<Tests, Walk>{s, c.blas, true, blasTri});
}

// instanceNormalToWorld of two_level.glsl: transpose(L^-1) n, not normalised.
inline vec3 instanceNormalToWorld(const Storage& s, int record, vec3 n) {
  int base = int(kInstanceTexels) * record;
  vec3 r0 = uintBitsToFloat(uvec3(fetchNode(s, base + 0)));
  vec3 r1 = uintBitsToFloat(uvec3(fetchNode(s, base + 1)));
  vec3 r2 = uintBitsToFloat(uvec3(fetchNode(s, base + 2)));
  return r0 * n.x + r1 * n.y + r2 * n.z;
}

inline uint instanceId(const Storage& s, int record) { return fetchNode(s, int(kInstanceTexels) * record + 7).x; }

}  // namespace bvhlab::glsl::two_level

namespace bvhlab {

// A kernel's two-level mirror, instantiated with one (triangle test, box test) pair.
using TwoLevelClosestFn = bool (*)(const glsl::Storage&, glsl::Ray, float tMin, float tMax, glsl::two_level::TwoLevelHit&,
                                   glsl::two_level::TwoLevelCounters&);
using TwoLevelAnyFn = bool (*)(const glsl::Storage&, glsl::Ray, float tMin, float tMax,
                               glsl::two_level::TwoLevelCounters&);
struct TwoLevelMirror {
  TwoLevelClosestFn closest;
  TwoLevelAnyFn any;
};

// Whether `kernel` has a two-level walk (the assembler refuses the others): the v1 kernels and
// the bvh2-cb kernels.
bool hasTwoLevelWalk(const std::string& kernel);
// The mirror of `kernel` over a two-level tree with robustness r's tests. Throws
// std::invalid_argument for a kernel without a two-level walk, naming those with one.
TwoLevelMirror twoLevelMirror(const std::string& kernel, Robustness r);

}  // namespace bvhlab
