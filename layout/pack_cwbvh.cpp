// packCwbvh: any builder's Bvh -> layout cwbvh (layout/layout_cwbvh.hpp). It goes through v1's packer
// and the collapse to width 8 (layout/collapse_v1.hpp), quantises each wide node's child boxes
// conservatively on the node's grid (Ylitie, Karras & Laine 2017, section 3.1: p, e, qlo, qhi), places
// the children in the 8 slots by octant (section 3.2; cwbvhAssignSlots), and re-orders v1's raw
// triangles so that each node's leaf triangles are consecutive in slot order.
#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "layout/collapse_v1.hpp"
#include "layout/layout_cwbvh.hpp"

namespace bvhlab {

namespace {

constexpr uint32_t kMinExponent = 1, kMaxExponent = 254;

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
float scaleOf(uint32_t e) { return std::bit_cast<float>(e << 23); }  // 2^(e - 127), = the decoder's

// The smallest e in 1..254 whose grid reaches hi: fl(p + 255 * 2^(e - 127)) >= hi. The start,
// ceil(log2(extent / 255)), is only a guess (the addition rounds); the loops settle it on the decoded
// value itself. A flat extent (hi == p) is reached by every exponent, so the smallest allowed, 1, comes
// out: e = 0 would decode as a scale of +0 (or a subnormal on hardware that flushes them), where 1
// keeps the scale a normal power of two and q * scale exact. The children's q are all 0 there anyway.
uint32_t chooseExponent(float p, float hi) {
  const double extent = double(hi) - double(p);
  int e = int(kMinExponent);
  if (extent > 0.0) e = std::clamp(int(std::ceil(std::log2(extent / 255.0))) + 127, int(kMinExponent), int(kMaxExponent));
  uint32_t u = uint32_t(e);
  while (u > kMinExponent && cwbvhDecode(p, 255, scaleOf(u - 1)) >= hi) --u;
  while (u < kMaxExponent && !(cwbvhDecode(p, 255, scaleOf(u)) >= hi)) ++u;
  return u;
}

// A first guess of q from the exact quotient, clamped to 0..255 (a NaN quotient gives 0: the loops and
// the final check decide).
uint32_t guess(double q) { return q >= 255.0 ? 255u : q >= 0.0 ? uint32_t(q) : 0u; }

// qlo: the largest q whose decoded value is <= lo; qhi: the smallest q whose decoded value is >= hi.
// Decoding is monotone in q (an exact, increasing p + q * scale, rounded once), so both are found by
// stepping from the guess; the bounds of the node's grid (q = 0 decodes to p <= lo, q = 255 to at
// least the node's max >= hi) make them exist.
void quantise(float p, float scale, float lo, float hi, uint32_t& qlo, uint32_t& qhi) {
  qlo = guess(std::floor((double(lo) - double(p)) / double(scale)));
  while (qlo > 0 && cwbvhDecode(p, qlo, scale) > lo) --qlo;
  while (qlo < 255 && cwbvhDecode(p, qlo + 1, scale) <= lo) ++qlo;
  qhi = guess(std::ceil((double(hi) - double(p)) / double(scale)));
  while (qhi < 255 && cwbvhDecode(p, qhi, scale) < hi) ++qhi;
  while (qhi > 0 && cwbvhDecode(p, qhi - 1, scale) >= hi) --qhi;
  // A flat child on a grid finer than p's ulp: several q decode to the same value, and qlo may pass
  // qhi; both decode to lo == hi then, so qhi's q serves for both.
  qlo = std::min(qlo, qhi);
  if (!(cwbvhDecode(p, qlo, scale) <= lo && cwbvhDecode(p, qhi, scale) >= hi))
    throw std::logic_error("packCwbvh: a quantised child box does not contain the child's box (a packer bug)");
}

// Byte j of consecutive texels from q (4 a uint, little-endian): the 48 quantised bytes from texel 2,
// the 8 meta bytes as bytes 8..15 of texel 1.
void putByte(glm::uvec4* q, uint32_t j, uint32_t value) { q[j / 16][(j / 4) % 4] |= value << (8 * (j % 4)); }
uint32_t getByte(const glm::uvec4* q, uint32_t j) { return (q[j / 16][(j / 4) % 4] >> (8 * (j % 4))) & 0xFFu; }

}  // namespace

std::array<int, 8> cwbvhAssignSlots(const std::vector<glm::vec3>& centroids, glm::vec3 parentCentroid) {
  if (centroids.empty() || centroids.size() > kCwbvhWidth)
    throw std::invalid_argument("cwbvhAssignSlots: " + std::to_string(centroids.size()) + " children (1 to 8)");
  struct Pair {
    double cost;
    int child, slot;
  };
  std::vector<Pair> pairs;
  for (int c = 0; c < int(centroids.size()); ++c)
    for (int s = 0; s < int(kCwbvhWidth); ++s) {
      double cost = 0.0;  // dot(centroid - parent centroid, octant s's diagonal direction)
      for (int a = 0; a < 3; ++a)
        cost += (double(centroids[size_t(c)][a]) - double(parentCentroid[a])) * ((s >> a) & 1 ? -1.0 : 1.0);
      pairs.push_back({cost, c, s});
    }
  // Greedy: the cheapest remaining (child, slot) pair first; ties by child, then slot, so the result is
  // deterministic. (A NaN cost compares false both ways; the centroids of finite boxes are finite.)
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.cost < y.cost; });
  std::array<int, 8> childOf;
  childOf.fill(-1);
  std::vector<bool> placed(centroids.size(), false);
  for (const Pair& pr : pairs) {
    if (placed[size_t(pr.child)] || childOf[size_t(pr.slot)] >= 0) continue;
    childOf[size_t(pr.slot)] = pr.child;
    placed[size_t(pr.child)] = true;
  }
  return childOf;
}

