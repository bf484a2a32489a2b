// kernel_bvh2cb_aila_laine.glsl — Aila & Laine's traversal over layout bvh2-cb (layout/layout_bvh2cb.hpp):
// "Understanding the Efficiency of Ray Traversal on GPUs" (HPG 2009) and its 2012 addendum with Karras,
// the "speculative while-while" kernel. C++ mirror: kernel_bvh2cb_aila_laine.hpp.
//
// The walk: the inner loop fetches records (both child boxes at once), goes on with the nearer child
// met and pushes the farther one, and pops when neither is met. The first leaf it reaches is not tested
// at once but POSTPONED (held in registers) and the walk goes on with the next stack entry; the inner
// loop ends when the ray has a postponed leaf (or the walk is over). The leaf loop then tests the
// postponed leaf and, while the current entry is also a leaf, that one too (popping after each), so
// two leaves met back to back are tested in one leaf loop. Then the inner loop starts again.
//
// The paper ends the inner loop when EVERY lane of the warp has a postponed leaf (a warp vote, __any),
// so that lanes keep fetching nodes speculatively instead of idling while others reach their leaf. A
// vote makes a ray's work depend on the rays beside it, which no per-ray mirror can reproduce; this
// kernel votes per ray (`searchingLeaf` of the ray itself, the `break` below), which is exactly what
// the mirror does, so every counter is the mirror's ray for ray. What remains of the speculation per
// ray is the postponement: a leaf met while another is postponed is tested in the same leaf loop.
//
// Differences from the paper's kernel, from values already in registers: a stack entry carries its entry
// distance, and a pop drops the entries entered beyond the closest hit found since without fetching
// them (as bvh2cb-stack-ordered; the paper re-fetches them and fails their boxes); a leaf is a slot's
// (link, count) rather than a negative index into a sentinel-terminated triangle list; the end of the
// walk is the count kAlDone rather than a sentinel entry at the stack's bottom.
//
// Stack bound: as bvh2cb-stack-ordered's (kernel_bvh2cb_stack.glsl). Every entry on the stack is the
// farther child of a record on the path from the root to the current entry, at most one per record,
// and a postponed leaf is held in registers, never on the stack; a pop only shortens the path. So at
// most D - 1 entries for a tree of depth D >= 2, at most 1 for the single-leaf tree (one record):
// BVH_STACK_SIZE = stackSizeFor(D) = max(1, D).
//
// Order and NaN: as bvh2cb-stack-ordered's: a NaN entry distance makes `bEnter < aEnter` false (A
// first) and the pop test `entry > hit.t` false (walked, never dropped). NaN costs work, never a hit.
//
// Counters: g_nodeVisits += 1 per record fetched (loadRecord), g_boxTests += 2 per record (one per
// intersectAabb call), g_triTests += 1 per KERNEL_LEAF_TEST call: the definitions of
// bvh2cb-stack-ordered, so the two kernels' counts compare one to one.
//
// No `return` inside the loops (an any hit or a stack overflow ends them through kAlDone instead):
// under persistent threads the walk is inlined into trace_rays.glsl's loop over rays, and there Mesa's
// llvmpipe (Mesa 22.3, LLVM 15) answered some any-hit rays "hit" that had tested no triangle when the
// walk returned from inside its loops (LayoutKernelsGlsl.EqualTheMirrorPerRay caught it).
//
// Compute path (shaders/trace_rays.glsl): this kernel is registered with persistent threads
// (KernelInfo::persistentThreads): a fixed number of invocations loop, taking batches of rays from an
// atomic counter, one batch per subgroup where GL_KHR_shader_subgroup_ballot is available (not on
// llvmpipe by default: traversal/kernels.hpp persistentThreadsOn says why).

#ifndef KERNEL_WALK
#define KERNEL_WALK traverseBvh2cbAilaLaine
#define KERNEL_LEAF_TEST testTriangle
#endif

#ifndef BVH2CB_AILA_LAINE_DONE
#define BVH2CB_AILA_LAINE_DONE
// The count of the entry past the stack's bottom: the walk is over. A leaf's count is below it, an inner
// child's is kBvh2cbInner (above it).
const uint kAlDone = 0xFFFFFFFEu;
// The next entry into (link, count): entries entered beyond the closest hit are dropped (they would
// fail their box test now), then the top is popped, or count = kAlDone when none is left. A macro, not
// a function: GLSL would copy the stack arrays in and out of an inout parameter.
#define AL_TAKE_NEXT_ENTRY()                             \
  while (sp > 0 && stackEnter[sp - 1] > hit.t) sp--;     \
  if (sp == 0) {                                         \
    count = kAlDone;                                     \
  } else {                                               \
    sp--;                                                \
    link = stackLink[sp];                                \
    count = stackCount[sp];                              \
  }
