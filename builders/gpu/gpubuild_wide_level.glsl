// GPU pack into cwbvh, step 3, one level of the wide tree (dispatched indirectly, one invocation per
// wide node of the level; gpubuild_wide_gate.glsl moves to the next). Queue entry q (a wide node; the
// root's entry 0 is written by the host) holds (binary node, parent entry, rank among the parent's inner
// children). Each invocation does what layout/pack_cwbvh.cpp does for one node:
//   - its children: the binary node's two sides given the slots of its internal split, expanded as
//     collapseWide's emit does (a distribution splits further, a leaf or an internal choice is a
//     child), left first; a binary root that is one leaf is the one leaf child of a node over itself
//   - the grid over the union of the children's boxes (glm's min/max), the exponents, the slot
//     assignment by octant (cwbvhAssignSlots: the cheapest free (child, slot) pair first, ties by child
//     then slot, costs in double), the meta bytes and the conservatively quantised bytes, into
//     scratch texels 7q .. 7q + 6 (the node's 5 texels without childBase and triBase, then the first
//     triangle in v1's order of each leaf slot)
//   - its inner children appended to the queue (one atomicAdd per node), each with the step from its
//     parent for the pointer jumping that numbers the nodes as the CPU packer does (depth-first, slot
//     order, a node's inner children consecutive): .x the inner children counted before the child's
//     own (the parent's, then the earlier inner siblings' subtrees' nodes less their roots), .y the
//     triangles written before the child's (the parent's leaf slots', then the earlier siblings'
//     subtrees').
// Float arithmetic that decides a bit is written as the CPU's: `precise` where a fused multiply-add
// could change a rounding, comparisons not min/max where an equal zero's sign matters. No NaN reaches
// a comparison: the boxes are finite (validated on the CPU before the build).
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Children { uint children[]; };
layout(std430, binding = 1) readonly buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 2) readonly buffer Info { uint info[]; };
layout(std430, binding = 3) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 4) readonly buffer Decisions { uint decisions[]; };
layout(std430, binding = 5) readonly buffer V1Steps { uvec4 v1Steps[]; };  // the binary pack's path sums
layout(std430, binding = 6) readonly buffer PackState { uvec3 dispatchGroups; uint unfinished; uint finalHalf; uint depth; };
layout(std430, binding = 7) buffer WideStateBuffer { WideState state; };  // gpubuild_wide_state.glsl
layout(std430, binding = 8) buffer Queue { uvec4 queue[]; };               // (binary, parent, rank, 0)
layout(std430, binding = 9) writeonly buffer WideSteps { uvec4 wideSteps[]; };        // first half
layout(std430, binding = 10) writeonly buffer WideAncestors { uint wideAncestors[]; };  // first half
layout(std430, binding = 11) writeonly buffer Scratch { uvec4 scratch[]; };          // 7 per entry
uniform uint u_count;  // primitives n

const uint kWidth = 8u;
const uint kMetaInner = 0x80u;   // layout/layout_cwbvh.hpp kCwbvhMetaInner
const uint kMinExponent = 1u, kMaxExponent = 254u;

bool isLeaf(uint x) { return info[2u * x + 1u] == 0u; }
uint decision(uint x, uint i) { return (decisions[2u * x + (i - 1u) / 4u] >> (8u * ((i - 1u) % 4u))) & 0xFFu; }
vec3 boxLow(uint x) { return vec3(nodeBoxes[6u * x], nodeBoxes[6u * x + 1u], nodeBoxes[6u * x + 2u]); }
vec3 boxHigh(uint x) { return vec3(nodeBoxes[6u * x + 3u], nodeBoxes[6u * x + 4u], nodeBoxes[6u * x + 5u]); }
vec3 minOf(vec3 x, vec3 y) { return vec3(y.x < x.x ? y.x : x.x, y.y < x.y ? y.y : x.y, y.z < x.z ? y.z : x.z); }
vec3 maxOf(vec3 x, vec3 y) { return vec3(x.x < y.x ? y.x : x.x, x.y < y.y ? y.y : x.y, x.z < y.z ? y.z : x.z); }
vec3 center(vec3 lo, vec3 hi) {
  precise vec3 c = 0.5 * (lo + hi);
  return c;
}