PackedBvh packCwbvh(const Bvh& bvh, const TriangleSoup& soup) {
  CollapsedV1 collapsed = collapseThroughV1(bvh, soup, kCwbvhWidth);
  const Bvh& binary = collapsed.binary;
  // A binary tree that is one leaf: one node with that leaf as its only child.
  const std::vector<WideNode> single{WideNode{0, {WideChild{0, true, 0}}}};
  const std::vector<WideNode>& wide = collapsed.wide.nodes.empty() ? single : collapsed.wide.nodes;
  const std::vector<glm::uvec4>& v1Triangles = collapsed.v1.triangles;
  const std::vector<glm::uvec4>& v1Attributes = collapsed.v1.attributes;

  PackedBvh out;
  out.layout = kLayoutCwbvh;
  out.nodes.resize(kCwbvhNodeTexels * wide.size());
  out.triangles.reserve(v1Triangles.size());
  out.attributes.reserve(v1Attributes.size());
  std::vector<uint32_t> index(wide.size()), depth(wide.size());
  index[0] = 0, depth[0] = 1;
  uint32_t nextNode = 1, maxDepth = 1;
  std::vector<uint32_t> stack{0};  // wide nodes whose index is given, to be written
  while (!stack.empty()) {
    const uint32_t w = stack.back();
    stack.pop_back();
    const WideNode& n = wide[w];
    const uint32_t k = uint32_t(n.children.size());
    if (k < 1 || k > kCwbvhWidth) throw std::logic_error("packCwbvh: a wide node of " + std::to_string(k) + " children");
    // The grid spans the union of the children's boxes (not the parent's box: it need not be tight).
    Aabb frame;
    for (const WideChild& ch : n.children) frame.grow(binary.nodes[ch.binaryNode].bounds);
    const glm::vec3 p = frame.min;
    glm::uvec3 e(kMinExponent);
    glm::vec3 scale(0.0f);
    for (int a = 0; a < 3; ++a) e[a] = chooseExponent(p[a], frame.max[a]), scale[a] = scaleOf(e[a]);

    glm::uvec4* texels = &out.nodes[size_t(kCwbvhNodeTexels) * index[w]];
    const uint32_t triBase = uint32_t(out.triangles.size() / kTriangleTexels);
    uint32_t childBase = 0, inner = 0;
    for (const WideChild& ch : n.children) inner += !ch.leaf;
    if (inner > 0) childBase = nextNode, nextNode += inner;
    texels[0] = {bits(p.x), bits(p.y), bits(p.z), e.x | e.y << 8 | e.z << 16 | k << 24};
    texels[1] = {childBase, triBase, 0u, 0u};
    // Slot s gets the child that rays of octant s meet first (cwbvhAssignSlots); empty slots keep
    // meta 0 and q bytes 0.
    std::vector<glm::vec3> centroids;
    for (const WideChild& ch : n.children) centroids.push_back(binary.nodes[ch.binaryNode].bounds.center());
    const std::array<int, 8> childOf = cwbvhAssignSlots(centroids, frame.center());
    uint32_t rank = 0;
    for (uint32_t c = 0; c < kCwbvhWidth; ++c) {
      if (childOf[c] < 0) continue;
      const WideChild& ch = n.children[size_t(childOf[c])];
      uint32_t meta = kCwbvhMetaInner;
      if (ch.leaf) {
        meta = collapsed.refs[ch.binaryNode];
        if (meta > kCwbvhMaxLeaf)
          throw std::runtime_error("packCwbvh: a leaf of " + std::to_string(meta) + " triangles; layout cwbvh stores at most " +
                                   std::to_string(kCwbvhMaxLeaf) + " per leaf (a 7-bit count): build with --leaf-size " +
                                   std::to_string(kCwbvhMaxLeaf) + " or less");
        const size_t first = collapsed.first[ch.binaryNode];
        out.triangles.insert(out.triangles.end(), v1Triangles.begin() + ptrdiff_t(kTriangleTexels * first),
                             v1Triangles.begin() + ptrdiff_t(kTriangleTexels * (first + meta)));
        out.attributes.insert(out.attributes.end(), v1Attributes.begin() + ptrdiff_t(kAttributeTexels * first),
                              v1Attributes.begin() + ptrdiff_t(kAttributeTexels * (first + meta)));
      } else {
        index[ch.wideNode] = childBase + rank++;
        depth[ch.wideNode] = depth[w] + 1;
      }
      putByte(&texels[1], 8 + c, meta);  // meta[c]: byte c of texel 1's lanes z, w (its bytes 8..15)
      const Aabb& box = binary.nodes[ch.binaryNode].bounds;
      for (uint32_t a = 0; a < 3; ++a) {
        uint32_t qlo, qhi;
        quantise(p[a], scale[a], box.min[a], box.max[a], qlo, qhi);
        putByte(&texels[2], 8 * a + c, qlo);
        putByte(&texels[2], 8 * (3 + a) + c, qhi);
      }
    }
    maxDepth = std::max(maxDepth, depth[w] + 1);
    for (uint32_t c = kCwbvhWidth; c-- > 0;)  // first inner child on top: walked first, its subtree next to it
      if (childOf[c] >= 0 && !n.children[size_t(childOf[c])].leaf) stack.push_back(n.children[size_t(childOf[c])].wideNode);
  }
  if (out.triangles.size() != v1Triangles.size())
    throw std::logic_error("packCwbvh: the leaves do not cover v1's triangle stream once (a packer bug)");
  out.depth = maxDepth;
  return out;
}

