// SBVH: SAH with spatial splits (Stich, Friedrich & Dietrich, "Spatial Splits in Bounding Volume
// Hierarchies", HPG 2009).
//
// Per node, over the node's references (a reference = a primitive id + a box holding the part of the
// primitive this reference stands for):
//   1. Object split: binned (as sah-binned: centroids into `bins` equal bins per axis, SAH at every
//      bin boundary), or for nodes of at most `bins` references an exact sweep over the centroids
//      sorted on each axis. A reference's centroid is the input centroid while it is whole, its
//      box's centre once it has been clipped (measured: the clamped input centroid gives 0.62x
//      instead of 0.54x sah-binned's SAH on long thin triangles, the same on meshes).
//   2. When the overlap of that split's two children, area(left box ∩ right box) / area(root), is
//      above BuildOptions::sbvhAlpha, binned spatial splits: the node box is cut into
//      min(bins, max(4, N)) equal slabs per axis (float planes); each reference is clipped into every
//      slab it spans (its triangle, or its box when no triangles are given) and counted as entering
//      its first slab and exiting its last; the SAH is evaluated at every plane. These slab boxes
//      only rank the planes; the chosen split clips with builders/clip.hpp's conservative bounds.
//   3. The cheapest of the two (SAH: Ci (A_L N_L + A_R N_R)); a leaf when that does not beat the
//      leaf cost Ci A N and N <= maxLeafSize.
//   4. Reference unsplitting (Stich et al. section 4.3): a reference that straddles the chosen
//      spatial plane goes whole to the left (C1 = A(L ∪ ref) N_L + A_R (N_R - 1)) or right side
//      (C2 = A_L (N_L - 1) + A(R ∪ ref) N_R) instead of being split (C_split = A_L N_L + A_R N_R)
//      when that is cheaper (ties favour fewer references), the boxes and counts updated as we go.
//      Straddlers that are split are clipped at the plane; a side whose clipped box is empty gets no
//      reference (the exact part on that side is empty: clip.hpp's boxes are conservative).
//
// Reference budget: at most BuildOptions::sbvhReferenceBudget x primitives leaf references. The root
// may create floor((budget - 1) N) extra references; a spatial split may only be chosen where its
// straddlers fit in the node's share, and after a split the rest is shared between the children in
// proportion to their reference counts (as Embree does). The shares depend only on the node, never
// on the order in which nodes are built, so the budget is exact and the tree deterministic; a node
// without budget left gets object splits only. Termination: an object or median split shrinks both
// sides; a spatial split that does not consumes budget, which is finite.
//
// Threads: as builders/build_util.hpp's driver (which assumes a fixed range per node, so SBVH has its
// own): nodes with more than N/16 references are processed level by level (each level's nodes as
// parallel jobs), smaller ones become independent subtree jobs spliced in creation order. Every
// decision depends on the node's own references and budget only, so the tree is the same for any
// thread count.
//
// Numerics: boxes are floats and are only ever intersected/united (exact) or produced by clip.hpp
// (rounded outward), so a child's box lies in its parent's and every leaf box holds the clipped
// part of each of its references. Costs are doubles of finite areas and counts: no NaN can reach a
// comparison (inputs are validated finite; a zero-area root disables spatial splits, whose overlap
// test would divide by it).
//
// Files: builders/sbvh_slabs.hpp (the reference, the slabs of one axis of a spatial-split search and
// the part of a straddling reference in each), here the node step and the driver.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "builders/build_util.hpp"
#include "builders/builder.hpp"
#include "builders/clip.hpp"
#include "builders/sbvh_slabs.hpp"