float scaleOf(uint e) { return uintBitsToFloat(e << 23); }
// p + q * scale: q * scale is exact, so the one rounding is the sum's (layout/layout_cwbvh.hpp cwbvhDecode).
float decode(float p, uint q, float scale) {
  precise float v = p + float(q) * scale;
  return v;
}

// The smallest e in 1..254 with decode(p, 255, 2^(e - 127)) >= hi, from a guess settled by the loops
// (pack_cwbvh.cpp chooseExponent: decoding is monotone in e, so any start ends at the same e).
uint chooseExponent(float p, float hi) {
  precise float extent = hi - p;  // the guess only: it may round, or overflow to +infinity
  int e = int(kMinExponent);
  if (isinf(extent)) e = int(kMaxExponent);
  else if (extent > 0.0) e = clamp(int(ceil(log2(extent / 255.0))) + 127, int(kMinExponent), int(kMaxExponent));
  uint u = uint(e);
  while (u > kMinExponent && decode(p, 255u, scaleOf(u - 1u)) >= hi) --u;
  while (u < kMaxExponent && !(decode(p, 255u, scaleOf(u)) >= hi)) ++u;
  return u;
}

// qlo: the largest q with decode <= lo; qhi: the smallest with decode >= hi (pack_cwbvh.cpp quantise:
// from a guess, settled by the loops on the decoded values).
uvec2 quantise(float p, float scale, float lo, float hi) {
  float gl = floor((lo - p) / scale), gh = ceil((hi - p) / scale);
  uint qlo = gl >= 255.0 ? 255u : gl >= 0.0 ? uint(gl) : 0u;
  while (qlo > 0u && decode(p, qlo, scale) > lo) --qlo;
  while (qlo < 255u && decode(p, qlo + 1u, scale) <= lo) ++qlo;
  uint qhi = gh >= 255.0 ? 255u : gh >= 0.0 ? uint(gh) : 0u;
  while (qhi < 255u && decode(p, qhi, scale) < hi) ++qhi;
  while (qhi > 0u && decode(p, qhi - 1u, scale) >= hi) --qhi;
  return uvec2(min(qlo, qhi), qhi);
}

void putByte(inout uvec4 t[4], uint j, uint value) { t[j / 16u][(j / 4u) % 4u] |= value << (8u * (j % 4u)); }

