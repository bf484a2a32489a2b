// kernel_cwbvh_stack.glsl — ordered stack traversal over layout cwbvh (layout/layout_cwbvh.hpp; the
// compressed 8-wide node of Ylitie, Karras & Laine 2017), registered as cwbvh-stack-ordered. The walk
// is kernel_wide_stack.glsl's: at a node the kernel decodes and tests every child box; the nearest
// child the ray meets is walked next (held in registers) and the others met are inserted sorted by
// entry distance into this node's part of the stack, nearer above farther. A leaf is walked straight
// from its parent's node, and a popped entry whose entry lies beyond the closest hit found since is
// dropped unfetched. (The paper's traversal keeps node groups with a hit mask instead; this kernel
// keeps the project's sorted stack so that the layouts differ only in the node.) C++ mirror:
// kernel_cwbvh_stack.hpp.
//
// Stack entries are (link, count): an inner child is (its node index, kCwbvhInner), a leaf (its first
// triangle, its triangle count < kCwbvhInner). The ROOT NODE's own box is not stored; the kernel first
// tests the root's whole grid, p .. p + 255 scale (cwbvhGridBox: one texel, a box that contains every
// child box, up to twice the root box's extent per axis since e is the smallest that reaches), so a
// ray that misses the scene costs one box test and no visit, as bvh8's root slot. (Entering the root
// untested instead cost 1.37 visits and 10.8 box tests per primary ray on the report scene, where most
// rays miss the mesh, against bvh8's 0.45 and 4.5: 3.80x Embree against bvh8's 2.61x in one
// bench_traversal run.)
//
// Stack bound: W = 8, D = PackedBvh::depth (root node = 1, its children 2, leaves counted). Nodes sit
// at depths 1..D-1, and a node pushes at most W - 1 entries (its nearest child met is not pushed).
// Entering a node at depth d the stack holds at most W - 1 entries per node above it on the path, so
// (W - 1)(d - 1); the node adds at most W - 1: (W - 1) d <= (W - 1)(D - 1). stackSizeFor(const
// PackedBvh&) (traversal/kernels.hpp) returns max(1, (W - 1)(D - 1)).
//
// Loop shape: "if-if", as kernel_wide_stack.glsl and for its reason (while-while: 1.22x the time
// on the bunny's diffuse rays, in the git history of docs/layouts.md).
//
// Order and NaN: the box tests never return a NaN entry for a finite ray (ray_box*.glsl), and a
// decoded box is finite for a finite scene. Should a NaN appear anyway, `enter < nearEnter` and the
// insertion's `<=` are false (a NaN child is pushed, and stays above the entries it meets) and the pop
// test `entry > hit.t` is false (never dropped): NaN can only cost work or order, never lose a hit.
// Equal entries keep the children's stored order (the lower slot is walked first).
//
// Counters: g_nodeVisits += 1 per node entered (80 bytes fetched, whatever k); g_boxTests += 1 per
// intersectAabb call (the root grid's test, then one per child of each node entered); g_triTests += 1
// per testTriangle call. A leaf costs no visit (its box and link came with its parent).
const uint kCwbvhInner = 0x80000000u;  // a stack entry's count for an inner child (leaves: <= 127)

bool traverseCwbvh(Ray ray, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  uint stackLink[BVH_STACK_SIZE];
  uint stackCount[BVH_STACK_SIZE];
  float stackEnter[BVH_STACK_SIZE];
  int sp = 0;

  vec3 bmin, bmax;
  float tEnter;
  cwbvhGridBox(0u, bmin, bmax);
  g_boxTests++;
  if (!intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  uint link = 0u;  // the current entry: the root node
  uint count = kCwbvhInner;
  while (true) {
    // Inner step: decode and test every child; the nearest one the ray meets is kept in registers and
    // walked next, every other child met is inserted into this node's part of the stack (nearer above
    // farther). A node whose children all miss goes on as an empty leaf (the step below pops).
    if (count == kCwbvhInner) {
      g_nodeVisits++;
      CwNode node = loadCwNode(link);
      int first = sp;
      uint nearLink = 0u, nearCount = 0u;
      float nearEnter = 0.0;
      bool met = false;
      uint innerRank = 0u, triOffset = 0u;  // the next inner child's rank, the next leaf's first triangle
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
    if (count != kCwbvhInner) {
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
  return traverseCwbvh(ray, tMin, tMax, false, hit);
}

// Any hit with tMin < t < tMax (shadow rays): the same walk, stopped at the first hit.
bool traceAny(Ray ray, float tMin, float tMax) {
  MeshHit hit;
  return traverseCwbvh(ray, tMin, tMax, true, hit);
}