namespace bvhlab {

namespace {

// Inputs below this size are built on one thread. sbvh keeps its own level-parallel driver (its tasks
// own their references, which the clipping grows), and the threshold the shared driver had when it
// was written, so its trees and node order stay as they were (detail::kParallelMinInput is lower).
constexpr uint32_t kParallelMinInput = 16384;

// Bin count default (object and spatial bins alike), measured with leaf 4, Ct = Ci = 1, alpha 1e-5,
// budget 2x, one thread, best of 3 builds on a shared 2-core machine (times are rough), SAH as a
// ratio to sah-binned's (64 bins):
//    bins   bunny SAH   elephant SAH   armadillo SAH   thin20000 SAH   bunny build ms
//      16     0.967x        0.989x         0.975x          0.542x            920
//      32     0.961x        0.978x         0.976x          0.540x            820
//      64     0.963x        0.978x         0.973x          0.536x           1400
// More bins buy nothing on the meshes (the object split already sweeps small nodes exactly, and a
// node never gets more spatial bins than references, see findSpatialSplit), so 32.
constexpr uint32_t kDefaultBins = 32;
constexpr uint32_t kMaxBins = 256;
static_assert(kMaxBins == kMaxBuildBins, "reviewBuildOptions (builders/registry.cpp) validates --bins against kMaxBuildBins");

using sbvh::Ref, sbvh::Slabs;  // builders/sbvh_slabs.hpp

struct Task {
  uint32_t node = 0;
  std::vector<Ref> refs;
  int64_t budget = 0;  // extra references this subtree may still create
};

struct Step {
  bool leaf = true;
  Aabb childBox[2];
  Task child[2];
};

// a's area with b added, without building the union box twice in the callers.
inline float unionArea(const Aabb& a, const Aabb& b) {
  Aabb u = a;
  u.grow(b);
  return u.halfArea();
}

struct Shared {
  BuildInput input;
  const BuildOptions& options;
  uint32_t bins;
  double rootArea;
  double overlapThreshold;  // alpha * root area
  bool triangles;
};

class Stepper {
 public:
  explicit Stepper(const Shared& s) : s_(s) {}

  // Leaf (the task keeps its references) or a split: the task's references move to the children.
  Step step(Task& task, const Aabb& box) {
    Step step;
    const uint32_t n = uint32_t(task.refs.size());
    if (n <= 1) return step;
    const CostModel& c = s_.options.cost;
    const double area = box.halfArea();

    Aabb centroids;
    for (const Ref& r : task.refs) centroids.grow(r.centroid);
    const ObjectSplit object = findObjectSplit(task.refs, centroids);

    // Spatial splits where the object split's children overlap (or where there is no object split:
    // all centroids coincide, the children would be the node).
    SpatialSplit spatial;
    if (s_.rootArea > 0.0 && task.budget > 0) {
      const double overlap =
          object.axis >= 0 ? double(clip::intersect(object.left, object.right).halfArea()) : area;
      if (overlap > s_.overlapThreshold) spatial = findSpatialSplit(task.refs, box, task.budget);
    }
    const bool useSpatial = spatial.axis >= 0 && (object.axis < 0 || spatial.cost < object.cost);
    const bool anySplit = useSpatial || object.axis >= 0;
    const double bestCost = useSpatial ? spatial.cost : object.axis >= 0 ? object.cost : 0.0;
    const bool splitWins = anySplit && c.traversalCost * area + bestCost < c.intersectionCost * area * n;
    if (!splitWins && n <= s_.options.maxLeafSize) return step;

    std::vector<Ref> left, right;
    bool done = false;
    if (useSpatial) done = partitionSpatial(task.refs, spatial, left, right);
    if (!done && object.axis >= 0) done = partitionObject(task.refs, centroids, object, left, right);
    if (!done) partitionMedian(task.refs, centroids, left, right);

    // Budget: what this split used, the rest shared in proportion to the children's sizes.
    const int64_t nl = int64_t(left.size()), nr = int64_t(right.size());
    const int64_t remaining = std::max<int64_t>(0, task.budget - std::max<int64_t>(0, nl + nr - int64_t(n)));
    const int64_t leftShare = remaining * nl / (nl + nr);

    step.leaf = false;
    for (int side = 0; side < 2; ++side) {
      std::vector<Ref>& refs = side == 0 ? left : right;
      Aabb childBox;
      for (const Ref& r : refs) childBox.grow(r.box);
      step.childBox[side] = childBox;
      step.child[side].refs = std::move(refs);
      step.child[side].budget = side == 0 ? leftShare : remaining - leftShare;
    }
    task.refs.clear();
    task.refs.shrink_to_fit();
    return step;
  }

