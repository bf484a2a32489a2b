// kernel_cwbvh_groups.glsl — layout cwbvh (layout/layout_cwbvh.hpp) traversed as Ylitie, Karras & Laine
// 2017 traverse their compressed wide BVH ("Efficient Incoherent Ray Traversal on GPUs Through
// Compressed Wide BVHs", HPG 2017, section 4), registered as cwbvh-groups. C++ mirror:
// kernel_cwbvh_groups.hpp. Where kernel_cwbvh_stack.glsl decodes every child box to world space and
// pushes every child it meets as its own sorted entry, this kernel:
//
// - keeps NODE GROUPS: one stack entry per node = (childBase, hit mask of its inner children | imask
//   << 8 | entry bound << 16), 8 bytes (uvec2). Children are taken from a group with findMSB, the
//   mask's bits permuted by the ray's octant: slot s's hit is bit s ^ (7 - octant), so bits taken
//   highest first visit the slots in the order octant, octant ^ 1, ..., octant ^ 7, and the packer put
//   in slot `octant` the child rays of that octant meet first (cwbvhAssignSlots). A child's node index
//   is childBase + the count of inner slots below it (imask). The rest of a group goes on the stack
//   only when a child is taken from it and bits remain.
//   Two additions to the paper's scheme, both from values the child tests leave in registers: the
//   first child taken from the node just intersected is its nearest inner child met (the order above
//   applies to the rest), and the entry bound, the nearest entry of the group's children kept in 16
//   bits (cwbvhEnterBits, a lower bound), drops a whole group unfetched once the closest hit lies
//   before it. (The paper's entries carry no distance.) On the bunny's diffuse rays these took the bytes per
//   ray from 970.7 to 957.5 in the mirror (watertight; test_bytes_fetched prints the totals).
// - keeps a lazy TRIANGLE GROUP: the leaf children a node's tests hit (a mask over slots, permuted by
//   the octant as above, each leaf's entry bound in 16 bits of a uvec4) are tested right after the
//   node, before its inner children are walked, from registers: with the node's triBase and meta bytes,
//   which give each leaf's first triangle and count; a leaf entered beyond the closest hit found so far
//   is skipped. Triangles are never pushed one by one and the group never goes on the stack. (The
//   paper may postpone a triangle group onto the stack when few SIMD lanes would test triangles; this
//   kernel does not: one ray per invocation, no lane voting.)
// - tests the QUANTISED PLANES directly. Per node: off = (p - origin) * invDir and the scaled inverse
//   direction S = 2^(e - 127) * invDir per axis (exact: a power of two times a float), and the near and
//   far byte arrays chosen once by the direction's sign per axis (qlo is near where invDir >= 0, qhi
//   where it is negative). Per child and plane then one multiply-add: t = float(q) * S' + off. S' is S
//   cut to 16 significant bits, rounded toward 0 for the lo planes and away from 0 for the hi planes:
//   an 8-bit q times a 16-bit S' is exact (S' normal: scale >= 2^-126 and |invDir| >= 1 for direction
//   components of magnitude <= 1), so the multiply-add rounds once whether or not a compiler fuses it
//   (GLSL and the C++ mirror agree bit for bit). The planes it tests lie at p + q s' with s' <= scale for
//   lo and s' >= scale for hi: in exact arithmetic never inside the quantised box (outward by at most
//   2^-15 of the node's extent), which the packer made contain the child. The test itself then rounds
//   as ray_box.glsl's slab test does, with no promise at the last ulp (the robust test below has one).
//   A ray parallel to an axis (|invDir| at least kParallelInverse, ray_box.glsl) takes, for that axis,
//   the slab test's closed-slab rule on the decoded planes, as ray_box.glsl does: whether the origin
//   lies between them. With the robust box test (BVH_BOX_ROBUST, --robust box or watertight) the
//   child boxes are decoded and go through ray_box_robust.glsl's intersectAabb instead: Ize's bound
//   holds for a world-space slab test, not for the plane form (its offset's rounding is relative to
//   p - origin, not to the plane's distance).
// - the root: as kernel_cwbvh_stack.glsl, the root's whole grid is tested first (one texel), then the
//   walk starts from a group holding the root alone.
//
// NaN: invDir is finite (rayInverseDirection); S is clamped to +-2^119 so that q * S' <= 255 * 2^119 is
// finite (the clamp acts only where scale |invDir| > 2^119: off a parallel axis |invDir| < 5e29, so for
// nodes over about 3e8 units wide, far beyond the scenes here; on a parallel axis the rule below decides),
// off is finite or +-inf, so t = q S' + off is a sum of a finite and a finite-or-infinite value: never
// NaN. The parallel rule replaces t by +-INF. The masks and indices are integers.
//
// Stack bound: a group is pushed only when a child is taken from it and bits remain, so the stack holds
// at most one group per node on the path above the node being visited: nodes lie at depths 1 .. D - 1
// (PackedBvh::depth counts leaves), so at most D - 2 entries, within stackSizeFor(const PackedBvh&)'s
// (W - 1)(D - 1) for layout cwbvh.
//
// Counters: g_nodeVisits += 1 per node fetched (80 bytes), g_boxTests += 1 for the root grid's test and
// per occupied slot of each node visited (empty slots are skipped by their meta), g_triTests += 1 per
// testTriangle call. The mirror also counts bytes: 8 per group pushed or popped (dropped ones too).
const float kCwbvhMaxScaledInverse = 6.64613997892457936e35;  // 2^119: 255 * 2^119 < FLT_MAX

