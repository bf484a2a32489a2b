// Embree 3's generic BVH builder (rtcBuildBVH) through its user-callback API, converted to our Bvh.
// It is the reference the other builders are measured against (NOTES.md has its figures).
//   embree       RTC_BUILD_QUALITY_MEDIUM: binned SAH
//   embree-low   RTC_BUILD_QUALITY_LOW: Morton-code builder
// HIGH is not offered: its extra is spatial splits, which reference a primitive from several leaves
// (our Bvh promises each primitive exactly once); without room for such duplicates it built the same
// tree as MEDIUM (same SAH and node count on the bunny and a 1M-triangle sphere, measured).
// Embree runs on its own thread pool (all hardware threads) and ignores BuildOptions::threads.
#include <algorithm>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include "builders/builder.hpp"
#include "builders/bvh.hpp"

namespace bvhlab {

namespace {

// One device for the process: creating one starts Embree's thread pool (milliseconds). It is never
// released, so no build pays for it twice and no static destructor races Embree's own shutdown.
RTCDevice embreeDevice() {
  static std::once_flag once;
  static RTCDevice device = nullptr;
  std::call_once(once, [] { device = rtcNewDevice(nullptr); });
  if (!device) throw std::runtime_error("embree: rtcNewDevice failed: " + std::to_string(int(rtcGetDeviceError(nullptr))));
  return device;
}

// Nodes live in Embree's per-thread allocator (freed with the RTCBVH).
struct EmbreeNode {
  bool leaf;
};
struct EmbreeInner : EmbreeNode {
  EmbreeNode* children[2];
};
struct EmbreeLeaf : EmbreeNode {
  uint32_t count;
  uint32_t* ids() { return reinterpret_cast<uint32_t*>(this + 1); }
};

void* createNode(RTCThreadLocalAllocator alloc, unsigned int childCount, void*) {
  // maxBranchingFactor = 2, so Embree asks for binary nodes only.
  void* mem = rtcThreadLocalAlloc(alloc, sizeof(EmbreeInner), alignof(EmbreeInner));
  return new (mem) EmbreeInner{{false}, {nullptr, nullptr}};
}

void setNodeChildren(void* node, void** children, unsigned int childCount, void*) {
  auto* inner = static_cast<EmbreeInner*>(node);
  for (unsigned int i = 0; i < childCount && i < 2; ++i) inner->children[i] = static_cast<EmbreeNode*>(children[i]);
}

// Bounds are recomputed bottom-up from the input boxes after conversion (exactly tight by
// construction), so Embree's copies are not kept.
void setNodeBounds(void*, const RTCBounds**, unsigned int, void*) {}

void* createLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
  void* mem = rtcThreadLocalAlloc(alloc, sizeof(EmbreeLeaf) + count * sizeof(uint32_t), alignof(EmbreeLeaf));
  auto* leaf = new (mem) EmbreeLeaf{{true}, uint32_t(count)};
  for (size_t i = 0; i < count; ++i) leaf->ids()[i] = prims[i].primID;
  return leaf;
}

Bvh buildWithEmbree(const BuildInput& input, const BuildOptions& options, RTCBuildQuality quality) {
  RTCDevice device = embreeDevice();
  const size_t n = input.boxes.size();
  // Embree reorders this array in place, so it is made afresh for every build.
  std::vector<RTCBuildPrimitive> prims(n);
  for (size_t i = 0; i < n; ++i) {
    const Aabb& b = input.boxes[i];
    prims[i] = {b.min.x, b.min.y, b.min.z, 0u, b.max.x, b.max.y, b.max.z, uint32_t(i)};
  }

  RTCBVH handle = rtcNewBVH(device);
  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.buildQuality = quality;
  args.maxBranchingFactor = 2;
  // Embree's default depth limit (32) makes it give up on deep but legal trees; when a node nears
  // the limit Embree stops using the SAH and halves ranges, so a limit far above log2(n) is safe.
  args.maxDepth = 1024;
  args.minLeafSize = 1;
  // Embree caps leaves at RTC_BUILD_MAX_PRIMITIVES_PER_LEAF (32); smaller leaves honour the limit.
  static_assert(kEmbreeMaxLeafSize == uint32_t(RTC_BUILD_MAX_PRIMITIVES_PER_LEAF));
  args.maxLeafSize = std::min<uint32_t>(options.maxLeafSize, RTC_BUILD_MAX_PRIMITIVES_PER_LEAF);
  args.traversalCost = options.cost.traversalCost;
  args.intersectionCost = options.cost.intersectionCost;
  args.bvh = handle;
  args.primitives = prims.data();
  args.primitiveCount = n;
  args.primitiveArrayCapacity = n;  // no room for spatial-split duplicates
  args.createNode = createNode;
  args.setNodeChildren = setNodeChildren;
  args.setNodeBounds = setNodeBounds;
  args.createLeaf = createLeaf;
  const auto* root = static_cast<EmbreeNode*>(rtcBuildBVH(&args));
  if (!root) {
    const RTCError error = rtcGetDeviceError(device);
    rtcReleaseBVH(handle);
    throw std::runtime_error("embree: rtcBuildBVH failed (RTCError " + std::to_string(int(error)) + ")");
  }

  // Convert depth-first with an explicit stack; siblings get adjacent indices, children follow
  // their parents, so the reverse index order is a valid bottom-up order for the refit.
  Bvh bvh;
  bvh.nodes.reserve(2 * n - 1);
  bvh.primIndices.reserve(n);
  bvh.nodes.push_back({});
  std::vector<std::pair<const EmbreeNode*, uint32_t>> stack{{root, 0u}};
  while (!stack.empty()) {
    auto [en, index] = stack.back();
    stack.pop_back();
    if (en->leaf) {
      const auto* leaf = static_cast<const EmbreeLeaf*>(en);
      if (leaf->count == 0) {  // count 0 would read as an inner node
        rtcReleaseBVH(handle);
        throw std::runtime_error("embree: rtcBuildBVH produced an empty leaf");
      }
      BvhNode& node = bvh.nodes[index];
      node.first = uint32_t(bvh.primIndices.size());
      node.count = leaf->count;
      const uint32_t* ids = const_cast<EmbreeLeaf*>(leaf)->ids();
      for (uint32_t i = 0; i < leaf->count; ++i) {
        node.bounds.grow(input.boxes[ids[i]]);
        bvh.primIndices.push_back(ids[i]);
      }
    } else {
      const auto* inner = static_cast<const EmbreeInner*>(en);
      const uint32_t left = uint32_t(bvh.nodes.size());
      bvh.nodes[index].left = left;
      bvh.nodes[index].right = left + 1;
      bvh.nodes.push_back({});
      bvh.nodes.push_back({});
      stack.push_back({inner->children[1], left + 1});
      stack.push_back({inner->children[0], left});
    }
  }
  rtcReleaseBVH(handle);
  for (size_t i = bvh.nodes.size(); i-- > 0;) {
    BvhNode& node = bvh.nodes[i];
    if (!node.isLeaf()) {
      node.bounds = bvh.nodes[node.left].bounds;
      node.bounds.grow(bvh.nodes[node.right].bounds);
    }
  }
  return bvh;
}

}  // namespace

Bvh buildEmbreeBvh(const BuildInput& input, const BuildOptions& options) {
  return buildWithEmbree(input, options, RTC_BUILD_QUALITY_MEDIUM);
}

Bvh buildEmbreeLowBvh(const BuildInput& input, const BuildOptions& options) {
  return buildWithEmbree(input, options, RTC_BUILD_QUALITY_LOW);
}

}  // namespace bvhlab