 private:
  struct ObjectSplit {
    int axis = -1;  // -1: none (all centroids in one bin on every axis)
    bool sweep = false;  // a full sweep: the nLeft smallest by (centroid, id) go left
    uint32_t nLeft = 0;
    uint32_t bin = 0;
    double cost = 0.0;  // Ci (A_L N_L + A_R N_R)
    Aabb left, right;
    glm::vec3 origin{0.0f}, scale{0.0f};
  };

  struct SpatialSplit {
    int axis = -1;
    float plane = 0.0f;
    double cost = 0.0;
    Aabb left, right;
    uint32_t nLeft = 0, nRight = 0;
  };

  // Same mapping as sah-binned: bin = min(trunc((c - origin) * scale), bins - 1); an axis whose
  // extent is 0 (or whose scale overflows) is not binned.
  static int binOf(float c, float origin, float scale, uint32_t bins) {
    return std::min(int((c - origin) * scale), int(bins) - 1);
  }

  static bool centroidLess(const Ref& x, const Ref& y, int axis) {
    return x.centroid[axis] < y.centroid[axis] || (x.centroid[axis] == y.centroid[axis] && x.id < y.id);
  }

  // Small nodes: the exact best object split (every position in centroid order on each axis, as
  // sah-sweep), cheaper than binning when there are fewer references than bins.
  ObjectSplit sweepObjectSplit(const std::vector<Ref>& refs, const Aabb& centroids) {
    ObjectSplit best;
    const size_t n = refs.size();
    const double ci = s_.options.cost.intersectionCost;
    sorted_.assign(refs.begin(), refs.end());
    sweepArea_.resize(n);
    for (int a = 0; a < 3; ++a) {
      if (!(centroids.extent()[a] > 0.0f)) continue;
      std::sort(sorted_.begin(), sorted_.end(), [a](const Ref& x, const Ref& y) { return centroidLess(x, y, a); });
      Aabb right;
      for (size_t k = n - 1; k > 0; --k) {
        right.grow(sorted_[k].box);
        sweepArea_[k] = right.halfArea();
      }
      Aabb left;
      size_t bestK = 0;
      for (size_t k = 1; k < n; ++k) {
        left.grow(sorted_[k - 1].box);
        const double cost = ci * (double(left.halfArea()) * double(k) + double(sweepArea_[k]) * double(n - k));
        if (best.axis < 0 || cost < best.cost) best.axis = a, best.cost = cost, bestK = k;
      }
      if (bestK > 0) {
        best.sweep = true;
        best.nLeft = uint32_t(bestK);
        best.left = best.right = Aabb{};
        for (size_t k = 0; k < n; ++k) (k < bestK ? best.left : best.right).grow(sorted_[k].box);
      }
    }
    return best;
  }

