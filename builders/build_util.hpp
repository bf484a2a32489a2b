// Small pieces the top-down builders share: primitive references, range bounds, the object-median
// split, and the fixed top-level task split that lets a builder run subtrees on threads while the
// tree stays identical for any thread count.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <span>
#include <thread>
#include <vector>

#include "builders/bvh.hpp"

namespace bvhlab::detail {

// A primitive as the builders move it around: its box, its centroid (the caller's, which need not be
// the box centre) and its input index.
struct PrimRef {
  Aabb box;
  glm::vec3 centroid;
  uint32_t id;
};

inline std::vector<PrimRef> makePrimRefs(const BuildInput& input) {
  std::vector<PrimRef> refs(input.boxes.size());
  for (size_t i = 0; i < refs.size(); ++i)
    refs[i] = {input.boxes[i], input.centroids[i], uint32_t(i)};
  return refs;
}

struct RangeBounds {
  Aabb box;        // union of the primitives' boxes
  Aabb centroids;  // bounds of their centroids
};

inline RangeBounds rangeBounds(std::span<const PrimRef> refs) {
  RangeBounds b;
  for (const PrimRef& r : refs) {
    b.box.grow(r.box);
    b.centroids.grow(r.centroid);
  }
  return b;
}

// The axis of largest extent; ties go to the lower axis so the choice is deterministic.
inline int longestAxis(const glm::vec3& extent) {
  int axis = 0;
  if (extent.y > extent[axis]) axis = 1;
  if (extent.z > extent[axis]) axis = 2;
  return axis;
}

// Puts the `mid` smallest references (by centroid on `axis`, then by id, a total order so the result
// does not depend on the input order of equal centroids) in refs[0, mid).
inline void objectMedianSplit(std::span<PrimRef> refs, size_t mid, int axis) {
  std::nth_element(refs.begin(), refs.begin() + mid, refs.end(), [axis](const PrimRef& a, const PrimRef& b) {
    return a.centroid[axis] < b.centroid[axis] || (a.centroid[axis] == b.centroid[axis] && a.id < b.id);
  });
}

// A node whose subtree is built as one unit: its index in Bvh::nodes (already holding its bounds) and
// its primitive range [begin, end) in the builder's reference array.
struct SubtreeTask {
  uint32_t node = 0;
  uint32_t begin = 0, end = 0;
  uint32_t size() const { return end - begin; }
};

// Builders split their top levels sequentially and defer every node with at most this many primitives
// (and more than kParallelMinSubtree) as an independent subtree. The cut depends on the input size
// only, never on the thread count, so the tree and its node order are the same for any thread count.
inline uint32_t parallelCutSize(size_t primitives) {
  return uint32_t(std::max<size_t>(primitives / 16, 1));
}
constexpr uint32_t kParallelMinSubtree = 1024;  // below this a thread costs more than it saves

inline unsigned resolveThreads(uint32_t requested) {
  if (requested) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

// Runs job(i) for i in [0, count) on up to `threads` threads (the caller's included). Jobs are claimed
// in index order; which thread runs which job never affects the results, which each job writes to its
// own slot. The first exception thrown by a job is rethrown here.
template <class Job>
void runJobs(size_t count, unsigned threads, Job&& job) {
  threads = unsigned(std::min<size_t>(threads, count));
  if (threads <= 1) {
    for (size_t i = 0; i < count; ++i) job(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::atomic<bool> failed{false};
  auto worker = [&] {
    for (size_t i; !failed.load() && (i = next.fetch_add(1)) < count;) {
      try {
        job(i);
      } catch (...) {
        if (!failed.exchange(true)) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

// Appends a subtree built into its own node array (its root at local index 0) to `nodes`: the local
// root replaces nodes[at], the rest go to the end with their child indices shifted.
inline void spliceSubtree(std::vector<BvhNode>& nodes, uint32_t at, const std::vector<BvhNode>& local) {
  const uint32_t shift = uint32_t(nodes.size()) - 1;  // local index k >= 1 lands at nodes.size() + k - 1
  auto fix = [shift](BvhNode n) {
    if (!n.isLeaf()) {
      n.left += shift;
      n.right += shift;
    }
    return n;
  };
  nodes[at] = fix(local[0]);
  for (size_t k = 1; k < local.size(); ++k) nodes.push_back(fix(local[k]));
}

}  // namespace bvhlab::detail
