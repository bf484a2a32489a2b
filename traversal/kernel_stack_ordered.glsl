// kernel_stack_ordered.glsl — nearest child first: an inner node tests both child boxes, walks
// into the one the ray enters first and pushes the other with its entry distance; a popped node
// whose entry lies beyond the closest hit found since is skipped without being fetched.
// C++ mirror: kernel_stack_ordered.hpp.
//
// Stack bound: the current node is held in registers, never on the stack; at depth k (root = 1)
// the stack holds at most one entry per ancestor, the farther child of an ancestor whose nearer
// subtree is being walked. A push happens at an inner node (depth <= D - 1) and makes at most
// D - 1 entries, so BVH_STACK_SIZE >= D - 1 never overflows (stackSizeFor gives D, for the
// unordered kernel); a chain whose every farther child is a leaf, with every box hit, needs D - 1.
//
// Counters: g_nodeVisits += 1 per node record fetched (loadNode): the root, each child whose box
// is tested, and each node popped (its record is fetched again; its box is not re-tested).
// g_triTests += 1 per testTriangle call; g_boxTests += 1 per intersectAabb call.
//
// Loop shape: "while-while" (an inner loop over inner nodes, then the leaf's triangles, then a pop),
// as kernel_bvh2cb_stack.glsl and for its reason; the walk and its counters are those of the one-loop
// if-else form it replaced (0.70x its time on the bunny's primary rays, 0.73x on diffuse ones).

// Two-level trees (traversal/two_level.glsl) assemble this file twice, with KERNEL_WALK naming the
// walk (blasWalk, tlasWalk) and KERNEL_LEAF_TEST the test of its leaves' primitives (testTriangle,
// testInstance); alone it is the flat kernel, under the names below. `root` is the node the walk
// starts at: 0 for a flat tree (a constant the compiler folds), a BLAS's or the TLAS's root otherwise.
#ifndef KERNEL_WALK
#define KERNEL_WALK traverseOrdered
#define KERNEL_LEAF_TEST testTriangle
#endif

bool KERNEL_WALK(Ray ray, int root, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  int stackNode[BVH_STACK_SIZE];
  float stackEnter[BVH_STACK_SIZE];
  int sp = 0;

  int node = root;
  vec3 bmin, bmax;
  uint a, escape, count;
  float tEnter;
  g_nodeVisits++;
  loadNode(node, bmin, bmax, a, escape, count);
  g_boxTests++;
  if (!intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  while (true) {
    // Inner loop: descend while the current node is inner and a child is met.
    bool met = true;
    while (count == 0u && met) {
      int left = node + 1;
      int right = int(a);
      uint leftA, leftCount, rightA, rightCount;
      float leftEnter, rightEnter;
      g_nodeVisits++;
      loadNode(left, bmin, bmax, leftA, escape, leftCount);
      g_boxTests++;
      bool hitLeft = intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, leftEnter);
      g_nodeVisits++;
      loadNode(right, bmin, bmax, rightA, escape, rightCount);
      g_boxTests++;
      bool hitRight = intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, rightEnter);
      if (hitLeft && hitRight) {
        if (sp == BVH_STACK_SIZE) {
          g_stackOverflow = true;  // stop: the result so far is incomplete, the flag says so
          return hit.tri >= 0;
        }
        bool leftFirst = leftEnter <= rightEnter;
        stackNode[sp] = leftFirst ? right : left;
        stackEnter[sp] = leftFirst ? rightEnter : leftEnter;
        sp++;
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
      g_triTests++;
      if (KERNEL_LEAF_TEST(ray, tri, tMin, hit.t, t, bary)) {
        hit = MeshHit(t, tri, bary);
        if (anyHit) return true;
      }
    }
    // Next pending node; those entered beyond the closest hit would fail their box test now.
    while (sp > 0 && stackEnter[sp - 1] > hit.t) sp--;
    if (sp == 0) break;
    node = stackNode[--sp];
    g_nodeVisits++;
    loadNode(node, bmin, bmax, a, escape, count);
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