// The octant of a direction: bit a set where invDir's component a is negative (a = x, y, z).
uint cwbvhOctant(vec3 invDir) {
  return (invDir.x < 0.0 ? 1u : 0u) | (invDir.y < 0.0 ? 2u : 0u) | (invDir.z < 0.0 ? 4u : 0u);
}

// A group's hit mask holds slot s at bit s ^ octInv, octInv = 7 - octant: findMSB then takes the slots
// in the order octant, octant ^ 1, ..., octant ^ 7 (bit 7 - k holds slot k ^ octant).
uint cwbvhHitBit(uint slot, uint octInv) { return slot ^ octInv; }
uint cwbvhSlotOfBit(uint bit, uint octInv) { return bit ^ octInv; }

// A distance kept in 16 bits, as a lower bound: the float's upper 16 bits (sign, exponent, 7 mantissa
// bits), rounded toward -inf (a positive float's low bits dropped, a negative one's rounded up in
// magnitude). cwbvhEnterBound gives the bound back as a float, <= the distance it was made from.
uint cwbvhEnterBits(float t) {
  uint b = floatBitsToUint(t);
  return (b & 0x80000000u) != 0u ? (b + 0xFFFFu) >> 16 : b >> 16;
}
float cwbvhEnterBound(uint bits16) { return uintBitsToFloat(bits16 << 16); }

// S = scale * invDir cut to 16 significant bits: toward 0 (lo planes), away from 0 (hi planes). The
// clamp keeps S finite; the rounding up of 2^119 is 2^119 (no low bits), so it stays finite.
void cwbvhScaledInverse(vec3 scale, vec3 invDir, out vec3 sLo, out vec3 sHi) {
  vec3 s = clamp(scale * invDir, vec3(-kCwbvhMaxScaledInverse), vec3(kCwbvhMaxScaledInverse));
  uvec3 b = floatBitsToUint(s);
  sLo = uintBitsToFloat(b & 0xFFFFFF00u);
  sHi = uintBitsToFloat((b + 0xFFu) & 0xFFFFFF00u);
}

// The 8 bytes (one per slot) of array a (0 .. 5: qlo.x, qlo.y, qlo.z, qhi.x, qhi.y, qhi.z) of a node.
uvec2 cwbvhPlaneBytes(CwNode n, uint a) {
  return a == 0u ? n.q0.xy : a == 1u ? n.q0.zw : a == 2u ? n.q1.xy : a == 3u ? n.q1.zw : a == 4u ? n.q2.xy : n.q2.zw;
}

// The first triangle of leaf slot c: triBase + the counts of the leaf slots below c (inner and empty
// slots add nothing: their meta is kCwbvhMetaInner, skipped, or 0).
uint cwbvhLeafFirst(CwNode n, uint c) {
  uint first = n.triBase;
  for (uint j = 0u; j < c; ++j) {
    uint meta = cwbvhMeta(n, j);
    if (meta != kCwbvhMetaInner) first += meta;
  }
  return first;
}

