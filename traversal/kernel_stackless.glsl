// kernel_stackless.glsl — no stack: nodes are visited in the stream's depth-first order. A node
// whose box the ray meets continues to its first child (node + 1) if it is inner; a leaf, after its
// triangles, and a node whose box is missed continue at their escape link (layout/layout.hpp).
// Every step moves to a higher node index, so the walk ends after at most one visit per node (a
// record that would not move forward ends it).
// C++ mirror: kernel_stackless.hpp.
//
// Counters: g_nodeVisits += 1 per node record fetched (loadNode), i.e. per node the walk reaches;
// each has its box tested once. g_triTests += 1 per testTriangle call;
// g_boxTests += 1 per intersectAabb call.
//
// Loop shape: box steps in an inner loop until a leaf whose box the ray meets, then its triangles
// (the "while-while" shape of kernel_bvh2cb_stack.glsl, and for its reason: llvmpipe runs every
// branch of a loop body under a mask, so a triangle test inside the box-step loop is paid by every
// step). The walk and its counters are those of the one-loop form it replaced.

// Two-level trees (traversal/two_level.glsl) assemble this file twice, with KERNEL_WALK naming the
// walk (blasWalk, tlasWalk) and KERNEL_LEAF_TEST the test of its leaves' primitives (testTriangle,
// testInstance); alone it is the flat kernel, under the names below. `root` is the node the walk
// starts at: 0 for a flat tree (a constant the compiler folds), a BLAS's or the TLAS's root otherwise.
#ifndef KERNEL_WALK
#define KERNEL_WALK traverseStackless
#define KERNEL_LEAF_TEST testTriangle
#endif

bool KERNEL_WALK(Ray ray, int root, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  uint node = uint(root);
  while (true) {
    uint a, escape, count;
    // Box steps: follow child and escape links until a leaf whose box the ray meets, or the end.
    bool atLeaf = false;
    while (!atLeaf && node != kEscapeEnd) {
      vec3 bmin, bmax;
      float tEnter;
      g_nodeVisits++;
      loadNode(int(node), bmin, bmax, a, escape, count);
      g_boxTests++;
      if (!intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) {
        // A valid tree's escape link points past its node (every step moves to a higher index); a
        // record whose link does not ends the walk (kEscapeEnd) instead of looping. In a fragment
        // shader llvmpipe hands helper invocations zeros from storage buffers (--storage ssbo;
        // docs/layouts.md), and a record of zeros would spin until the driver's loop limit cut the
        // whole quad short.
        node = escape <= node ? kEscapeEnd : escape;
      } else if (count == 0u) {
        node = node + 1u;
      } else {
        atLeaf = true;
      }
    }
    if (!atLeaf) break;
    for (uint i = 0u; i < count; ++i) {
      int tri = int(a + i);
      float t;
      vec2 bary;
      g_triTests++;
      if (KERNEL_LEAF_TEST(ray, tri, tMin, hit.t, t, bary)) {
        hit = MeshHit(t, tri, bary);
        if (anyHit) return true;
      }
    }
    node = escape <= node ? kEscapeEnd : escape;
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