  ObjectSplit findObjectSplit(const std::vector<Ref>& refs, const Aabb& centroids) {
    if (refs.size() <= s_.bins) return sweepObjectSplit(refs, centroids);
    ObjectSplit best;
    const uint32_t bins = s_.bins;
    const double ci = s_.options.cost.intersectionCost;
    const glm::vec3 extent = centroids.extent();
    for (int a = 0; a < 3; ++a) {
      const float scale = float(bins) / extent[a];
      if (!(extent[a] > 0.0f) || !std::isfinite(scale)) continue;
      for (uint32_t b = 0; b < bins; ++b) boxes_[b] = Aabb{}, counts_[b] = 0;
      for (const Ref& r : refs) {
        const int b = binOf(r.centroid[a], centroids.min[a], scale, bins);
        boxes_[b].grow(r.box);
        ++counts_[b];
      }
      Aabb right;
      uint32_t rightCount = 0;
      for (uint32_t b = bins - 1; b > 0; --b) {
        right.grow(boxes_[b]);
        rightCount += counts_[b];
        rightArea_[b] = right.halfArea();
        rightCount_[b] = rightCount;
      }
      Aabb left;
      uint32_t leftCount = 0;
      int bestBin = -1;
      for (uint32_t b = 0; b + 1 < bins; ++b) {
        left.grow(boxes_[b]);
        leftCount += counts_[b];
        if (leftCount == 0 || rightCount_[b + 1] == 0) continue;
        const double cost = ci * (double(left.halfArea()) * leftCount + double(rightArea_[b + 1]) * rightCount_[b + 1]);
        if (best.axis < 0 || cost < best.cost) {
          best.axis = a, best.bin = b, best.cost = cost;
          bestBin = int(b);
        }
      }
      if (bestBin >= 0) {
        best.left = best.right = Aabb{};
        for (uint32_t b = 0; b < bins; ++b) (int(b) <= bestBin ? best.left : best.right).grow(boxes_[b]);
        best.origin = centroids.min;
        best.scale = glm::vec3(0.0f);
        best.scale[a] = scale;
      }
    }
    return best;
  }

  // The part of a reference inside the slab [lo, hi] on `axis`.
  Aabb clipRef(const Ref& r, int axis, float lo, float hi) const {
    if (!s_.triangles) return clip::clipBox(r.box, axis, lo, hi);
    const uint32_t t = r.id;
    return clip::clipReference(s_.input.v0[t], s_.input.v1[t], s_.input.v2[t], r.box, axis, lo, hi);
  }

  SpatialSplit findSpatialSplit(const std::vector<Ref>& refs, const Aabb& box, int64_t budget) {
    SpatialSplit best;
    // At most max(4, n) slabs for n references: near the leaves, where references span most of a
    // node and nearly all of the binning time goes, 32 slabs for 8 references bought nothing
    // (measured on the three meshes: SAH within 0.05%, about a third less time).
    const uint32_t bins = std::min<uint32_t>(s_.bins, std::max<uint32_t>(4, uint32_t(refs.size())));
    const int64_t n = int64_t(refs.size());
    const double ci = s_.options.cost.intersectionCost;
    for (int a = 0; a < 3; ++a) {
      const double lo = box.min[a], hi = box.max[a];
      if (!(hi > lo)) continue;
      // Float planes, non-decreasing, the outer ones the node's faces: a reference's slab range and
      // the final partition compare against the same floats, so they agree.
      float* planes = planes_.data();
      planes[0] = box.min[a];
      planes[bins] = box.max[a];
      for (uint32_t b = 1; b < bins; ++b)
        planes[b] = std::clamp(float(lo + (hi - lo) * double(b) / double(bins)), planes[b - 1], box.max[a]);
      for (uint32_t b = 0; b < bins; ++b) boxes_[b] = Aabb{}, enter_[b] = 0, exit_[b] = 0;
      const Slabs slabs{planes, bins, lo, double(bins) / (hi - lo)};

      for (const Ref& r : refs) {
        // last: the first slab whose upper plane reaches the reference's max; first: the last slab
        // up to `last` whose lower plane is at or below its min. (A reference flat on a plane
        // belongs to the slab below it, as the partition's "max <= plane goes left" rule says.)
        const uint32_t last = slabs.countBelow(r.box.max[a]);
        const uint32_t first = slabs.lastAtMost(r.box.min[a], 0, last);
        ++enter_[first];
        ++exit_[last];
        if (first == last) {
          boxes_[first].grow(r.box);
          continue;
        }
        sbvh::binStraddler(r, a, slabs, first, last, s_.input, s_.triangles, boxes_.data(), pieces_.data());
      }

      Aabb right;
      int64_t rightCount = 0;
      for (uint32_t b = bins - 1; b > 0; --b) {
        right.grow(boxes_[b]);
        rightCount += exit_[b];
        rightBox_[b] = right;
        rightCount_[b] = uint32_t(rightCount);
      }
      Aabb left;
      int64_t leftCount = 0;
      for (uint32_t k = 1; k < bins; ++k) {  // plane k: slabs [0, k) left, [k, bins) right
        left.grow(boxes_[k - 1]);
        leftCount += enter_[k - 1];
        const int64_t nr = rightCount_[k];
        if (leftCount == 0 || nr == 0 || leftCount + nr - n > budget) continue;
        if (!(planes[k] > planes[0] && planes[k] < planes[bins])) continue;  // not inside the node
        const double cost = ci * (double(left.halfArea()) * double(leftCount) + double(rightBox_[k].halfArea()) * double(nr));
        if (best.axis < 0 || cost < best.cost) {
          best.axis = a, best.plane = planes[k], best.cost = cost;
          best.left = left, best.right = rightBox_[k];
          best.nLeft = uint32_t(leftCount), best.nRight = uint32_t(nr);
        }
      }
    }
    return best;
  }

