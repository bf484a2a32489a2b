// Binned SAH builder (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies"):
// at each node the centroids are dropped into equal-width bins on each axis in one pass, the SAH is
// evaluated at every bin boundary, and the references are partitioned in place. A node's children
// get their boxes from the bins and their centroid bounds from the partition pass, so no node
// rescans its primitives, and nothing is allocated per node. Threads: build_util.hpp's driver (the
// tree does not depend on the thread count).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

// BVHLAB_NO_SIMD forces the portable path (to check that it builds the same trees).
#if defined(__SSE2__) && !defined(BVHLAB_NO_SIMD)
#define BVHLAB_BINNED_SSE 1
#include <emmintrin.h>
#endif

#include "builders/build_util.hpp"

namespace bvhlab {

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
constexpr uint32_t kMaxBins = 256;
constexpr float kInf = std::numeric_limits<float>::infinity();

// Four floats with the handful of operations binning needs: SSE where the target has it, a plain
// loop elsewhere. (GCC does not vectorise the loop form itself: std::min/max on floats are not
// min/max instructions to it without -ffinite-math-only.) No NaN ever reaches these: inputs are
// validated finite, and lane 3 holds 0 or +-inf padding that no decision reads.
struct alignas(16) F4 {
#if defined(BVHLAB_BINNED_SSE)
  __m128 v;
  static F4 set(float x, float y, float z, float w) { return {_mm_setr_ps(x, y, z, w)}; }
  void store(float* p) const { _mm_store_ps(p, v); }
  friend F4 min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
  friend F4 max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
  friend F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
  friend F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
  // Truncation toward zero of values in [0, 2^31).
  void truncate(int32_t* out) const { _mm_store_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(v)); }
#else
  float v[4];
  static F4 set(float x, float y, float z, float w) { return {{x, y, z, w}}; }
  void store(float* p) const { std::memcpy(p, v, sizeof v); }
  template <class Op>
  static F4 map(F4 a, F4 b, Op op) { return {{op(a.v[0], b.v[0]), op(a.v[1], b.v[1]), op(a.v[2], b.v[2]), op(a.v[3], b.v[3])}}; }
  friend F4 min(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x < y ? x : y; }); }
  friend F4 max(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x > y ? x : y; }); }
  friend F4 operator-(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x - y; }); }
  friend F4 operator*(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x * y; }); }
  void truncate(int32_t* out) const { for (int k = 0; k < 4; ++k) out[k] = int32_t(v[k]); }
#endif
  float operator[](int k) const {
    alignas(16) float f[4];
    store(f);
    return f[k];
  }
};

F4 point(const glm::vec3& p) { return F4::set(p.x, p.y, p.z, 0.0f); }
glm::vec3 vec3(F4 a) {
  alignas(16) float f[4];
  a.store(f);
  return {f[0], f[1], f[2]};
}

// A box as two F4 corners; starts empty (+inf/-inf).
struct Box4 {
  F4 lo = F4::set(kInf, kInf, kInf, kInf);
  F4 hi = F4::set(-kInf, -kInf, -kInf, -kInf);

  void grow(F4 l, F4 h) { lo = min(lo, l), hi = max(hi, h); }
  void grow(const Box4& b) { grow(b.lo, b.hi); }
  float halfArea() const {  // only on non-empty boxes
    const glm::vec3 e = vec3(hi - lo);
    return e.x * e.y + e.y * e.z + e.z * e.x;
  }
  Aabb aabb() const { return {vec3(lo), vec3(hi)}; }
};

// The reference the builder moves: box corners and centroid as F4 (lane 3 is 0), input index.
struct Ref {
  F4 lo, hi, centroid;
  uint32_t id;
};

// Work item: a node whose box is set, its reference range and the bounds of its centroids.
struct Task {
  uint32_t node, begin, end;
  Box4 centroids;
};

struct Split {
  int axis = -1;     // -1: no SAH split (all centroids in one bin on every axis)
  uint32_t bin = 0;  // left side = bins 0..bin
  double cost = 0;   // Ci * (A_L N_L + A_R N_R), without the node's own traversal term
  Box4 left, right;
};

