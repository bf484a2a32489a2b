// LBVH (Lauterbach et al. 2009, "Fast BVH Construction on GPUs"; the tree Karras 2012 builds in
// parallel): centroids quantised to a 2^21 grid over their bounds, interleaved into 63-bit Morton
// codes (with BuildOptions::mortonSizeBits, size bits among the upper ones: builders/morton.hpp),
// radix-sorted; each node splits its range where the highest differing code bit flips (equal
// codes: in the middle), down to single primitives. A bottom-up pass then refits the boxes and
// collapses every subtree of at most maxLeafSize primitives whose SAH cost as one leaf is no higher
// than as a subtree. Fast and SAH-blind above the leaves: the usual quality gap to SAH builders.
#include <array>
#include <bit>
#include <utility>
#include <vector>

#include "builders/morton.hpp"
#include "builders/morton_sort.hpp"
#include "builders/build_util.hpp"
#include "builders/collapse.hpp"

namespace bvhlab {

namespace {

using detail::Keyed;

struct Task {
  uint32_t node, begin, end;
};

// Splits [begin, end) of the sorted codes at the first index whose code has the highest differing
// bit set (binary search: codes in the range share every bit above it).
class MortonStepper {
 public:
  explicit MortonStepper(const detail::ScratchVector<Keyed>& keys) : keys_(keys) {}

  detail::NodeStep<Task> step(const Task& task, const Aabb&) {
    detail::NodeStep<Task> step;
    if (task.end - task.begin == 1) return step;
    const uint64_t first = keys_[task.begin].code, last = keys_[task.end - 1].code;
    uint32_t mid;
    if (first == last) {
      mid = task.begin + (task.end - task.begin) / 2;
    } else {
      const uint64_t bit = std::bit_floor(first ^ last);
      uint32_t lo = task.begin + 1, hi = task.end - 1;  // answer in [lo, hi]: keys_[hi] has the bit
      while (lo < hi) {
        const uint32_t probe = lo + (hi - lo) / 2;
        if (keys_[probe].code & bit)
          hi = probe;
        else
          lo = probe + 1;
      }
      mid = lo;
    }
    step.leaf = false;  // boxes are refit bottom-up afterwards
    step.child[0] = {0, task.begin, mid};
    step.child[1] = {0, mid, task.end};
    return step;
  }

 private:
  const detail::ScratchVector<Keyed>& keys_;
};

}  // namespace

Bvh buildLbvh(const BuildInput& input, const BuildOptions& options) {
  const uint32_t n = uint32_t(input.boxes.size());
  const detail::MortonEncoder encoder(input, options.mortonSizeBits, options.mortonGrid);
  detail::ScratchVector<Keyed> keys(n);
  for (uint32_t i = 0; i < n; ++i) keys[i] = {encoder.code(i), i};
  detail::sortMortonKeys(keys, detail::resolveThreads(options.threads));

  std::vector<BvhNode> full = detail::buildTopDown(Aabb{}, Task{0, 0, n}, detail::resolveThreads(options.threads),
                                                   [&] { return MortonStepper(keys); });

  // Bottom-up (children have larger indices than their parents): refit boxes, let every leaf name its
  // primitive, then collapse small subtrees by SAH (builders/collapse.hpp).
  for (size_t i = full.size(); i-- > 0;) {
    BvhNode& node = full[i];
    if (node.isLeaf()) {
      node.first = keys[node.first].id;
      node.bounds = input.boxes[node.first];
    } else {
      node.bounds = full[node.left].bounds;
      node.bounds.grow(full[node.right].bounds);
    }
  }
  return detail::collapseLeavesBySah(full, options);
}

}  // namespace bvhlab