uint32_t CwbvhNode::link(uint32_t c) const {
  uint32_t rank = 0, offset = 0;
  for (uint32_t i = 0; i < c; ++i) {
    if (isInner(i)) ++rank;
    else offset += meta[i];
  }
  return isInner(c) ? childBase + rank : triBase + offset;
}

CwbvhNode unpackCwbvhNode(const PackedBvh& packed, uint32_t index) {
  if (packed.layout != kLayoutCwbvh)
    throw std::invalid_argument("unpackCwbvhNode decodes layout cwbvh; this tree is packed in layout '" + packed.layout + "'");
  if (uint64_t(index) >= cwbvhNodeCount(packed))
    throw std::out_of_range("unpackCwbvhNode: node " + std::to_string(index) + " of " + std::to_string(cwbvhNodeCount(packed)));
  const glm::uvec4* t = &packed.nodes[size_t(kCwbvhNodeTexels) * index];
  CwbvhNode n;
  n.origin = {std::bit_cast<float>(t[0].x), std::bit_cast<float>(t[0].y), std::bit_cast<float>(t[0].z)};
  n.exponent = {t[0].w & 0xFFu, (t[0].w >> 8) & 0xFFu, (t[0].w >> 16) & 0xFFu};
  n.scale = {scaleOf(n.exponent.x), scaleOf(n.exponent.y), scaleOf(n.exponent.z)};
  n.children = t[0].w >> 24;
  n.childBase = t[1].x;
  n.triBase = t[1].y;
  for (uint32_t c = 0; c < 8; ++c) {
    n.meta[c] = getByte(&t[1], 8 + c);
    for (uint32_t a = 0; a < 3; ++a) {
      n.qlo[c][a] = getByte(&t[2], 8 * a + c);
      n.qhi[c][a] = getByte(&t[2], 8 * (3 + a) + c);
      n.bmin[c][a] = cwbvhDecode(n.origin[a], n.qlo[c][a], n.scale[a]);
      n.bmax[c][a] = cwbvhDecode(n.origin[a], n.qhi[c][a], n.scale[a]);
    }
  }
  return n;
}

}  // namespace bvhlab