// Maps centroids to bins over [origin, origin + extent): bin = min((c - origin) * scale, bins - 1),
// truncated. An axis whose extent is zero (or so small that bins / extent overflows) cannot be binned
// and is skipped (its scale is 0: everything lands in bin 0); that is the zero-extent guard. Inputs
// are finite and c >= origin, so the value is finite and in [0, bins - 1] before truncation. Binning
// and partitioning both go through binsOf(), so they always agree on a reference's bin.
struct BinMapping {
  F4 origin, scale, last;
  std::array<bool, 3> usable;

  BinMapping(const Box4& centroids, uint32_t bins) : origin(centroids.lo) {
    const glm::vec3 extent = vec3(centroids.hi - centroids.lo);
    float s[3];
    for (int a = 0; a < 3; ++a) {
      s[a] = float(bins) / extent[a];
      usable[a] = extent[a] > 0.0f && std::isfinite(s[a]);
      if (!usable[a]) s[a] = 0.0f;
    }
    scale = F4::set(s[0], s[1], s[2], 0.0f);
    const float lastBin = float(bins - 1);
    last = F4::set(lastBin, lastBin, lastBin, lastBin);
  }
  bool anyUsable() const { return usable[0] || usable[1] || usable[2]; }
  void binsOf(F4 centroid, int32_t* bin) const { min((centroid - origin) * scale, last).truncate(bin); }
};

class BinnedStepper {
 public:
  BinnedStepper(std::vector<Ref>& refs, const BuildOptions& options, uint32_t bins)
      : refs_(refs), options_(options), bins_(bins) {
    for (auto& counts : counts_) counts.fill(0);
  }