// The stack. In `bvhlab trace`'s compute path (COMPUTE_LANES invocations a workgroup) with
// SHARED_STACK_ENTRIES = K defined (registered as cwbvh-groups-shared), a SHORT STACK: the top K
// entries in shared memory, a ring (entry i in slot i mod K, one column per invocation: slot j of
// invocation l at j * COMPUTE_LANES + l, so a warp's invocations touch consecutive words), and the
// entries below them spilled to a local array: a push onto K entries first moves the oldest of them
// out, a pop brings it back. Elsewhere (the renderer's fragment shader, or without the define) a local
// array of BVH_STACK_SIZE. Where an entry lives changes neither the walk nor its counts.
#if defined(SHARED_STACK_ENTRIES) && defined(COMPUTE_LANES)
shared uvec2 s_cwStack[SHARED_STACK_ENTRIES * COMPUTE_LANES];
const int kCwStackSpill = BVH_STACK_SIZE > SHARED_STACK_ENTRIES ? BVH_STACK_SIZE - SHARED_STACK_ENTRIES : 1;
uvec2 g_cwStackSpill[kCwStackSpill];
uint cwStackSlot(int i) { return uint(i % SHARED_STACK_ENTRIES) * uint(COMPUTE_LANES) + gl_LocalInvocationIndex; }
// Pushes entry `sp` (the stack holds 0 .. sp - 1, sp < BVH_STACK_SIZE): entry sp - K leaves its slot.
void cwStackPush(int sp, uvec2 v) {
  if (sp >= SHARED_STACK_ENTRIES) g_cwStackSpill[sp - SHARED_STACK_ENTRIES] = s_cwStack[cwStackSlot(sp)];
  s_cwStack[cwStackSlot(sp)] = v;
}
// Pops entry sp - 1: entry sp - 1 - K comes back from the spill into the slot it frees.
uvec2 cwStackPop(int sp) {
  uvec2 v = s_cwStack[cwStackSlot(sp - 1)];
  if (sp - 1 >= SHARED_STACK_ENTRIES) s_cwStack[cwStackSlot(sp - 1)] = g_cwStackSpill[sp - 1 - SHARED_STACK_ENTRIES];
  return v;
}
#define CW_STACK_DECLARE
#define CW_STACK_PUSH(sp, v) cwStackPush(sp, v)
#define CW_STACK_POP(sp) cwStackPop(sp)
#else
#define CW_STACK_DECLARE uvec2 stack[BVH_STACK_SIZE];  // node groups below the current one
#define CW_STACK_PUSH(sp, v) stack[sp] = (v)
#define CW_STACK_POP(sp) stack[(sp) - 1]
#endif

