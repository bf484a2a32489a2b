// Binned SAH builder (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies"):
// at each node the centroids are dropped into equal-width bins on each axis in one pass, the SAH is
// evaluated at every bin boundary, and the references are partitioned in place. Threads:
// build_util.hpp's driver (the tree does not depend on the thread count).
//
// The tree is the one the textbook binned build makes (tests/test_sah_binned.cpp builds both): the
// same bins, the same float half areas, the same double costs, the same first minimum over axes x,
// y, z and bins in order, the same leaf test and median fallback. What is faster (docs/builders.md,
// "sah-binned", has the measurements):
// - References are 48 bytes (box corners, centroid; the index in the upper corner's spare lane) in
//   one uninitialised, huge-page-advised array; a bin keeps its count in its lower corner's spare
//   lane, so binning a reference on an axis is two loads, a min, an integer add, a max, two stores.
// - Binning stores each reference's three bins (a byte per axis); the partition classifies from
//   them (no recomputation) and swaps only the misplaced references, in the pairs a two-sided
//   (Hoare) scan would swap, so even the reference order is the textbook's.
// - The three axes' sweeps run together, one axis per SIMD lane (SSE2): bins transposed, prefix and
//   suffix unions, half areas and double costs four lanes at a time.
// - Nodes by size: 2 references, one comparison; 3 or 4, the half areas of all subsets once, then a
//   sorting network per axis; 5..32, the references themselves sorted by (bin, position) with a
//   sorting network on all three axes at once and swept (no bins to fill or clear); up to the bin
//   count, bins compacted to the occupied ones; larger nodes, all bins (two interleaved bin sets from
//   1024 references, so that a run of references in one bin does not chain every update through one
//   memory location).
//
// Files: sah_binned_f4.hpp (four-float SIMD vocabulary), sah_binned.hpp (types and the stepper),
// sah_binned_small.cpp (2..32 references), sah_binned_bins.cpp (binning), sah_binned_lanes.hpp (the
// three-axis sweep), sah_binned_partition.cpp (the partition), and here the node step and the driver.
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

#include "builders/sah_binned.hpp"

namespace bvhlab {

namespace binned {

detail::NodeStep<Task> BinnedStepper::step(const Task& task, const Aabb& box) {
  detail::NodeStep<Task> step;
  const uint32_t n = task.end - task.begin;
  if (n == 1) return step;

  const BinMapping mapping(task.centroids, bins_);
  const Split split = mapping.anyUsable() ? findSplit(task, mapping) : Split{};

  const CostModel& c = options_.cost;
  const double area = box.halfArea();
  const bool splitWins = split.axis >= 0 && c.traversalCost * area + split.cost < c.intersectionCost * area * n;
  if (!splitWins && n <= options_.maxLeafSize) return step;

  uint32_t mid;
  Box4 leftBox, rightBox, leftCentroids, rightCentroids;
  if (splitWins) {
    mid = n == 2 ? partitionPair(task, split) : n <= kTinyMax ? partitionBySides(task, split.leftCount) : partition(task, split);
    leftBox = split.left;
    rightBox = split.right;
    centroidBounds(task.begin, mid, leftCentroids);
    centroidBounds(mid, task.end, rightCentroids);
  } else {
    // Median fallback: no SAH split beats a leaf (or none exists: all centroids equal), but the
    // node is over the leaf size limit. Halving bounds the depth by log2(n) from here.
    mid = task.begin + n / 2;
    medianSplit(task, detail::longestAxis(vec3(task.centroids.hi - task.centroids.lo)));
    bounds(task.begin, mid, leftBox, leftCentroids);
    bounds(mid, task.end, rightBox, rightCentroids);
  }
  step.leaf = false;
  step.childBox[0] = leftBox.aabb();
  step.childBox[1] = rightBox.aabb();
  step.child[0] = {0, task.begin, mid, leftCentroids};
  step.child[1] = {0, mid, task.end, rightCentroids};
  return step;
}

// Each branch returns its finder's result as is, so that it is built where `step` keeps it: assigning
// it to a Split declared before would copy it, 16 bytes at a time, right after the finder stored its
// fields 4 bytes at a time (a failed store-to-load forward per node; measured 1-2% of a bunny build).
Split BinnedStepper::findSplit(const Task& task, const BinMapping& mapping) {
  const uint32_t n = task.end - task.begin;
  if (n == 2) return splitPair(task, mapping);
  if (n <= kTinyMax) return tinySplit(task, mapping);
  reserveScratch(n);
  return n < bins_ ? findSplitSmall(task, mapping) : findSplitLarge(task, mapping);
}

void BinnedStepper::reserveScratch(uint32_t n) {
  if (binOf_ && binOf_->size() >= n + kScratchPad) return;
  binOf_ = std::make_unique<detail::ScratchArray<uint32_t>>(n + kScratchPad);
  std::fill_n(binOf_->data() + n, kScratchPad, 0u);  // the classification reads past the references
  sides_.resize(n / 64 + 2);
}

// Four partial boxes, merged at the end: one box would chain every reference's min and max through
// the previous one (4 cycles each). Min and max are exact, so the order changes no value; it may
// change the sign of a zero bound (min of -0 and +0 returns either, by operand order), which no bin
// index, extent or median split depends on: the trees are those of one box, bit for bit.
void BinnedStepper::centroidBounds(uint32_t begin, uint32_t end, Box4& centroids) const {
  Box4 part[4];
  uint32_t i = begin;
  for (; i + 4 <= end; i += 4)
    for (uint32_t k = 0; k < 4; ++k) part[k].grow(refs_[i + k].centroid, refs_[i + k].centroid);
  for (; i < end; ++i) part[0].grow(refs_[i].centroid, refs_[i].centroid);
  part[0].grow(part[1]), part[2].grow(part[3]), part[0].grow(part[2]);
  centroids.grow(part[0]);
}