  // Leaf, or a split of the task's range (partitioned in place) with the children's boxes.
  detail::NodeStep<Task> step(const Task& task, const Aabb& box) {
    detail::NodeStep<Task> step;
    const uint32_t n = task.end - task.begin;
    if (n == 1) return step;

    const BinMapping mapping(task.centroids, bins_);
    Split split;
    if (mapping.anyUsable()) split = findSplit(task, mapping);

    const CostModel& c = options_.cost;
    const double area = box.halfArea();
    const bool splitWins = split.axis >= 0 && c.traversalCost * area + split.cost < c.intersectionCost * area * n;
    if (!splitWins && n <= options_.maxLeafSize) return step;

    uint32_t mid;
    Box4 leftBox, rightBox, leftCentroids, rightCentroids;
    if (splitWins) {
      mid = partition(task, mapping, split, leftCentroids, rightCentroids);
      leftBox = split.left;
      rightBox = split.right;
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

 private:
  // One pass over the references fills the bins of all three axes and marks the occupied ones; then
  // one sweep per usable axis over its occupied bins only (a boundary between empty bins repeats its
  // neighbour's split, and near the leaves most bins are empty). Bins are left cleared for the next
  // node, so nothing here costs O(bins) per node except the occupancy words.
  Split findSplit(const Task& task, const BinMapping& mapping) {
    alignas(16) int32_t bin[4];
    for (uint32_t i = task.begin; i < task.end; ++i) {
      const Ref& r = refs_[i];
      mapping.binsOf(r.centroid, bin);
      for (int a = 0; a < 3; ++a) {
        boxes_[a][bin[a]].grow(r.lo, r.hi);
        ++counts_[a][bin[a]];
        occupancy_[a][bin[a] >> 6] |= uint64_t(1) << (bin[a] & 63);
      }
    }
    const double ci = options_.cost.intersectionCost;
    Split best;
    for (int a = 0; a < 3; ++a) {
      Box4* boxes = boxes_[a].data();
      uint32_t* counts = counts_[a].data();
      uint32_t used = 0;  // occupied bins, in order, in occupied_[0, used)
      for (uint32_t w = 0; w < (bins_ + 63) / 64; ++w) {
        for (uint64_t bits = occupancy_[a][w]; bits; bits &= bits - 1)
          occupied_[used++] = 64 * w + uint32_t(std::countr_zero(bits));
        occupancy_[a][w] = 0;
      }
      if (mapping.usable[a]) {
        // Right sweep: SAH term of the right side starting at occupied bin k.
        Box4 right;
        uint32_t rightCount = 0;
        for (uint32_t k = used - 1; k > 0; --k) {
          right.grow(boxes[occupied_[k]]);
          rightCount += counts[occupied_[k]];
          rightCost_[k] = double(right.halfArea()) * rightCount;
        }
        Box4 left;
        uint32_t leftCount = 0, bestK = used;
        for (uint32_t k = 0; k + 1 < used; ++k) {
          left.grow(boxes[occupied_[k]]);
          leftCount += counts[occupied_[k]];
          const double cost = ci * (double(left.halfArea()) * leftCount + rightCost_[k + 1]);
          if (best.axis < 0 || cost < best.cost) best.axis = a, best.bin = occupied_[k], best.cost = cost, bestK = k;
        }
        if (bestK < used) {  // this axis holds the best split so far: keep its children's boxes
          best.left = best.right = Box4{};
          for (uint32_t k = 0; k < used; ++k) (k <= bestK ? best.left : best.right).grow(boxes[occupied_[k]]);
        }
      }
      for (uint32_t k = 0; k < used; ++k) {
        boxes[occupied_[k]] = Box4{};
        counts[occupied_[k]] = 0;
      }
    }
    return best;
  }

  // In-place two-sided partition by bin; collects the centroid bounds of both sides on the way.
  uint32_t partition(const Task& task, const BinMapping& mapping, const Split& split, Box4& leftCentroids,
                     Box4& rightCentroids) {
    alignas(16) int32_t bin[4];
    const int axis = split.axis;
    const int32_t last = int32_t(split.bin);
    auto isLeft = [&](const Ref& r) {
      mapping.binsOf(r.centroid, bin);
      return bin[axis] <= last;
    };
    uint32_t i = task.begin, j = task.end;
    while (true) {
      for (; i < j && isLeft(refs_[i]); ++i) leftCentroids.grow(refs_[i].centroid, refs_[i].centroid);
      for (; i < j && !isLeft(refs_[j - 1]); --j) rightCentroids.grow(refs_[j - 1].centroid, refs_[j - 1].centroid);
      if (i >= j) break;
      std::swap(refs_[i], refs_[j - 1]);
    }
    return i;
  }

  // The n/2 smallest references by (centroid on `axis`, input index) first: a total order, so the
  // split does not depend on where equal centroids happen to sit.
  void medianSplit(const Task& task, int axis) {
    const uint32_t n = task.end - task.begin;
    auto first = refs_.begin() + task.begin;
    std::nth_element(first, first + n / 2, first + n, [axis](const Ref& a, const Ref& b) {
      const float ca = a.centroid[axis], cb = b.centroid[axis];
      return ca < cb || (ca == cb && a.id < b.id);
    });
  }

  void bounds(uint32_t begin, uint32_t end, Box4& box, Box4& centroids) const {
    for (uint32_t i = begin; i < end; ++i) {
      box.grow(refs_[i].lo, refs_[i].hi);
      centroids.grow(refs_[i].centroid, refs_[i].centroid);
    }
  }

  std::vector<Ref>& refs_;
  const BuildOptions& options_;
  uint32_t bins_;
  std::array<std::array<Box4, kMaxBins>, 3> boxes_;      // all empty between nodes
  std::array<std::array<uint32_t, kMaxBins>, 3> counts_;  // all zero between nodes
  static constexpr uint32_t kOccupancyWords = kMaxBins / 64;
  std::array<std::array<uint64_t, kOccupancyWords>, 3> occupancy_{};  // all zero between nodes
  std::array<uint32_t, kMaxBins> occupied_;
  std::array<double, kMaxBins> rightCost_;
};

}  // namespace

Bvh buildSahBinnedBvh(const BuildInput& input, const BuildOptions& options) {
  const uint32_t bins = options.bins ? options.bins : kDefaultBins;
  if (bins < 2 || bins > kMaxBins)
    throw std::invalid_argument("sah-binned: bins = " + std::to_string(bins) + " is outside 2.." +
                                std::to_string(kMaxBins));
  const uint32_t n = uint32_t(input.boxes.size());
  std::vector<Ref> refs(n);
  Box4 box, centroids;
  for (uint32_t i = 0; i < n; ++i) {
    Ref& r = refs[i];
    r = {point(input.boxes[i].min), point(input.boxes[i].max), point(input.centroids[i]), i};
    box.grow(r.lo, r.hi);
    centroids.grow(r.centroid, r.centroid);
  }

  Bvh bvh;
  bvh.nodes = detail::buildTopDown(box.aabb(), Task{0, 0, n, centroids}, detail::resolveThreads(options.threads),
                                   [&] { return BinnedStepper(refs, options, bins); });
  bvh.primIndices.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.primIndices[i] = refs[i].id;
  return bvh;
}

}  // namespace bvhlab
