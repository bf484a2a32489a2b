// packBvh: any builder's Bvh -> the texel streams described in layout/layout.hpp.
#include <bit>
#include <stdexcept>
#include <string>
#include <utility>

#include "layout/layout.hpp"

namespace bvhlab {

namespace {

// std::bit_cast, component by component: GLM's vector floatBitsToUint/uintBitsToFloat
// reinterpret_cast between vector types, which breaks strict aliasing (GCC -O2 miscompiled them in
// tests/test_layout.cpp).
uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
glm::vec3 floats(const glm::uvec4& t) {
  return {std::bit_cast<float>(t.x), std::bit_cast<float>(t.y), std::bit_cast<float>(t.z)};
}

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("packBvh: " + what); }

// The reachable nodes in depth-first pre-order, first (left) child first: the order the NODE stream
// stores them in. Also checks the tree's shape, since everything after relies on it.
struct DepthFirstOrder {
  std::vector<uint32_t> nodes;  // original indices, in stream order
  uint32_t depth = 0;           // root alone = 1
};

DepthFirstOrder depthFirstOrder(const Bvh& bvh) {
  DepthFirstOrder order;
  order.nodes.reserve(bvh.nodes.size());
  std::vector<bool> reached(bvh.nodes.size(), false);
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};  // (node, its depth)
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    if (reached[index])
      fail("node " + std::to_string(index) + " is reached twice (the nodes do not form a tree)");
    reached[index] = true;
    order.nodes.push_back(index);
    order.depth = std::max(order.depth, depth);
    const BvhNode& node = bvh.nodes[index];
    if (node.isLeaf()) {
      if (node.count > kMaxLeafSize)
        fail("node stream: leaf " + std::to_string(index) + " holds " + std::to_string(node.count) +
             " triangles; the count field has 8 bits (at most " + std::to_string(kMaxLeafSize) + ")");
      if (uint64_t(node.first) + node.count > bvh.primIndices.size())
        fail("leaf " + std::to_string(index) + " range [" + std::to_string(node.first) + ", +" +
             std::to_string(node.count) + ") exceeds primIndices (" + std::to_string(bvh.primIndices.size()) +
             ")");
      continue;
    }
    for (uint32_t child : {node.left, node.right})
      if (child >= bvh.nodes.size())
        fail("inner node " + std::to_string(index) + " names child " + std::to_string(child) + " of " +
             std::to_string(bvh.nodes.size()) + " nodes");
    stack.push_back({node.right, depth + 1});  // popped second
    stack.push_back({node.left, depth + 1});   // popped first: child A is adjacent
  }
  return order;
}

void checkSoup(const TriangleSoup& soup) {
  const size_t n = soup.size();
  const bool consistent = soup.v1.size() == n && soup.v2.size() == n && soup.n0.size() == n &&
                          soup.n1.size() == n && soup.n2.size() == n && soup.uv0.size() == n &&
                          soup.uv1.size() == n && soup.uv2.size() == n && soup.material.size() == n &&
                          soup.mesh.size() == n;
  if (!consistent) fail("the triangle soup's arrays differ in length");
}

}  // namespace