  // The n/2 smallest references by (centroid on `axis`, input index) first: a total order, so the
  // split does not depend on where equal centroids happen to sit.
void BinnedStepper::medianSplit(const Task& task, int axis) {
  const uint32_t n = task.end - task.begin;
  Ref* const first = refs_ + task.begin;
  std::nth_element(first, first + n / 2, first + n, [axis](const Ref& a, const Ref& b) {
    const float ca = a.centroid[axis], cb = b.centroid[axis];
    return ca < cb || (ca == cb && a.id() < b.id());
  });
}

void BinnedStepper::bounds(uint32_t begin, uint32_t end, Box4& box, Box4& centroids) const {
  for (uint32_t i = begin; i < end; ++i) {
    box.grow(refs_[i].lo, refs_[i].hi);
    centroids.grow(refs_[i].centroid, refs_[i].centroid);
  }
}

}  // namespace binned

namespace {

// Bin count default, measured on bunny00 (75,408 triangles, triangle centroids, leaf 4, Ct = Ci = 1;
// one thread, best of 15 builds; Embree MEDIUM: SAH 34.261):
//    bins   SAH cost   build ms
//       8     35.294      38.8
//      16     34.736      42.1
//      32     34.443      44.0
//      64     34.254      46.1
//     128     34.034      48.9
// 64 matches Embree's SAH (1.0053x at 32) for ~5% more time; on a 1M-triangle bumpy sphere the
// gap is wider (32 bins: 1.018x Embree, 64: 1.008x), so 64 it is.
constexpr uint32_t kDefaultBins = 64;

}  // namespace

Bvh buildSahBinnedBvh(const BuildInput& input, const BuildOptions& options) {
  using namespace binned;
  const uint32_t bins = options.bins ? options.bins : kDefaultBins;
  if (bins < 2 || bins > kMaxBins)
    throw std::invalid_argument("sah-binned: bins = " + std::to_string(bins) + " is outside 2.." +
                                std::to_string(kMaxBins));
  const uint32_t n = uint32_t(input.boxes.size());
  detail::ScratchArray<Ref> refs(n);
  Box4 box, centroids;
  for (uint32_t i = 0; i < n; ++i) {
    Ref& r = refs[i];
    const Aabb& b = input.boxes[i];
    r = {F4::set(b.min.x, b.min.y, b.min.z, kInf), F4::withLane3(b.max.x, b.max.y, b.max.z, i), point(input.centroids[i])};
    box.grow(r.lo, r.hi);
    centroids.grow(r.centroid, r.centroid);
  }

  Bvh bvh;
  bvh.nodes = detail::buildTopDown(box.aabb(), Task{0, 0, n, centroids}, detail::resolveThreads(options.threads),
                                   [&] { return BinnedStepper(refs.data(), options, bins); });
  bvh.primIndices.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.primIndices[i] = refs[i].id();
  return bvh;
}

}  // namespace bvhlab
