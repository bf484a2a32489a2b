// GPU pack into cwbvh, step 2: the SAH-optimal collapse to width 8 (layout/collapse_wide.hpp, Ylitie,
// Karras & Laine 2017, section 4.1), its dynamic program bottom-up as the collapse phase climbs
// (atomic counters: the second child to arrive solves the parent). Over the COLLAPSED binary tree: a
// node whose info says it emits no inner node is a binary leaf, whose cost is Ci A P for every slot
// count; its descendants are skipped. Per inner node p that emits inner nodes, for i = 1..8 slots:
//   costs[8p + i - 1]   C(p, i), in double, with the CPU's operations in the CPU's order under
//                       `precise` (no fused multiply-add): leaf Ci A P (infinite past the leaf cap),
//                       internal Ct A + Cdistribute(p, 8), Cdistribute(p, j) the first least of
//                       C(left, k) + C(right, j - k) over k = 1..j - 1 (strict <), ties to the leaf
//   counts[8p + i - 1]  the wide nodes the choice makes in p's subtree (0 for a leaf, 1 + the two
//                       sides' for an internal node, the sides' for a distribution): the packer's
//                       node numbering needs subtree sizes
//   decisions[2p + ..]  byte i - 1: the choice (0 leaf, 1 internal, 2 distribute) | its split << 2;
//                       bits 5..7 of byte 0: the split of Cinternal's 8 slots
// A is the node's half area as Aabb::halfArea computes it, over the root's, a double quotient rounded as
// the CPU's IEEE division rounds it (divideRounded), so the choices are the CPU's bit for bit. Costs
// are finite sums or +infinity, never NaN.
layout(local_size_x = 256) in;
// bindings 0-2 (children, parents, node boxes) and halfArea: gpubuild_tree_area.glsl
layout(std430, binding = 3) readonly buffer Info { uint info[]; };
layout(std430, binding = 4) coherent buffer Costs { double costs[]; };
layout(std430, binding = 5) coherent buffer Counts { uint counts[]; };
layout(std430, binding = 6) coherent buffer Decisions { uint decisions[]; };
layout(std430, binding = 7) coherent buffer Counters { uint counters[]; };
layout(std430, binding = 8) buffer WideStateBuffer { WideState state; };  // gpubuild_wide_state.glsl
uniform uint u_count;  // primitives n: inner nodes 0 .. n - 2, leaves n - 1 + sorted position
uniform float u_ct, u_ci;

const uint kWidth = 8u;
const uint kMaxLeafSize = 255u;  // builders/bvh.hpp

bool isLeaf(uint x) { return info[2u * x + 1u] == 0u; }

// The CPU's relative area (layout/collapse_wide.cpp relativeAreas): 0 for every node under a root of zero
// area. A root whose area overflows a float is refused by the CPU; here it is flagged (rootInfinite, an
// error at the download) before anything is solved.
// `root`: the root's half area, finite (main refuses an infinite one).
double area(uint x, double root) { return root > 0.0 ? divideRounded(double(halfArea(x)), root) : 0.0; }

// C(x, 1..8) of a child: a binary leaf's Ci A P whatever the slots, else what x's solve stored.
void childCosts(uint x, double root, out double c[8]) {
  if (isLeaf(x)) {
    precise double leaf = double(u_ci) * area(x, root) * double(info[2u * x]);
    for (uint i = 0u; i < kWidth; ++i) c[i] = leaf;
  } else {
    for (uint i = 0u; i < kWidth; ++i) c[i] = costs[kWidth * x + i];
  }
}
uint childCount(uint x, uint i) { return isLeaf(x) ? 0u : counts[kWidth * x + i - 1u]; }

void solve(uint p, double root, double infinity) {
  uint l = children[2u * p], r = children[2u * p + 1u];
  uint refs = info[2u * p];
  double a = area(p, root);
  precise double leafCost = refs <= min(state.leafCap, kMaxLeafSize) ? double(u_ci) * a * double(refs) : infinity;
  double left[8], right[8];
  childCosts(l, root, left);
  childCosts(r, root, right);
  double dist[9];
  uint best[9];
  for (uint j = 2u; j <= kWidth; ++j) {
    dist[j] = infinity;
    best[j] = 1u;
    for (uint k = 1u; k < j; ++k) {
      precise double d = left[k - 1u] + right[j - k - 1u];
      if (d < dist[j]) dist[j] = d, best[j] = k;
    }
  }
  precise double internalCost = double(u_ct) * a + dist[kWidth];
  uint internalSplit = best[kWidth];
  bool asLeaf = leafCost <= internalCost;
  double c = asLeaf ? leafCost : internalCost;
  uint choice = asLeaf ? 0u : 1u, split = 0u;
  uint count = asLeaf ? 0u : 1u + childCount(l, internalSplit) + childCount(r, kWidth - internalSplit);
  uint bytes[2] = uint[2](0u, 0u);
  for (uint i = 1u; i <= kWidth; ++i) {
    if (i > 1u && dist[i] < c) {
      c = dist[i], choice = 2u, split = best[i];
      count = childCount(l, split) + childCount(r, i - split);
    }
    costs[kWidth * p + i - 1u] = c;
    counts[kWidth * p + i - 1u] = count;
    bytes[(i - 1u) / 4u] |= (choice | split << 2) << (8u * ((i - 1u) % 4u));
  }
  bytes[0] |= internalSplit << 5;
  decisions[2u * p] = bytes[0];
  decisions[2u * p + 1u] = bytes[1];
}

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= u_count) return;
  double infinity = double(uintBitsToFloat(0x7f800000u));
  double root = double(halfArea(0u));
  if (isinf(root)) {  // flagged, not solved: no infinity or NaN enters the program
    state.rootInfinite = 1u;
    return;
  }
  uint node = u_count - 1u + k;
  for (;;) {
    uint parent = parents[node];
    if (parent == 0xffffffffu) break;
    memoryBarrierBuffer();
    if (atomicAdd(counters[parent], 1u) == 0u) break;
    memoryBarrierBuffer();
    if (!isLeaf(parent)) solve(parent, root, infinity);
    node = parent;
  }
}
