// refitOrder and refitBvh (builders/refit.hpp).
#include "builders/refit.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>

#include "builders/build_util.hpp"  // runJobs
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

namespace {

void checkFrame(const FrameTriangles& frame) {
  const size_t n = frame.v0.size();
  if (frame.v1.size() != n || frame.v2.size() != n)
    throw std::invalid_argument("refit: " + std::to_string(n) + "/" + std::to_string(frame.v1.size()) + "/" +
                                std::to_string(frame.v2.size()) + " triangle vertices (v0/v1/v2 differ in length)");
}

// Refits the nodes order[begin, end) in turn (children before parents), adding each to `sums`.
void refitRange(Bvh& bvh, std::span<const uint32_t> order, const FrameTriangles& frame, SahSums* sums) {
  const size_t n = frame.v0.size();
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

}  // namespace

void refitBvh(Bvh& bvh, std::span<const uint32_t> order, const FrameTriangles& frame, SahSums* sums) {
  checkFrame(frame);
  refitRange(bvh, order, frame, sums);
}

RefitSchedule refitSchedule(const Bvh& bvh, unsigned threads) {
  RefitSchedule s;
  s.order = refitOrder(bvh);
  const uint32_t count = uint32_t(s.order.size());
  const uint32_t cut = std::max<uint32_t>(kRefitTaskNodes, count / (8u * std::max(1u, threads)));
  if (threads <= 1 || count <= cut) {
    if (count > 0) s.tasks.push_back({0u, count});
    return s;
  }
  // Subtree sizes, and each node's position in the order (its subtree is [pos - size + 1, pos]).
  std::vector<uint32_t> size(bvh.nodes.size(), 1), position(bvh.nodes.size(), 0);
  for (uint32_t p = 0; p < count; ++p) {
    const uint32_t i = s.order[p];
    position[i] = p;
    const BvhNode& node = bvh.nodes[i];
    if (!node.isLeaf()) size[i] = 1 + size[node.left] + size[node.right];
  }
  std::vector<uint8_t> inTask(count, 0);
  std::vector<uint32_t> stack{s.order.back()};  // the root is last
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh.nodes[i];
    if (node.isLeaf() || size[i] <= cut) {
      const uint32_t end = position[i] + 1, begin = end - size[i];
      s.tasks.push_back({begin, end});
      std::fill(inTask.begin() + begin, inTask.begin() + end, uint8_t(1));
      continue;
    }
    stack.push_back(node.right);
    stack.push_back(node.left);
  }
  std::sort(s.tasks.begin(), s.tasks.end());
  for (uint32_t p = 0; p < count; ++p)
    if (!inTask[p]) s.top.push_back(p);
  return s;
}

void refitBvh(Bvh& bvh, const RefitSchedule& schedule, const FrameTriangles& frame, unsigned threads,
              SahSums* sums) {
  checkFrame(frame);
  const std::span<const uint32_t> order(schedule.order);
  if (schedule.tasks.size() <= 1 && schedule.top.empty()) {
    refitRange(bvh, order, frame, sums);
    return;
  }
  // Each task's first error kept in its slot; the lowest task's is the first in `order`.
  std::vector<std::exception_ptr> errors(schedule.tasks.size());
  detail::runJobs(schedule.tasks.size(), threads, [&](size_t t) {
    const auto [begin, end] = schedule.tasks[t];
    try {
      refitRange(bvh, order.subspan(begin, end - begin), frame, nullptr);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  BvhNode* nodes = bvh.nodes.data();
  for (const uint32_t p : schedule.top) {  // inner nodes above the tasks, children first
    BvhNode& node = nodes[order[p]];
    Aabb box = nodes[node.left].bounds;
    box.grow(nodes[node.right].bounds);
    node.bounds = box;
  }
  if (sums)  // in `order`, as sahCost sums: the same double, bit for bit
    for (const uint32_t index : order) sums->add(nodes[index]);
}

void refitBvh(Bvh& bvh, const FrameTriangles& frame) {
  const std::vector<uint32_t> order = refitOrder(bvh);
  refitBvh(bvh, order, frame);
}

void checkFiniteVertices(const FrameTriangles& frame) {
  auto finite = [](const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  for (size_t i = 0; i < frame.size(); ++i)
    if (!finite(frame.v0[i]) || !finite(frame.v1[i]) || !finite(frame.v2[i]))
      throw InputError("update: triangle " + std::to_string(i) + " has a non-finite vertex");
}

}  // namespace bvhlab