#endif

bool KERNEL_WALK(Ray ray, int root, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  uint stackLink[BVH_STACK_SIZE];
  uint stackCount[BVH_STACK_SIZE];
  float stackEnter[BVH_STACK_SIZE];
  int sp = 0;

  uint link = uint(root);  // the current entry: the root record
  uint count = kBvh2cbInner;
  uint leafLink = 0u;  // the postponed leaf: none
  uint leafCount = kAlDone;
  while (count != kAlDone) {
    // Inner loop: records until the ray has postponed a leaf.
    bool searchingLeaf = true;
    while (count == kBvh2cbInner) {
      vec3 aMin, aMax, bMin, bMax;
      uint aLink, aCount, bLink, bCount;
      float aEnter, bEnter;
      g_nodeVisits++;
      loadRecord(int(link), aMin, aMax, aLink, aCount, bMin, bMax, bLink, bCount);
      g_boxTests++;
      bool hitA = intersectAabb(ray.origin, invDir, aMin, aMax, tMin, hit.t, aEnter);
      g_boxTests++;
      bool hitB = intersectAabb(ray.origin, invDir, bMin, bMax, tMin, hit.t, bEnter);
      if (hitA && hitB) {
        if (sp == BVH_STACK_SIZE) {
          g_stackOverflow = true;  // stop: the result so far is incomplete, the flag says so
          count = kAlDone;  // stop: no loop goes on
          leafCount = kAlDone;
          break;
        }
        bool bFirst = bEnter < aEnter;
        stackLink[sp] = bFirst ? aLink : bLink;
        stackCount[sp] = bFirst ? aCount : bCount;
        stackEnter[sp] = bFirst ? aEnter : bEnter;
        sp++;
        link = bFirst ? bLink : aLink;
        count = bFirst ? bCount : aCount;
      } else if (hitA || hitB) {
        link = hitA ? aLink : bLink;
        count = hitA ? aCount : bCount;
      } else {  // neither: pop (entries entered beyond the closest hit would fail their box test now: dropped)
        AL_TAKE_NEXT_ENTRY();
      }
      // The first leaf (reached or popped): postpone it and go on with the next entry.
      if (count < kAlDone && leafCount == kAlDone) {
        searchingLeaf = false;
        leafLink = link;
        leafCount = count;
        AL_TAKE_NEXT_ENTRY();
      }
      // The paper's warp vote (__any(searchingLeaf)), taken per ray: see the header.
      if (!searchingLeaf) break;
    }
    // Leaf loop: the postponed leaf, then the current entry while it is a leaf too.
    while (leafCount != kAlDone) {
      for (uint i = 0u; i < leafCount; ++i) {
        int tri = int(leafLink + i);
        float t;
        vec2 bary;
        g_triTests++;
        if (KERNEL_LEAF_TEST(ray, tri, tMin, hit.t, t, bary)) {
          hit = MeshHit(t, tri, bary);
          if (anyHit) {  // done: the loops end with no entry left
            count = kAlDone;
            break;
          }
        }
      }
      bool isLeaf = count < kAlDone;
      leafLink = link;
      leafCount = isLeaf ? count : kAlDone;
      if (isLeaf) {
        AL_TAKE_NEXT_ENTRY();
      }
    }
  }
  return hit.tri >= 0;
}

#ifndef TWO_LEVEL  // two_level.glsl defines the entry points of a two-level tree
// Closest hit with tMin < t < tMax; hit.tri = -1 and hit.t = tMax when there is none.
bool traceClosest(Ray ray, float tMin, float tMax, out MeshHit hit) {
  return KERNEL_WALK(ray, 0, tMin, tMax, false, hit);
}

// Any hit with tMin < t < tMax (shadow rays): the same walk, stopped at the first hit.
bool traceAny(Ray ray, float tMin, float tMax) {
  MeshHit hit;
  return KERNEL_WALK(ray, 0, tMin, tMax, true, hit);
}
#endif