  // Returns false (and leaves the references alone) when a side would be empty.
  bool partitionSpatial(std::vector<Ref>& refs, const SpatialSplit& split, std::vector<Ref>& left,
                        std::vector<Ref>& right) {
    const int a = split.axis;
    const float s = split.plane;
    Aabb lbox = split.left, rbox = split.right;
    double nl = split.nLeft, nr = split.nRight;
    left.clear(), right.clear();
    left.reserve(split.nLeft), right.reserve(split.nRight);
    for (const Ref& r : refs) {
      if (r.box.max[a] <= s) {
        left.push_back(r);
        continue;
      }
      if (r.box.min[a] >= s) {
        right.push_back(r);
        continue;
      }
      // Unsplitting: whole to one side when that is no more expensive than splitting.
      const double areaL = lbox.halfArea(), areaR = rbox.halfArea();
      const double cSplit = areaL * nl + areaR * nr;
      const float areaL1 = unionArea(lbox, r.box), areaR2 = unionArea(rbox, r.box);
      const double c1 = double(areaL1) * nl + areaR * (nr - 1.0);
      const double c2 = areaL * (nl - 1.0) + double(areaR2) * nr;
      if (c1 <= cSplit && c1 <= c2) {
        left.push_back(r);
        lbox.grow(r.box);
        nr -= 1.0;
        continue;
      }
      if (c2 <= cSplit) {
        right.push_back(r);
        rbox.grow(r.box);
        nl -= 1.0;
        continue;
      }
      const float inf = std::numeric_limits<float>::infinity();
      const Aabb pl = clipRef(r, a, -inf, s), pr = clipRef(r, a, s, inf);
      if (!pl.empty()) left.push_back({pl, pl.center(), r.id});
      if (!pr.empty()) right.push_back({pr, pr.center(), r.id});
    }
    if (left.empty() || right.empty()) {
      left.clear(), right.clear();
      return false;
    }
    return true;
  }

  bool partitionObject(std::vector<Ref>& refs, const Aabb& centroids, const ObjectSplit& split, std::vector<Ref>& left,
                       std::vector<Ref>& right) {
    const int a = split.axis;
    left.clear(), right.clear();
    if (split.sweep) {
      std::sort(refs.begin(), refs.end(), [a](const Ref& x, const Ref& y) { return centroidLess(x, y, a); });
      left.assign(refs.begin(), refs.begin() + split.nLeft);
      right.assign(refs.begin() + split.nLeft, refs.end());
      return !left.empty() && !right.empty();
    }
    for (const Ref& r : refs)
      (binOf(r.centroid[a], split.origin[a], split.scale[a], s_.bins) <= int(split.bin) ? left : right).push_back(r);
    return !left.empty() && !right.empty();  // true by construction: the split bin separates occupied bins
  }

