// kernel_wide_stack.glsl — ordered stack traversal over the wide layouts bvh4 and bvh8
// (layout/layout_wide.hpp; registered as bvh4-stack-ordered and bvh8-stack-ordered, the same code:
// the width only bounds a record's child count, which the slot pointing at it carries). At a record
// the kernel tests every child box and pushes the children the ray meets, sorted by entry distance
// so that the nearest is on top (insertion into this record's part of the stack); the top is walked
// next. A leaf is walked straight from its slot, and a popped entry whose entry lies beyond the
// closest hit found since is dropped unfetched. C++ mirror: kernel_wide_stack.hpp.
//
// Stack bound: W = the layout's width, D = PackedBvh::depth (the wide tree's depth, root slot = 1).
// Records sit at depths 1..D-1. Entering a record at depth d, the stack holds at most W - 1 entries
// per record above it on the path (each pushed at most W and one of them was popped to come down),
// so (W - 1)(d - 1); the record then pushes at most W before popping one: (W - 1)(d - 1) + W <=
// (W - 1)(D - 2) + W = (W - 1)(D - 1) + 1. A tree whose root slot is a leaf (D = 1) pushes nothing.
// stackSizeFor(const PackedBvh&) (traversal/kernels.hpp) returns max(1, (W - 1)(D - 1) + 1).
//
// Order and NaN: the box tests never return a NaN entry for a finite ray (ray_box*.glsl). Should one
// appear anyway, the insertion's `<=` is false (the entry stays above the others: walked first) and
// the pop test `entry > hit.t` is false (never dropped): NaN can only cost work, never lose a hit.
// Equal entries keep the children's stored order (the lower slot is walked first).
//
// Counters: g_nodeVisits += 1 per record entered (a wide node counts once, whatever its width);
// g_boxTests += 1 per intersectAabb call (the root slot's test, then one per child of each record);
// g_triTests += 1 per intersectTriangle call. A leaf costs no visit (its slot came with its parent).

bool traverseWide(Ray ray, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  uint stackLink[BVH_STACK_SIZE];
  uint stackCount[BVH_STACK_SIZE];
  float stackEnter[BVH_STACK_SIZE];
  int sp = 0;

  vec3 bmin, bmax;
  uint link, count;
  float tEnter;
  loadSlot(0u, bmin, bmax, link, count);  // the root slot
  g_boxTests++;
  if (!intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  while (true) {
    // Inner step: push every child the ray meets, nearest on top; then go on as an empty leaf, whose
    // step below pops the nearest.
    if (count >= kWideInner) {
      g_nodeVisits++;
      int first = sp;
      uint children = count - kWideInner;
      for (uint i = 0u; i < children; ++i) {
        uint childLink, childCount;
        float enter;
        loadSlot(link + 2u * i, bmin, bmax, childLink, childCount);
        g_boxTests++;
        if (intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, enter)) {
          if (sp == BVH_STACK_SIZE) {
            g_stackOverflow = true;  // stop: the result so far is incomplete, the flag says so
            return hit.tri >= 0;
          }
          int j = sp;
          while (j > first && stackEnter[j - 1] <= enter) {
            stackLink[j] = stackLink[j - 1];
            stackCount[j] = stackCount[j - 1];
            stackEnter[j] = stackEnter[j - 1];
            j--;
          }
          stackLink[j] = childLink;
          stackCount[j] = childCount;
          stackEnter[j] = enter;
          sp++;
        }
      }
      count = 0u;
    }
    // Leaf step: the current leaf's triangles, then the next pending entry; entries entered beyond the
    // closest hit would fail their box test now and are dropped.
    if (count < kWideInner) {
      for (uint i = 0u; i < count; ++i) {
        int tri = int(link + i);
        vec3 v0, v1, v2;
        loadTriangle(tri, v0, v1, v2);
        float t;
        vec2 bary;
        g_triTests++;
        if (intersectTriangle(ray, v0, v1, v2, tMin, hit.t, t, bary)) {
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
  }
  return hit.tri >= 0;
}

// Closest hit with tMin < t < tMax; hit.tri = -1 and hit.t = tMax when there is none.
bool traceClosest(Ray ray, float tMin, float tMax, out MeshHit hit) {
  return traverseWide(ray, tMin, tMax, false, hit);
}

// Any hit with tMin < t < tMax (shadow rays): the same walk, stopped at the first hit.
bool traceAny(Ray ray, float tMin, float tMax) {
  MeshHit hit;
  return traverseWide(ray, tMin, tMax, true, hit);
}
