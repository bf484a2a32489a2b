// hploc: H-PLOC's tree (builders/hploc.hpp says what it is) built on the CPU: as on the GPU, climbs
// from the leaves (in jobs of kLeavesPerJob leaves on BuildOptions::threads threads) finish each
// subtree of the radix tree when its second child is done, and cluster it as builders/hploc.hpp
// defines. The GPU builder hploc-gpu builds the same tree; this one is its reference and the CPU's
// side of the comparison. Leaves are collapsed by SAH (builders/collapse.hpp) as lbvh's and ploc's are.
#include <algorithm>
#include <array>
#include <atomic>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/build_util.hpp"
#include "builders/collapse.hpp"
#include "builders/hploc.hpp"
#include "builders/morton.hpp"
#include "builders/morton_sort.hpp"
#include "builders/ploc_keys.hpp"

namespace bvhlab {

namespace {

using detail::hploc::kGroup;
using detail::hploc::kKeep;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
// Leaves per job: each job climbs from its leaves in order. Jobs only split the work: the tree is the
// same for any thread count (builders/hploc.hpp).
constexpr uint32_t kLeavesPerJob = 4096;

// One PLOC pass over the m <= kGroup clusters of a list (their nodes and boxes): every cluster's
// nearest neighbour within +-radius, mutual pairs merged at the lower position by makeInner(left,
// right, box) -> new node, the list compacted in place. Returns the new count.
template <class MakeInner>
uint32_t clusterPass(std::array<uint32_t, kGroup>& node, std::array<Aabb, kGroup>& box, uint32_t m, uint32_t radius,
                     MakeInner&& makeInner) {
  std::array<uint32_t, kGroup> nearest;
  for (uint32_t x = 0; x < m; ++x) {
    uint64_t best = ~uint64_t(0);
    nearest[x] = x;
    const uint32_t from = x - std::min(x, radius), to = std::min(m - 1, x + radius);
    for (uint32_t j = from; j <= to; ++j) {
      if (j == x) continue;
      const uint64_t key = detail::ploc::candidateKey(detail::ploc::mergedArea(box[x], box[j]), x, j);
      if (key < best) best = key, nearest[x] = j;
    }
  }
  uint32_t out = 0;
  for (uint32_t x = 0; x < m; ++x) {
    const uint32_t y = nearest[x];
    const bool mutual = nearest[y] == x;
    if (mutual && y < x) continue;  // merged into y
    if (!mutual) {
      node[out] = node[x], box[out++] = box[x];
      continue;
    }
    Aabb merged = box[x];
    merged.grow(box[y]);
    node[out] = makeInner(node[x], node[y], merged);
    box[out++] = merged;
  }
  return out;
}

}  // namespace

Bvh buildHploc(const BuildInput& input, const BuildOptions& options) {
  const uint32_t radius = options.plocRadius;
  if (radius < 1 || radius > kMaxPlocRadius)
    throw std::invalid_argument("hploc: plocRadius " + std::to_string(radius) + " is outside 1.." +
                                std::to_string(kMaxPlocRadius));
  if (options.plocTopDown != 0)
    throw std::invalid_argument("hploc: --ploc-top-down " + std::to_string(options.plocTopDown) +
                                " is not supported (only 0: clustering up to the root)");
  const uint32_t n = uint32_t(input.boxes.size());
  const detail::MortonEncoder encoder(input, options.mortonSizeBits, options.mortonGrid);
  detail::ScratchVector<detail::Keyed> keys(n);
  for (uint32_t i = 0; i < n; ++i) keys[i] = {encoder.code(i), i};
  detail::sortMortonKeys(keys, detail::resolveThreads(options.threads));

  // The full tree as ploc numbers it: leaves at n - 1 + (sorted position), inner nodes downwards from
  // n - 2 as they are made. A node is made after its children on any thread (the climb that makes it
  // took their subtrees over through `waiting`), so a parent's index is below its children's and the
  // root, made last, is 0; the emitted tree does not depend on the numbering.
  const unsigned threads = detail::resolveThreads(options.threads);
  const size_t nodes = 2 * size_t(n) - 1;
  std::vector<BvhNode> full(nodes);
  std::vector<detail::CollapseInfo> info(nodes);
  // The lists: a subtree [L, R] keeps its clusters' nodes at list[L ..] and their count at count[L].
  std::vector<uint32_t> list(n), count(n, 1);
  // waiting[s]: the other end of the child that reached the parent over boundary s first.
  std::vector<std::atomic<uint32_t>> waiting(n > 1 ? n - 1 : 0);
  const size_t jobs = (size_t(n) + kLeavesPerJob - 1) / kLeavesPerJob;
  detail::runJobs(jobs, threads, [&](size_t job) {
    for (uint32_t k = uint32_t(job * kLeavesPerJob), end = std::min(n, k + kLeavesPerJob); k < end; ++k) {
      full[n - 1 + k] = BvhNode{input.boxes[keys[k].id], 0, 0, keys[k].id, 1};
      info[n - 1 + k] = detail::collapseLeafInfo(full[n - 1 + k], options);
      list[k] = n - 1 + k;
      if (k + 1 < n) waiting[k].store(kNone, std::memory_order_relaxed);
    }
  });
  std::atomic<uint32_t> made{0};
  auto makeInner = [&](uint32_t left, uint32_t right, const Aabb& box) {
    const uint32_t index = n - 2 - made.fetch_add(1, std::memory_order_relaxed);
    full[index] = BvhNode{box, left, right, 0, 0};
    info[index] = detail::collapseInnerInfo(full[index], info[left], info[right], options);
    return index;
  };

  // delta(i) < delta(j): the keys at i, i + 1 differ in a lower bit than those at j, j + 1.
  auto deltaLess = [&](uint32_t i, uint32_t j) {
    const uint64_t a = keys[i].code ^ keys[i + 1].code, b = keys[j].code ^ keys[j + 1].code;
    return a != b ? a < b : (i ^ (i + 1)) < (j ^ (j + 1));
  };
  // Each job climbs from its leaves in order, as hploc-gpu's invocations climb from theirs.
  auto climb = [&](size_t job) {
    std::array<uint32_t, kGroup> groupNode;
    std::array<Aabb, kGroup> groupBox;
    for (uint32_t leaf = uint32_t(job * kLeavesPerJob), end = std::min(n, leaf + kLeavesPerJob); leaf < end; ++leaf) {
      uint32_t l = leaf, r = leaf;
      for (;;) {
        // The parent spans the boundary between split and split + 1; the first child to arrive waits
        // there (its other end), the second goes on with the parent. The exchange publishes this
        // subtree's nodes and list to the sibling's climb (release) and takes the sibling's (acquire).
        const bool leftChild = l == 0 || (r != n - 1 && deltaLess(r, l - 1));
        const uint32_t split = leftChild ? r : l - 1;
        const uint32_t other = waiting[split].exchange(leftChild ? l : r, std::memory_order_acq_rel);
        if (other == kNone) break;
        (leftChild ? r : l) = other;
        const bool root = l == 0 && r == n - 1;
        const uint32_t left = count[l], right = count[split + 1];
        if (keys[l].code == keys[r].code) {  // a run of equal codes: the radix tree's node, one cluster
          Aabb box = full[list[l]].bounds;
          box.grow(full[list[split + 1]].bounds);
          list[l] = makeInner(list[l], list[split + 1], box);
        } else if (r - l + 1 > kKeep || root) {  // clustered by the group
          for (uint32_t k = 0; k < left; ++k) groupNode[k] = list[l + k];
          for (uint32_t k = 0; k < right; ++k) groupNode[left + k] = list[split + 1 + k];
          uint32_t m = left + right;
          for (uint32_t k = 0; k < m; ++k) groupBox[k] = full[groupNode[k]].bounds;
          while (m > (root ? 1u : kKeep)) m = clusterPass(groupNode, groupBox, m, radius, makeInner);
          for (uint32_t k = 0; k < m; ++k) list[l + k] = groupNode[k];
          count[l] = m;
        } else {  // the left list, then the right one
          for (uint32_t k = 0; k < right; ++k) list[l + left + k] = list[split + 1 + k];
          count[l] = left + right;
        }
        if (root) break;
      }
    }
  };
  if (n > 1) detail::runJobs(jobs, threads, climb);
  if (made.load() != n - 1)
    throw std::logic_error("hploc: " + std::to_string(made.load()) + " inner nodes made of " + std::to_string(n - 1));
  return detail::emitCollapsed([&](uint32_t i) -> const BvhNode& { return full[i]; },
                               [&](uint32_t i) -> detail::CollapseInfo& { return info[i]; });
}

}  // namespace bvhlab
