// kernel_bvh2cb_stack.glsl — ordered stack traversal over layout bvh2-cb (layout/layout_bvh2cb.hpp):
// one record fetch gives both child boxes; the kernel tests both, walks into the one the ray enters
// first and pushes the other as (link, count, entry distance). A leaf child is walked straight from
// its slot (leaves have no record), and a popped entry whose entry lies beyond the closest hit found
// since is dropped without a fetch. C++ mirror: kernel_bvh2cb_stack.hpp.
//
// Stack bound: the current entry is held in registers, never on the stack. An entry is pushed only at
// a record (an inner node), at most one per record on the path from the root, and it is the farther
// child of a record whose nearer subtree is being walked. For a tree of depth D >= 2 (root alone = 1)
// a path passes at most D - 1 inner nodes, so at most D - 1 entries; the single-leaf tree (D = 1) has
// one record (the leaf and an empty slot) and pushes at most 1. BVH_STACK_SIZE = stackSizeFor(D) =
// max(1, D) covers both.
//
// Order and NaN: the box tests (ray_box*.glsl) never return a NaN entry for a finite ray (finite
// invDir, the parallel case handled without 0 * inf). Should one appear anyway, `bEnter < aEnter` is
// false (A first) and the pop test `entry > hit.t` is false (the entry is walked, never dropped):
// NaN can only cost work, never lose a hit.
//
// Counters: g_nodeVisits += 1 per record fetched (loadRecord): once per inner node entered, the root
// included, whether descended into or popped; its two box tests are not counted separately. A leaf
// costs no visit (its slot came with its parent's record), only its triangle tests. So a bvh2-cb visit
// is a 64-byte fetch where a v1 visit (kernel_stack_ordered.glsl) is a 32-byte one, and the visit
// counts of the two layouts are not comparable one to one. g_triTests += 1 per testTriangle call.
// g_boxTests += 1 per intersectAabb call (two per record).
//
// Loop shape: "while-while" (Aila & Laine 2009): an inner loop runs the inner steps until the entry
// is a leaf (or empty), and only then the triangle loop runs. llvmpipe executes every branch of a
// loop body for all lanes under a mask (it branches only on loop back-edges), so the "if-if" shape,
// which had the triangle loop in every iteration, paid one masked triangle test per inner step:
// 0.77x the time on the bunny's primary rays and 0.80x on its diffuse ones with this shape
// (the runs are in the git history of docs/layouts.md). The walk, and so every counter, is the same in both shapes.

// Two-level trees (traversal/two_level.glsl) assemble this file twice, with KERNEL_WALK naming the
// walk (blasWalk, tlasWalk) and KERNEL_LEAF_TEST the test of its leaves' primitives (testTriangle,
// testInstance); alone it is the flat kernel, under the names below. `root` is the node the walk
// starts at: 0 for a flat tree (a constant the compiler folds), a BLAS's or the TLAS's root otherwise.
#ifndef KERNEL_WALK
#define KERNEL_WALK traverseBvh2cb
#define KERNEL_LEAF_TEST testTriangle
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
  while (true) {
    // Inner loop: fetch the record, test both children, go on with the nearer one that the ray meets
    // (pushing the other when both are met); when it meets neither, go on with an empty leaf.
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
          return hit.tri >= 0;
        }
        bool bFirst = bEnter < aEnter;
        stackLink[sp] = bFirst ? aLink : bLink;
        stackCount[sp] = bFirst ? aCount : bCount;
        stackEnter[sp] = bFirst ? aEnter : bEnter;
        sp++;
        link = bFirst ? bLink : aLink;
        count = bFirst ? bCount : aCount;
      } else {
        link = hitA ? aLink : bLink;
        count = hitA ? aCount : hitB ? bCount : 0u;
      }
    }
    // Leaf: the one the inner loop reached, or a popped one; then the next pending entry. Entries
    // entered beyond the closest hit would fail their box test now and are dropped.
    for (uint i = 0u; i < count; ++i) {
      int tri = int(link + i);
      float t;
      vec2 bary;
      g_triTests++;
      if (KERNEL_LEAF_TEST(ray, tri, tMin, hit.t, t, bary)) {
        hit = MeshHit(t, tri, bary);
        if (anyHit) return true;
      }
    }
    while (sp > 0 && stackEnter[sp - 1] > hit.t) sp--;
    if (sp == 0) break;
    sp--;
    link = stackLink[sp];
    count = stackCount[sp];
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
