// kernel_wide_stack.glsl — ordered stack traversal over the wide layouts bvh4 and bvh8
// (layout/layout_wide.hpp; registered as bvh4-stack-ordered and bvh8-stack-ordered, the same code:
// the width only bounds a record's child count, which the slot pointing at it carries).
//
// WIDE_FETCH_WHOLE = W (registered as bvh4-fetch-whole and bvh8-fetch-whole): the same walk, but a
// record's 2k texels are all fetched into registers before its first box test, so a GPU has the k
// slots' loads in flight at once instead of one slot's per test (the node fetched whole, as the wide
// kernels of Ylitie et al. 2017 fetch theirs). Every counter, byte and hit is the plain kernel's. At a record
// the kernel tests every child box; the nearest child the ray meets is walked next (held in
// registers) and the others met are pushed sorted by entry distance, nearer above farther (insertion
// into this record's part of the stack). A leaf is walked straight from its slot, and a popped entry whose entry lies beyond the
// closest hit found since is dropped unfetched. C++ mirror: kernel_wide_stack.hpp.
//
// Stack bound: W = the layout's width, D = PackedBvh::depth (the wide tree's depth, root slot = 1).
// Records sit at depths 1..D-1, and a record pushes at most W - 1 entries (its nearest child met is
// not pushed). Entering a record at depth d, the stack holds at most W - 1 entries per record above
// it on the path, so (W - 1)(d - 1); the record adds at most W - 1: (W - 1) d <= (W - 1)(D - 1).
// A tree whose root slot is a leaf (D = 1) pushes nothing. stackSizeFor(const PackedBvh&)
// (traversal/kernels.hpp) returns max(1, (W - 1)(D - 1)).
//
// Order and NaN: the box tests never return a NaN entry for a finite ray (ray_box*.glsl). Should one
// appear anyway, `enter < nearEnter` and the insertion's `<=` are false (a NaN child is pushed, and
// stays above the entries it meets) and the pop test `entry > hit.t` is false (never dropped): NaN
// can only cost work or order, never lose a hit. Equal entries keep the children's stored order (the
// lower slot is walked first).
//
// Loop shape: "if-if" (one loop, an inner step and a leaf step per iteration). The "while-while"
// shape that speeds up the binary kernels on llvmpipe (kernel_bvh2cb_stack.glsl) slows this one
// down: bunny close view, diffuse rays, 1.16x the time for bvh4 and 1.14x for bvh8 (docs/layouts.md,
// "Loop shape"): a wide inner step costs several triangle tests, so lanes waiting in an inner loop
// for the slowest lane waste more than the masked triangle test that if-if pays per step.
//
// Counters: g_nodeVisits += 1 per record entered (a wide node counts once, whatever its width);
// g_boxTests += 1 per intersectAabb call (the root slot's test, then one per child of each record);
// g_triTests += 1 per testTriangle call. A leaf costs no visit (its slot came with its parent).

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
    // Inner step: the nearest child the ray meets is kept in registers and walked next; every other
    // child met goes on the stack, inserted into this record's part of it so that nearer ones lie
    // above farther ones. A record whose children all miss goes on as an empty leaf (the step below
    // pops).
    if (count >= kWideInner) {
      g_nodeVisits++;
      int first = sp;
      uint children = count - kWideInner;
      uint nearLink = 0u, nearCount = 0u;
      float nearEnter = 0.0;
      bool met = false;
#ifdef WIDE_FETCH_WHOLE
      children = min(children, uint(WIDE_FETCH_WHOLE));  // the packer's bound (k <= W): the arrays' size
      uvec4 slotLo[WIDE_FETCH_WHOLE], slotHi[WIDE_FETCH_WHOLE];
      for (uint i = 0u; i < children; ++i) {
        slotLo[i] = fetchNode(int(link + 2u * i));
        slotHi[i] = fetchNode(int(link + 2u * i) + 1);
      }
#endif
      for (uint i = 0u; i < children; ++i) {
        uint childLink, childCount;
        float enter;
#ifdef WIDE_FETCH_WHOLE
        decodeSlot(slotLo[i], slotHi[i], bmin, bmax, childLink, childCount);
#else
        loadSlot(link + 2u * i, bmin, bmax, childLink, childCount);
#endif
        g_boxTests++;
        if (intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, enter)) {
          if (!met) {
            nearLink = childLink;
            nearCount = childCount;
            nearEnter = enter;
            met = true;
            continue;
          }
          if (sp == BVH_STACK_SIZE) {
            g_stackOverflow = true;  // stop: the result so far is incomplete, the flag says so
            return hit.tri >= 0;
          }
          // The farther of (nearest so far, this child) is pushed; ties keep the lower slot nearest.
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
            j--;
          }
          stackLink[j] = pushLink;
          stackCount[j] = pushCount;
          stackEnter[j] = pushEnter;
          sp++;
        }
      }
      link = nearLink;
      count = met ? nearCount : 0u;
    }
    // Leaf step: the current leaf's triangles, then the next pending entry; entries entered beyond the
    // closest hit would fail their box test now and are dropped.
    if (count < kWideInner) {
      for (uint i = 0u; i < count; ++i) {
        int tri = int(link + i);
        float t;
        vec2 bary;
        g_triTests++;
        if (testTriangle(ray, tri, tMin, hit.t, t, bary)) {
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
