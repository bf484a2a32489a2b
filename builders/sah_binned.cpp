// Binned SAH builder (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies"):
// at each node the centroids are dropped into equal-width bins on each axis in one pass, the SAH is
// evaluated at every bin boundary, and the references are partitioned in place. Nodes hold their
// box; the children's boxes come out of the bins, their centroid bounds out of the partition pass,
// so no node rescans its primitives. Top levels run sequentially, subtrees below the fixed cut
// (build_util.hpp) on threads; the tree does not depend on the thread count.
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab {

namespace {

using detail::PrimRef;

// Bin count default, measured on bunny00 (75,408 triangles, leaf 4, Ct = Ci = 1; single thread):
//    bins   SAH cost   build ms
//       8     TODO
//      16
//      32
//      64
constexpr uint32_t kDefaultBins = 16;
constexpr uint32_t kMaxBins = 256;

struct Bin {
  Aabb box;
  uint32_t count = 0;
};

// Work item: a node whose box is set, its reference range and the bounds of its centroids.
struct Task {
  uint32_t node, begin, end;
  Aabb centroids;
};

struct Split {
  int axis = -1;     // -1: no SAH split (all centroids in one bin on every axis)
  uint32_t bin = 0;  // left side = bins 0..bin
  double cost = 0;   // Ci * (A_L N_L + A_R N_R), without the node's own traversal term
  Aabb left, right;
  uint32_t leftCount = 0;
};

// Maps centroids to bins over [origin, origin + extent). An axis whose extent is zero (or so small
// that bins / extent overflows) cannot be binned and is skipped; that is the zero-extent guard.
struct BinMapping {
  glm::vec3 origin, scale;
  std::array<bool, 3> usable;
  uint32_t bins;

  BinMapping(const Aabb& centroids, uint32_t binCount) : origin(centroids.min), bins(binCount) {
    const glm::vec3 extent = centroids.extent();
    for (int a = 0; a < 3; ++a) {
      const float s = float(bins) / extent[a];
      usable[a] = extent[a] > 0.0f && std::isfinite(s);
      scale[a] = usable[a] ? s : 0.0f;
    }
  }
  bool anyUsable() const { return usable[0] || usable[1] || usable[2]; }
  // Inputs are finite (validated) and c >= origin, so the product is finite and >= 0; the maximum
  // centroid lands at ~bins and is clamped into the last bin.
  uint32_t binOf(const glm::vec3& c, int axis) const {
    return std::min(uint32_t((c[axis] - origin[axis]) * scale[axis]), bins - 1);
  }
};

class BinnedBuilder {
 public:
  BinnedBuilder(std::vector<PrimRef>& refs, const BuildOptions& options, uint32_t bins)
      : refs_(refs), options_(options), bins_(bins) {}

  // Processes `root` and its descendants into `nodes`. Nodes whose range size lies in
  // (deferMin, deferMax] are not processed but appended to `deferred` (deferMax = 0: none).
  void build(std::vector<BvhNode>& nodes, const Task& root, uint32_t deferMin, uint32_t deferMax,
             std::vector<Task>* deferred) {
    std::vector<Task> stack{root};
    while (!stack.empty()) {
      Task task = stack.back();
      stack.pop_back();
      const uint32_t n = task.end - task.begin;
      if (task.node != root.node && n > deferMin && n <= deferMax) {
        deferred->push_back(task);
        continue;
      }
      Task children[2];
      if (!splitNode(nodes, task, children)) continue;
      stack.push_back(children[1]);
      stack.push_back(children[0]);
    }
  }

 private:
  // Makes nodes[task.node] a leaf or splits it, filling `children`. Returns false for a leaf.
  bool splitNode(std::vector<BvhNode>& nodes, const Task& task, Task children[2]) {
    const uint32_t n = task.end - task.begin;
    const Aabb box = nodes[task.node].bounds;
    if (n == 1) return makeLeaf(nodes[task.node], task);

    const BinMapping mapping(task.centroids, bins_);
    Split split;
    if (mapping.anyUsable()) split = findSplit(task, mapping);

    const CostModel& c = options_.cost;
    const double area = box.halfArea();
    const bool splitWins = split.axis >= 0 && c.traversalCost * area + split.cost < c.intersectionCost * area * n;
    if (!splitWins && n <= options_.maxLeafSize) return makeLeaf(nodes[task.node], task);

    uint32_t mid;
    Aabb leftBox, rightBox, leftCentroids, rightCentroids;
    if (splitWins) {
      mid = partition(task, mapping, split, leftCentroids, rightCentroids);
      leftBox = split.left;
      rightBox = split.right;
    } else {
      // Median fallback: no SAH split beats a leaf (or none exists: all centroids equal), but the
      // node is over the leaf size limit. Halving bounds the depth by log2(n) from here.
      mid = task.begin + n / 2;
      std::span<PrimRef> range(refs_.data() + task.begin, n);
      detail::objectMedianSplit(range, n / 2, detail::longestAxis(task.centroids.extent()));
      const detail::RangeBounds l = detail::rangeBounds(range.first(n / 2));
      const detail::RangeBounds r = detail::rangeBounds(range.subspan(n / 2));
      leftBox = l.box, rightBox = r.box, leftCentroids = l.centroids, rightCentroids = r.centroids;
    }

    const uint32_t left = uint32_t(nodes.size());
    nodes.push_back({leftBox});
    nodes.push_back({rightBox});
    BvhNode& node = nodes[task.node];
    node.left = left;
    node.right = left + 1;
    node.count = 0;
    children[0] = {left, task.begin, mid, leftCentroids};
    children[1] = {left + 1, mid, task.end, rightCentroids};
    return true;
  }

  static bool makeLeaf(BvhNode& node, const Task& task) {
    node.first = task.begin;
    node.count = task.end - task.begin;
    return false;
  }

  // One pass over the references fills the bins of all three axes; then one sweep per usable axis
  // over its non-empty bins only (a boundary between empty bins repeats its neighbour's split, and
  // near the leaves most bins are empty). Bins are left cleared for the next node.
  Split findSplit(const Task& task, const BinMapping& mapping) {
    for (uint32_t i = task.begin; i < task.end; ++i) {
      const PrimRef& r = refs_[i];
      for (int a = 0; a < 3; ++a) {
        Bin& bin = binsByAxis_[a][mapping.binOf(r.centroid, a)];
        bin.box.grow(r.box);
        ++bin.count;
      }
    }
    const double ci = options_.cost.intersectionCost;
    Split best;
    for (int a = 0; a < 3; ++a) {
      Bin* bins = binsByAxis_[a].data();
      uint32_t used = 0;  // non-empty bins, in order, in occupied_[0, used)
      for (uint32_t b = 0; b < bins_; ++b)
        if (bins[b].count) occupied_[used++] = b;
      if (mapping.usable[a]) {
        // Right sweep: cost and box of the right side starting at occupied bin k.
        Aabb right;
        uint32_t rightCount = 0;
        for (uint32_t k = used - 1; k > 0; --k) {
          right.grow(bins[occupied_[k]].box);
          rightCount += bins[occupied_[k]].count;
          rightCost_[k] = double(right.halfArea()) * rightCount;
          rightBox_[k] = right;
        }
        Aabb left;
        uint32_t leftCount = 0;
        for (uint32_t k = 0; k + 1 < used; ++k) {
          left.grow(bins[occupied_[k]].box);
          leftCount += bins[occupied_[k]].count;
          const double cost = ci * (double(left.halfArea()) * leftCount + rightCost_[k + 1]);
          if (best.axis < 0 || cost < best.cost) best = {a, occupied_[k], cost, left, rightBox_[k + 1], leftCount};
        }
      }
      for (uint32_t k = 0; k < used; ++k) bins[occupied_[k]] = Bin{};
    }
    return best;
  }

  // In-place two-sided partition by bin; collects the centroid bounds of both sides on the way.
  uint32_t partition(const Task& task, const BinMapping& mapping, const Split& split, Aabb& leftCentroids,
                     Aabb& rightCentroids) {
    uint32_t i = task.begin, j = task.end;
    const int axis = split.axis;
    while (true) {
      while (i < j && mapping.binOf(refs_[i].centroid, axis) <= split.bin) leftCentroids.grow(refs_[i++].centroid);
      while (i < j && mapping.binOf(refs_[j - 1].centroid, axis) > split.bin) rightCentroids.grow(refs_[--j].centroid);
      if (i >= j) break;
      std::swap(refs_[i], refs_[j - 1]);
    }
    return i;  // == task.begin + split.leftCount
  }

  std::vector<PrimRef>& refs_;
  const BuildOptions& options_;
  uint32_t bins_;
  std::array<std::array<Bin, kMaxBins>, 3> binsByAxis_;  // all empty between nodes
  std::array<uint32_t, kMaxBins> occupied_;
  std::array<double, kMaxBins> rightCost_;
  std::array<Aabb, kMaxBins> rightBox_;
};

}  // namespace

Bvh buildSahBinnedBvh(const BuildInput& input, const BuildOptions& options) {
  const uint32_t bins = options.bins ? options.bins : kDefaultBins;
  if (bins < 2 || bins > kMaxBins)
    throw std::invalid_argument("sah-binned: bins = " + std::to_string(bins) + " is outside 2.." +
                                std::to_string(kMaxBins));
  std::vector<PrimRef> refs = detail::makePrimRefs(input);
  const uint32_t n = uint32_t(refs.size());
  const detail::RangeBounds all = detail::rangeBounds(refs);

  Bvh bvh;
  bvh.nodes.reserve(2 * size_t(n) - 1);
  bvh.nodes.push_back({all.box});

  // Top levels: sequential, stopping at the fixed cut. Subtrees below it: one job each.
  std::vector<Task> deferred;
  BinnedBuilder(refs, options, bins)
      .build(bvh.nodes, {0, 0, n, all.centroids}, detail::kParallelMinSubtree - 1, detail::parallelCutSize(n),
             &deferred);
  std::vector<std::vector<BvhNode>> subtrees(deferred.size());
  detail::runJobs(deferred.size(), detail::resolveThreads(options.threads), [&](size_t k) {
    const Task& t = deferred[k];
    auto& local = subtrees[k];
    local.reserve(2 * size_t(t.end - t.begin) - 1);
    local.push_back(bvh.nodes[t.node]);
    BinnedBuilder(refs, options, bins).build(local, {0, t.begin, t.end, t.centroids}, 0, 0, nullptr);
  });
  for (size_t k = 0; k < deferred.size(); ++k) detail::spliceSubtree(bvh.nodes, deferred[k].node, subtrees[k]);

  bvh.primIndices.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.primIndices[i] = refs[i].id;
  return bvh;
}

}  // namespace bvhlab