  // The n/2 smallest by (centroid on the longest centroid axis, id): a total order within a node (a
  // node never holds two references of one primitive: the two parts of a split go to different
  // children), so the halves do not depend on the references' order.
  void partitionMedian(std::vector<Ref>& refs, const Aabb& centroids, std::vector<Ref>& left, std::vector<Ref>& right) {
    const int axis = detail::longestAxis(centroids.extent());
    const size_t mid = refs.size() / 2;
    std::nth_element(refs.begin(), refs.begin() + mid, refs.end(), [axis](const Ref& x, const Ref& y) {
      return x.centroid[axis] < y.centroid[axis] || (x.centroid[axis] == y.centroid[axis] && x.id < y.id);
    });
    left.assign(refs.begin(), refs.begin() + mid);
    right.assign(refs.begin() + mid, refs.end());
  }

  const Shared& s_;
  std::array<Aabb, kMaxBins> boxes_;
  std::array<uint32_t, kMaxBins> counts_, enter_, exit_, rightCount_;
  std::array<float, kMaxBins> rightArea_;
  std::array<Aabb, kMaxBins> rightBox_;
  std::array<Aabb, kMaxBins> pieces_;
  std::vector<Ref> sorted_;
  std::vector<float> sweepArea_;
  std::array<float, kMaxBins + 1> planes_;
};

// One subtree's nodes and leaf references (leaf `first` indexes `prims`).
struct Subtree {
  std::vector<BvhNode> nodes;
  std::vector<uint32_t> prims;
};

// Applies a step to nodes[task.node]; a leaf's references are appended to `prims`.
void apply(std::vector<BvhNode>& nodes, std::vector<uint32_t>& prims, Task& task, Step& step) {
  if (step.leaf) {
    BvhNode& node = nodes[task.node];
    node.first = uint32_t(prims.size());
    node.count = uint32_t(task.refs.size());
    for (const Ref& r : task.refs) prims.push_back(r.id);
    task.refs = {};
    return;
  }
  const uint32_t left = uint32_t(nodes.size());
  nodes[task.node].left = left;
  nodes[task.node].right = left + 1;
  nodes[task.node].count = 0;
  nodes.push_back({step.childBox[0]});
  nodes.push_back({step.childBox[1]});
  step.child[0].node = left;
  step.child[1].node = left + 1;
}

// Depth first with an explicit stack (a degenerate input can make a deep tree).
void buildSubtree(Subtree& out, Task root, const Shared& shared) {
  Stepper stepper(shared);
  std::vector<Task> stack;
  stack.push_back(std::move(root));
  while (!stack.empty()) {
    Task task = std::move(stack.back());
    stack.pop_back();
    Step step = stepper.step(task, out.nodes[task.node].bounds);
    apply(out.nodes, out.prims, task, step);
    if (step.leaf) continue;
    stack.push_back(std::move(step.child[1]));
    stack.push_back(std::move(step.child[0]));
  }
}

}  // namespace

Bvh buildSbvh(const BuildInput& input, const BuildOptions& options) {
  const uint32_t bins = options.bins ? options.bins : kDefaultBins;
  if (bins < 2 || bins > kMaxBins)
    throw std::invalid_argument("sbvh: bins = " + std::to_string(bins) + " is outside 2.." + std::to_string(kMaxBins));
  if (!(options.sbvhAlpha >= 0.0f) || !std::isfinite(options.sbvhAlpha))
    throw std::invalid_argument("sbvh: alpha must be finite and >= 0 (got " + std::to_string(options.sbvhAlpha) + ")");
  if (!(options.sbvhReferenceBudget >= 1.0f) || !std::isfinite(options.sbvhReferenceBudget))
    throw std::invalid_argument("sbvh: the reference budget must be finite and >= 1 (got " +
                                std::to_string(options.sbvhReferenceBudget) + ")");
  const uint32_t n = uint32_t(input.boxes.size());

  Task root;
  root.refs.resize(n);
  Aabb rootBox;
  for (uint32_t i = 0; i < n; ++i) {
    root.refs[i] = {input.boxes[i], input.centroids[i], i};
    rootBox.grow(input.boxes[i]);
  }
  // Extra references: (budget - 1) N, capped so the leaf count stays a uint32 (the layout's limit is
  // far lower and is checked by the packer).
  const double extra = std::floor((double(options.sbvhReferenceBudget) - 1.0) * double(n));
  root.budget = int64_t(std::min(extra, double(UINT32_MAX) - double(n)));

  const Shared shared{input, options, bins, double(rootBox.halfArea()),
                      double(options.sbvhAlpha) * double(rootBox.halfArea()), input.hasTriangles()};

  Bvh bvh;
  std::vector<BvhNode>& nodes = bvh.nodes;
  nodes.push_back({rootBox});
  root.node = 0;
  if (n < kParallelMinInput) {
    Subtree all;
    all.nodes = std::move(nodes);
    buildSubtree(all, std::move(root), shared);
    bvh.nodes = std::move(all.nodes);
    bvh.primIndices = std::move(all.prims);
    return bvh;
  }

  // Top levels: nodes bigger than the cut, one level at a time, each level's nodes in parallel.
  const unsigned threads = detail::resolveThreads(options.threads);
  const size_t cut = n / detail::kSubtreeFraction;
  std::vector<Task> level, subtrees;
  level.push_back(std::move(root));
  while (!level.empty()) {
    std::vector<Step> steps(level.size());
    detail::runJobs(level.size(), threads, [&](size_t k) {
      Stepper stepper(shared);
      steps[k] = stepper.step(level[k], nodes[level[k].node].bounds);
    });
    std::vector<Task> next;
    for (size_t k = 0; k < level.size(); ++k) {
      apply(nodes, bvh.primIndices, level[k], steps[k]);
      if (steps[k].leaf) continue;
      for (Task& child : steps[k].child) (child.refs.size() <= cut ? subtrees : next).push_back(std::move(child));
    }
    level = std::move(next);
  }

  // Subtrees into their own arrays, biggest first (load balance), spliced in creation order.
  std::vector<Subtree> local(subtrees.size());
  std::vector<uint32_t> order(subtrees.size());
  for (uint32_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t x, uint32_t y) { return subtrees[x].refs.size() > subtrees[y].refs.size(); });
  std::vector<uint32_t> placeholders(subtrees.size());
  for (size_t k = 0; k < subtrees.size(); ++k) placeholders[k] = subtrees[k].node;
  detail::runJobs(
      subtrees.size(), threads,
      [&](size_t k) {
        Task task = std::move(subtrees[k]);
        local[k].nodes.push_back(nodes[task.node]);
        task.node = 0;
        buildSubtree(local[k], std::move(task), shared);
      },
      order);
  for (size_t k = 0; k < local.size(); ++k) {
    // Local node j >= 1 lands at nodes.size() + j - 1; the local root replaces its placeholder.
    const uint32_t shift = uint32_t(nodes.size()) - 1;
    const uint32_t primShift = uint32_t(bvh.primIndices.size());
    auto moved = [&](BvhNode node) {
      if (node.isLeaf())
        node.first += primShift;
      else
        node.left += shift, node.right += shift;
      return node;
    };
    nodes[placeholders[k]] = moved(local[k].nodes[0]);
    for (size_t j = 1; j < local[k].nodes.size(); ++j) nodes.push_back(moved(local[k].nodes[j]));
    bvh.primIndices.insert(bvh.primIndices.end(), local[k].prims.begin(), local[k].prims.end());
    local[k] = {};
  }
  return bvh;
}

}  // namespace bvhlab
