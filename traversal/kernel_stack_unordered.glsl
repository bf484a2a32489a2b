// kernel_stack_unordered.glsl — the report's Algorithm 2: an explicit stack of nodes to visit. Pop
// a node; a leaf has its triangles tested; an inner node has both child boxes tested and the
// children the ray meets are pushed (the second child first, so the first child pops next and
// leaves are reached in the stream's depth-first order). No ordering by distance: a box is culled
// only when it lies beyond the closest hit found so far at the time it is tested.
// C++ mirror: kernel_stack_unordered.hpp.
//
// Stack bound: when a node of depth k (root = 1) is popped, the stack holds at most one entry per
// ancestor (the second child of an ancestor whose first subtree is being walked), k - 1 in all;
// pushing its two children makes k + 1. Inner nodes have depth <= D - 1 in a tree of depth D, so
// BVH_STACK_SIZE >= D never overflows, and a chain whose every second child is a leaf, with every
// box hit, needs exactly D.
//
// Counters: g_nodeVisits += 1 per node record fetched (loadNode): each pop and each child whose
// box is tested, so a node pushed and later popped counts twice. g_triTests += 1 per
// testTriangle call; g_boxTests += 1 per intersectAabb call.

// Two-level trees (traversal/two_level.glsl) assemble this file twice, with KERNEL_WALK naming the
// walk (blasWalk, tlasWalk) and KERNEL_LEAF_TEST the test of its leaves' primitives (testTriangle,
// testInstance); alone it is the flat kernel, under the names below. `root` is the node the walk
// starts at: 0 for a flat tree (a constant the compiler folds), a BLAS's or the TLAS's root otherwise.
#ifndef KERNEL_WALK
#define KERNEL_WALK traverseUnordered
#define KERNEL_LEAF_TEST testTriangle
#endif

bool KERNEL_WALK(Ray ray, int root, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  int stack[BVH_STACK_SIZE];
  int sp = 0;
  stack[sp++] = root;
  while (sp > 0) {
    int node = stack[--sp];
    vec3 bmin, bmax;
    uint a, escape, count;
    g_nodeVisits++;
    loadNode(node, bmin, bmax, a, escape, count);
    if (count > 0u) {
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
      continue;
    }
    int children[2] = int[2](int(a), node + 1);  // second child pushed first
    for (int k = 0; k < 2; ++k) {
      uint childA, childEscape, childCount;
      float tEnter;
      g_nodeVisits++;
      loadNode(children[k], bmin, bmax, childA, childEscape, childCount);
      g_boxTests++;
      if (!intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) continue;
      if (sp == BVH_STACK_SIZE) {
        g_stackOverflow = true;  // stop: the result so far is incomplete, the flag says so
        return hit.tri >= 0;
      }
      stack[sp++] = children[k];
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
