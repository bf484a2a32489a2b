// bench_builders' Embree yardstick, "embree-raw": rtcBuildBVH at MEDIUM quality with minimal
// callbacks, so that the tree is the nodes Embree's own tutorial would make, with no conversion to our
// layout timed. The nodes live in Embree's thread-local allocator (one RTCBVH for all the builds of a
// benchmark, so its blocks are reused from build to build). Private to bench_builders.cpp.
#pragma once
#include <cstddef>
#include <cstdint>
#include <new>
#include <utility>
#include <vector>

#include <embree3/rtcore.h>

namespace bvhlab::bench {

struct RawNode {
  bool leaf;
};
struct RawInner : RawNode {
  RTCBounds bounds[2];
  RawNode* children[2];
};
struct RawLeaf : RawNode {
  uint32_t count;
  uint32_t ids[1];  // `count` ids follow in the same allocation
};

inline void* rawCreateNode(RTCThreadLocalAllocator alloc, unsigned int, void*) {
  return new (rtcThreadLocalAlloc(alloc, sizeof(RawInner), 16)) RawInner{{false}, {}, {nullptr, nullptr}};
}
inline void rawSetChildren(void* node, void** children, unsigned int count, void*) {
  for (unsigned int i = 0; i < count; ++i) static_cast<RawInner*>(node)->children[i] = static_cast<RawNode*>(children[i]);
}
inline void rawSetBounds(void* node, const RTCBounds** bounds, unsigned int count, void*) {
  for (unsigned int i = 0; i < count; ++i) static_cast<RawInner*>(node)->bounds[i] = *bounds[i];
}
inline void* rawCreateLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
  auto* leaf = new (rtcThreadLocalAlloc(alloc, sizeof(RawLeaf) + count * sizeof(uint32_t), 16)) RawLeaf{{true}, uint32_t(count), {0}};
  for (size_t i = 0; i < count; ++i) leaf->ids[i] = prims[i].primID;
  return leaf;
}

inline double halfArea(const RTCBounds& b) {
  const double x = b.upper_x - b.lower_x, y = b.upper_y - b.lower_y, z = b.upper_z - b.lower_z;
  return x * y + y * z + z * x;
}

// SAH (Ct = Ci = 1, normalised by the root) and node count of a raw tree, from Embree's own bounds.
inline void rawStats(const RawNode* root, const RTCBounds& rootBounds, double& sah, size_t& nodes) {
  double sum = 0.0;
  nodes = 0;
  std::vector<std::pair<const RawNode*, RTCBounds>> stack{{root, rootBounds}};
  while (!stack.empty()) {
    auto [node, bounds] = stack.back();
    stack.pop_back();
    ++nodes;
    if (node->leaf) {
      sum += halfArea(bounds) * static_cast<const RawLeaf*>(node)->count;
    } else {
      sum += halfArea(bounds);
      const auto* inner = static_cast<const RawInner*>(node);
      for (int i = 0; i < 2; ++i) stack.push_back({inner->children[i], inner->bounds[i]});
    }
  }
  sah = sum / halfArea(rootBounds);
}

}  // namespace bvhlab::bench