void main() {
  uint q = state.levelBegin + gl_GlobalInvocationID.x;
  if (q >= state.levelEnd) return;
  uint b = queue[q].x;

  // The children, left first: binary node, slot count it was given, leaf or inner.
  uint childNode[8], childSlots[8];
  uint n = 0u, leafMask = 0u;
  if (isLeaf(b)) {
    childNode[0] = b, childSlots[0] = 1u, leafMask = 1u, n = 1u;
  } else {
    uint stackNode[8], stackSlots[8];
    uint split = decision(b, 1u) >> 5;
    stackNode[0] = children[2u * b + 1u], stackSlots[0] = kWidth - split;
    stackNode[1] = children[2u * b], stackSlots[1] = split;
    uint sp = 2u;
    while (sp > 0u) {
      --sp;
      uint x = stackNode[sp], i = stackSlots[sp];
      uint d = isLeaf(x) ? 0u : decision(x, i);
      if ((d & 3u) == 2u) {
        uint k = (d >> 2) & 7u;
        stackNode[sp] = children[2u * x + 1u], stackSlots[sp] = i - k;
        stackNode[sp + 1u] = children[2u * x], stackSlots[sp + 1u] = k;
        sp += 2u;
        continue;
      }
      childNode[n] = x, childSlots[n] = i;
      if ((d & 3u) == 0u) leafMask |= 1u << n;
      ++n;
    }
  }

  // The grid over the children's union, and the slot assignment by octant.
  vec3 lo = vec3(uintBitsToFloat(0x7f800000u)), hi = -lo;
  for (uint c = 0u; c < n; ++c) lo = minOf(lo, boxLow(childNode[c])), hi = maxOf(hi, boxHigh(childNode[c]));
  vec3 p = lo;
  uvec3 e = uvec3(chooseExponent(p.x, hi.x), chooseExponent(p.y, hi.y), chooseExponent(p.z, hi.z));
  vec3 scale = vec3(scaleOf(e.x), scaleOf(e.y), scaleOf(e.z));
  dvec3 parentCenter = dvec3(center(lo, hi));
  dvec3 offset[8];
  for (uint c = 0u; c < n; ++c) offset[c] = dvec3(center(boxLow(childNode[c]), boxHigh(childNode[c])));
  int childOf[8] = int[8](-1, -1, -1, -1, -1, -1, -1, -1);
  uint placed = 0u;
  for (uint round = 0u; round < n; ++round) {
    double bestCost = 0.0;
    int bestChild = -1, bestSlot = -1;
    for (uint c = 0u; c < n; ++c) {
      if ((placed & (1u << c)) != 0u) continue;
      for (uint s = 0u; s < kWidth; ++s) {
        if (childOf[s] >= 0) continue;
        precise double cost = 0.0;
        for (uint a = 0u; a < 3u; ++a) cost += (offset[c][a] - parentCenter[a]) * (((s >> a) & 1u) != 0u ? -1.0 : 1.0);
        if (bestChild < 0 || cost < bestCost) bestCost = cost, bestChild = int(c), bestSlot = int(s);
      }
    }
    childOf[bestSlot] = bestChild;
    placed |= 1u << uint(bestChild);
  }

  // The node's texels, and its inner children's queue entries and steps.
  uint inner = n - uint(bitCount(leafMask));
  uint base = inner > 0u ? atomicAdd(state.queued, inner) : 0u;
  uvec4 bytes[4] = uvec4[4](uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u));  // texels 1..4: meta in bytes 8..15, q from 16
  uvec4 leafFirst[2] = uvec4[2](uvec4(0u), uvec4(0u));
  uint ownTriangles = 0u;
  for (uint s = 0u; s < kWidth; ++s)
    if (childOf[s] >= 0 && (leafMask & (1u << uint(childOf[s]))) != 0u) ownTriangles += info[2u * childNode[childOf[s]]];
  uint rank = 0u, nodesBefore = inner, trianglesBefore = ownTriangles, largest = 0u;
  uint halfBase = finalHalf * (2u * u_count - 1u);
  for (uint s = 0u; s < kWidth; ++s) {
    if (childOf[s] < 0) continue;
    uint c = uint(childOf[s]), x = childNode[c];
    uint meta = kMetaInner;
    if ((leafMask & (1u << c)) != 0u) {
      meta = info[2u * x];
      largest = max(largest, meta);
      leafFirst[s / 4u][s % 4u] = v1Steps[halfBase + x].z;
    } else {
      uint entry = base + rank;
      queue[entry] = uvec4(x, q, rank, 0u);
      wideSteps[entry] = uvec4(nodesBefore, trianglesBefore, 0u, 0u);
      wideAncestors[entry] = q;
      nodesBefore += counts[kWidth * x + childSlots[c] - 1u] - 1u;
      trianglesBefore += info[2u * x];
      ++rank;
    }
    putByte(bytes, 8u + s, meta & 0xFFu);
    vec3 bl = boxLow(x), bh = boxHigh(x);
    for (uint a = 0u; a < 3u; ++a) {
      uvec2 qq = quantise(p[a], scale[a], bl[a], bh[a]);
      putByte(bytes, 16u + 8u * a + s, qq.x);
      putByte(bytes, 16u + 8u * (3u + a) + s, qq.y);
    }
  }
  if (largest > 127u) atomicMax(state.largestLeaf, largest);
  scratch[7u * q] = uvec4(floatBitsToUint(p), e.x | e.y << 8 | e.z << 16 | n << 24);
  for (uint t = 0u; t < 4u; ++t) scratch[7u * q + 1u + t] = bytes[t];
  scratch[7u * q + 5u] = leafFirst[0];
  scratch[7u * q + 6u] = leafFirst[1];
}