bool traverseCwbvhGroups(Ray ray, float tMin, float tMax, bool anyHit, out MeshHit hit) {
  hit = MeshHit(tMax, -1, vec2(0.0));
  vec3 invDir = rayInverseDirection(ray.dir);
  uint octInv = 7u - cwbvhOctant(invDir);  // slot s's bit in a group's hit mask: s ^ octInv
  bvec3 negative = lessThan(invDir, vec3(0.0));
#ifndef BVH_BOX_ROBUST
  bvec3 parallel = greaterThanEqual(abs(invDir), vec3(kParallelInverse));
  bool anyParallel = any(parallel);
#endif
  CW_STACK_DECLARE
  int sp = 0;

  vec3 bmin, bmax;
  float tEnter;
  cwbvhGridBox(0u, bmin, bmax);
  g_boxTests++;
  if (!intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, tEnter)) return false;
  // The current node group (x = childBase, y = hit mask | imask << 8 | entry bound << 16): the root
  // alone, as an inner child in slot 0 of base 0.
  uvec2 group = uvec2(0u, (1u << cwbvhHitBit(0u, octInv)) | (1u << 8) | (cwbvhEnterBits(tEnter) << 16));
  uint bit = cwbvhHitBit(0u, octInv);  // the group's child the next step takes
  while (true) {
    // Take that child (the group has it: the root's, the nearest inner child of the node just
    // intersected, or a popped group's next by octant order); the rest of the group is pushed if bits
    // remain.
    group.y &= ~(1u << bit);
    uint slot = cwbvhSlotOfBit(bit, octInv);
    uint imask = (group.y >> 8) & 0xFFu;
    uint child = group.x + uint(bitCount(imask & ((1u << slot) - 1u)));
    if ((group.y & 0xFFu) != 0u) {
      if (sp == BVH_STACK_SIZE) {
        g_stackOverflow = true;  // stop: the result so far is incomplete, the flag says so
        return hit.tri >= 0;
      }
      CW_STACK_PUSH(sp, group);
      sp++;
    }
    g_nodeVisits++;
    CwNode node = loadCwNode(child);
#ifndef BVH_BOX_ROBUST
    // Per node: the plane terms, and the near and far byte arrays by the direction's sign.
    vec3 sLo, sHi;
    cwbvhScaledInverse(node.scale, invDir, sLo, sHi);
    vec3 off = (node.p - ray.origin) * invDir;
    vec3 sNear = mix(sLo, sHi, negative);
    vec3 sFar = mix(sHi, sLo, negative);
    uvec2 nearX = cwbvhPlaneBytes(node, negative.x ? 3u : 0u), farX = cwbvhPlaneBytes(node, negative.x ? 0u : 3u);
    uvec2 nearY = cwbvhPlaneBytes(node, negative.y ? 4u : 1u), farY = cwbvhPlaneBytes(node, negative.y ? 1u : 4u);
    uvec2 nearZ = cwbvhPlaneBytes(node, negative.z ? 5u : 2u), farZ = cwbvhPlaneBytes(node, negative.z ? 2u : 5u);
#endif
    uint nodeHits = 0u, innerSlots = 0u, triHits = 0u;
    float groupEnter = INF;  // the nearest entry of the inner children met
    uint nearestBit = 0u;    // and that child's bit
    uvec4 leafEnter = uvec4(0u);  // leaf slot c's entry bound: 16 bits of component c / 2
    for (uint c = 0u; c < 8u; ++c) {
      uint meta = cwbvhMeta(node, c);
      if (meta == 0u) continue;  // an empty slot
      bool inner = meta == kCwbvhMetaInner;
      if (inner) innerSlots |= 1u << c;
      g_boxTests++;
#ifdef BVH_BOX_ROBUST
      cwbvhChildBox(node, c, bmin, bmax);
      float enter;
      bool met = intersectAabb(ray.origin, invDir, bmin, bmax, tMin, hit.t, enter);
#else
      vec3 tNear = vec3(uvec3(cwbvhByte(nearX, c), cwbvhByte(nearY, c), cwbvhByte(nearZ, c))) * sNear + off;
      vec3 tFar = vec3(uvec3(cwbvhByte(farX, c), cwbvhByte(farY, c), cwbvhByte(farZ, c))) * sFar + off;
      if (anyParallel) {
        // A parallel axis: inside the closed slab of the decoded planes for every t or for none.
        cwbvhChildBox(node, c, bmin, bmax);
        bvec3 inSlab = equal(clamp(ray.origin, bmin, bmax), ray.origin);
        tNear = mix(tNear, mix(vec3(INF), vec3(-INF), inSlab), parallel);
        tFar = mix(tFar, mix(vec3(-INF), vec3(INF), inSlab), parallel);
      }
      float enter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
      float exit = min(min(tFar.x, tFar.y), min(tFar.z, hit.t));
      bool met = enter <= exit;
#endif
      if (met) {
        if (inner) {
          nodeHits |= 1u << cwbvhHitBit(c, octInv);
          if (enter < groupEnter) nearestBit = cwbvhHitBit(c, octInv);
          groupEnter = min(groupEnter, enter);
        } else {
          triHits |= 1u << cwbvhHitBit(c, octInv);
          leafEnter[c >> 1] |= cwbvhEnterBits(enter) << (16u * (c & 1u));
        }
      }
    }
    // The node's group becomes the current one; its triangle group (triHits with the node's triBase
    // and meta) is tested now, lazily, leaf by leaf from registers.
    group = uvec2(node.childBase, nodeHits | (innerSlots << 8) | (cwbvhEnterBits(groupEnter) << 16));
    while (triHits != 0u) {
      uint tbit = uint(findMSB(triHits));
      triHits &= ~(1u << tbit);
      uint c = cwbvhSlotOfBit(tbit, octInv);
      // A leaf entered beyond the closest hit is skipped.
      if (cwbvhEnterBound((leafEnter[c >> 1] >> (16u * (c & 1u))) & 0xFFFFu) > hit.t) continue;
      uint first = cwbvhLeafFirst(node, c);
      uint count = cwbvhMeta(node, c);
      for (uint i = 0u; i < count; ++i) {
        int tri = int(first + i);
        float t;
        vec2 bary;
        g_triTests++;
        if (testTriangle(ray, tri, tMin, hit.t, t, bary)) {
          hit = MeshHit(t, tri, bary);
          if (anyHit) return true;
        }
      }
    }
    // The next group: the current one while it has children left entered before the closest hit, else
    // the stack's top; a group whose entry bound lies beyond the hit is dropped unfetched.
    bit = nearestBit;
    while ((group.y & 0xFFu) == 0u || cwbvhEnterBound(group.y >> 16) > hit.t) {
      if (sp == 0) return hit.tri >= 0;
      group = CW_STACK_POP(sp);
      sp--;
      bit = uint(findMSB(group.y & 0xFFu));
    }
  }
  return hit.tri >= 0;  // not reached: the loop returns
}

// Closest hit with tMin < t < tMax; hit.tri = -1 and hit.t = tMax when there is none.
bool traceClosest(Ray ray, float tMin, float tMax, out MeshHit hit) {
  return traverseCwbvhGroups(ray, tMin, tMax, false, hit);
}

// Any hit with tMin < t < tMax (shadow rays): the same walk, stopped at the first hit.
bool traceAny(Ray ray, float tMin, float tMax) {
  MeshHit hit;
  return traverseCwbvhGroups(ray, tMin, tMax, true, hit);
}