PackedBvh packBvh(const Bvh& bvh, const TriangleSoup& soup) {
  if (bvh.nodes.empty()) fail("the BVH has no nodes");
  checkSoup(soup);
  const DepthFirstOrder order = depthFirstOrder(bvh);
  const size_t nodeCount = order.nodes.size();
  // Node indices, including the escape target "one past the last node", must stay below kEscapeEnd.
  if (nodeCount >= kEscapeEnd)
    fail("node stream: " + std::to_string(nodeCount) + " nodes exceed the layout's limit of " +
         std::to_string(kEscapeEnd - 1));
  uint64_t triangleCount = 0;
  for (uint32_t index : order.nodes) triangleCount += bvh.nodes[index].count;
  if (triangleCount > kIndexMask)
    fail("triangle stream: " + std::to_string(triangleCount) + " triangles exceed the layout's limit of " +
         std::to_string(kIndexMask));

  std::vector<uint32_t> streamIndex(bvh.nodes.size(), 0);
  for (size_t i = 0; i < nodeCount; ++i) streamIndex[order.nodes[i]] = uint32_t(i);
  // Pre-order puts a subtree in [i, i + size): the escape is i + size. Children follow their
  // parent, so a reverse sweep sees them first.
  std::vector<uint32_t> subtreeSize(nodeCount, 1);
  for (size_t i = nodeCount; i-- > 0;) {
    const BvhNode& node = bvh.nodes[order.nodes[i]];
    if (!node.isLeaf()) subtreeSize[i] = 1 + subtreeSize[streamIndex[node.left]] + subtreeSize[streamIndex[node.right]];
  }

  PackedBvh packed;
  packed.depth = order.depth;
  packed.nodes.reserve(kNodeTexels * nodeCount);
  packed.triangles.reserve(kTriangleTexels * triangleCount);
  packed.attributes.reserve(kAttributeTexels * triangleCount);
  uint32_t nextTriangle = 0;
  for (size_t i = 0; i < nodeCount; ++i) {
    const BvhNode& node = bvh.nodes[order.nodes[i]];
    const uint64_t end = i + subtreeSize[i];
    const uint32_t escape = end == nodeCount ? kEscapeEnd : uint32_t(end);
    uint32_t a = 0, count = 0;
    if (node.isLeaf()) {
      a = nextTriangle;
      count = node.count;
      for (uint32_t k = 0; k < node.count; ++k) {
        const uint32_t p = bvh.primIndices[node.first + k];
        if (p >= soup.size())
          fail("leaf references primitive " + std::to_string(p) + " but the soup has " +
               std::to_string(soup.size()) + " triangles");
        packed.triangles.push_back({bits(soup.v0[p].x), bits(soup.v0[p].y), bits(soup.v0[p].z), p});
        packed.triangles.push_back({bits(soup.v1[p].x), bits(soup.v1[p].y), bits(soup.v1[p].z), soup.material[p]});
        packed.triangles.push_back({bits(soup.v2[p].x), bits(soup.v2[p].y), bits(soup.v2[p].z), soup.mesh[p]});
        packed.attributes.push_back({bits(soup.n0[p].x), bits(soup.n0[p].y), bits(soup.n0[p].z), bits(soup.uv0[p].x)});
        packed.attributes.push_back({bits(soup.n1[p].x), bits(soup.n1[p].y), bits(soup.n1[p].z), bits(soup.uv0[p].y)});
        packed.attributes.push_back({bits(soup.n2[p].x), bits(soup.n2[p].y), bits(soup.n2[p].z), bits(soup.uv1[p].x)});
        packed.attributes.push_back({bits(soup.uv1[p].y), bits(soup.uv2[p].x), bits(soup.uv2[p].y), 0u});
      }
      nextTriangle += node.count;
    } else {
      a = streamIndex[node.right];  // child A is i + 1 by construction of the order
    }
    const glm::vec3 lo = node.bounds.min, hi = node.bounds.max;
    packed.nodes.push_back({bits(lo.x), bits(lo.y), bits(lo.z), a | ((count & 0xFu) << 28)});
    packed.nodes.push_back({bits(hi.x), bits(hi.y), bits(hi.z), escape | ((count >> 4) << 28)});
  }
  return packed;
}

NodeRecord unpackNode(const PackedBvh& packed, uint32_t index) {
  if (packed.layout != "v1")
    throw std::invalid_argument("unpackNode decodes layout v1 nodes; this tree is packed in layout '" + packed.layout +
                                "'");
  if (uint64_t(index) * kNodeTexels + 1 >= packed.nodes.size())
    throw std::out_of_range("unpackNode: node " + std::to_string(index) + " of " +
                            std::to_string(packed.nodes.size() / kNodeTexels));
  const glm::uvec4 lo = packed.nodes[kNodeTexels * index + 0];
  const glm::uvec4 hi = packed.nodes[kNodeTexels * index + 1];
  NodeRecord r;
  r.bmin = floats(lo);
  r.bmax = floats(hi);
  r.a = lo.w & kIndexMask;
  r.escape = hi.w & kIndexMask;
  r.count = (lo.w >> 28) | ((hi.w >> 28) << 4);
  return r;
}

void checkStreamLimits(const PackedBvh& packed, const std::string& storage, uint64_t maxTexels) {
  const std::pair<const char*, size_t> streams[] = {
      {"node", packed.nodes.size()}, {"triangle", packed.triangles.size()}, {"attribute", packed.attributes.size()},
      {"vertex", packed.vertices.size()}};
  for (const auto& [name, texels] : streams)
    if (texels > maxTexels)
      throw std::runtime_error(std::string(name) + " stream: " + std::to_string(texels) + " texels exceed the " +
                               storage + " storage limit of " + std::to_string(maxTexels) + " texels");
}

}  // namespace bvhlab
