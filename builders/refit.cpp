// refitOrder and refitBvh (builders/refit.hpp).
#include "builders/refit.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "datasets/scene.hpp"  // InputError

namespace bvhlab {

std::vector<uint32_t> refitOrder(const Bvh& bvh) {
  std::vector<uint32_t> order;
  if (bvh.nodes.empty()) return order;
  order.reserve(bvh.nodes.size());
  std::vector<uint8_t> seen(bvh.nodes.size(), 0);
  // Explicit stack (a degenerate tree may be as deep as it has primitives): a node is pushed once to be
  // expanded and once more, marked, to be emitted after its children.
  std::vector<std::pair<uint32_t, bool>> stack{{0u, false}};
  while (!stack.empty()) {
    auto [index, expanded] = stack.back();
    stack.pop_back();
    if (expanded) {
      order.push_back(index);
      continue;
    }
    if (index >= bvh.nodes.size() || seen[index]++)
      throw std::invalid_argument("refit: malformed BVH: child index out of range or node " + std::to_string(index) +
                                  " reached twice");
    const BvhNode& node = bvh.nodes[index];
    if (node.isLeaf()) {
      order.push_back(index);
      continue;
    }
    stack.push_back({index, true});
    stack.push_back({node.right, false});
    stack.push_back({node.left, false});
  }
  return order;
}

namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

void refitBvh(Bvh& bvh, std::span<const uint32_t> order, const FrameTriangles& frame, SahSums* sums) {
  const size_t n = frame.v0.size();
  if (frame.v1.size() != n || frame.v2.size() != n)
    throw std::invalid_argument("refit: " + std::to_string(n) + "/" + std::to_string(frame.v1.size()) + "/" +
                                std::to_string(frame.v2.size()) + " triangle vertices (v0/v1/v2 differ in length)");
  BvhNode* nodes = bvh.nodes.data();
  const uint32_t* prims = bvh.primIndices.data();
  for (const uint32_t index : order) {
    BvhNode& node = nodes[index];
    if (!node.isLeaf()) {
      Aabb box = nodes[node.left].bounds;
      box.grow(nodes[node.right].bounds);
      node.bounds = box;
      if (sums) sums->add(node);
      continue;
    }
    if (size_t(node.first) + node.count > bvh.primIndices.size())
      throw std::invalid_argument("refit: leaf " + std::to_string(index) + " range past the primitive indices");
    Aabb box;
    bool ok = true;  // every vertex finite: min/max would drop a NaN silently
    for (uint32_t k = node.first; k < node.first + node.count; ++k) {
      const uint32_t prim = prims[k];
      if (prim >= n)
        throw std::invalid_argument("refit: leaf " + std::to_string(index) + " references triangle " +
                                    std::to_string(prim) + " of a frame of " + std::to_string(n));
      const glm::vec3 &a = frame.v0[prim], &b = frame.v1[prim], &c = frame.v2[prim];
      ok &= finite(a) & finite(b) & finite(c);
      box.grow(a);
      box.grow(b);
      box.grow(c);
    }
    if (!ok)
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        const uint32_t prim = prims[k];
        if (!finite(frame.v0[prim]) || !finite(frame.v1[prim]) || !finite(frame.v2[prim]))
          throw InputError("refit: triangle " + std::to_string(prim) + " has a non-finite vertex");
      }
    node.bounds = box;
    if (sums) sums->add(node);
  }
}

void refitBvh(Bvh& bvh, const FrameTriangles& frame) {
  const std::vector<uint32_t> order = refitOrder(bvh);
  refitBvh(bvh, order, frame);
}

}  // namespace bvhlab
