// sah-binned's private declarations: the reference it moves, its work items, a split, the bin
// mapping, a bin, and the per-node stepper whose parts live in builders/sah_binned*.cpp (the driver
// and the leaf/split decision in sah_binned.cpp, tiny nodes in sah_binned_small.cpp, binning in
// sah_binned_bins.cpp, the three-axis SIMD sweep in sah_binned_lanes.hpp, the in-place partition in
// sah_binned_partition.cpp). Private to those files.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "builders/build_util.hpp"
#include "builders/builder.hpp"
#include "builders/sah_binned_f4.hpp"

namespace bvhlab::binned {

constexpr uint32_t kMaxBins = 256;
static_assert(kMaxBins == kMaxBuildBins, "reviewBuildOptions (builders/registry.cpp) validates --bins against kMaxBuildBins");  // bin indices are stored in one byte

// The reference the builder moves: box corners and centroid as F4 (lane 3: +inf in `lo`, so that
// binning's min leaves a bin's count there alone; 0 elsewhere), input index.
struct Ref {
  F4 lo, hi, centroid;
  uint32_t id() const { return hi.lane3(); }
};

// Work item: a node whose box is set, its reference range and the bounds of its centroids.
struct Task {
  uint32_t node, begin, end;
  Box4 centroids;
};

struct Split {
  int axis = -1;            // -1: no SAH split (all centroids in one bin on every axis)
  uint32_t bin = 0;         // left side = bins 0..bin (pairs: 1 when the two are in the wrong order)
  uint32_t leftCount = 0;   // references on the left side
  double cost = kInf;       // Ci * (A_L N_L + A_R N_R), without the node's own traversal term
  Box4 left, right;
};

// Maps centroids to bins over [origin, origin + extent): bin = min((c - origin) * scale, bins - 1),
// truncated. An axis whose extent is zero (or so small that bins / extent overflows) cannot be binned
// and is skipped (its scale is 0: everything lands in bin 0); that is the zero-extent guard. Inputs
// are finite and c >= origin, so the value is finite and in [0, bins - 1] before truncation. The bin
// of a reference is computed once, by binsOf(), and stored: binning and partitioning always agree.
// binsOf() is monotonic in the centroid, so a node's highest bin on an axis is the bin of its
// centroid bounds' upper corner and its lowest is bin 0.
struct BinMapping {
  F4 origin, scale, last;
  std::array<bool, 3> usable;

  BinMapping(const Box4& centroids, uint32_t bins) : origin(centroids.lo) {
    const glm::vec3 extent = vec3(centroids.hi - centroids.lo);
    const F4 s4 = F4::splat(float(bins)) / F4::set(extent.x, extent.y, extent.z, 1.0f);  // == float(bins) / extent[a]
    float s[3];
    for (int a = 0; a < 3; ++a) {
      s[a] = s4[a];
      usable[a] = extent[a] > 0.0f && s[a] < kInf;  // s is never NaN: bins > 0, extent >= 0
      if (!usable[a]) s[a] = 0.0f;
    }
    scale = F4::set(s[0], s[1], s[2], 0.0f);
    last = F4::splat(float(bins - 1));
  }
  bool anyUsable() const { return usable[0] || usable[1] || usable[2]; }
  void binsOf(F4 centroid, int32_t* bin) const { min((centroid - origin) * scale, last).truncate(bin); }
};

// A bin: its box, and its reference count in lane 3 of `lo` (an integer: binning's min against a
// reference's +inf leaves it alone, and one integer add counts the reference). Bin sets are arrays of
// 3 x bins of these, axis-major.
struct Bin {
  F4 lo = F4::withLane3(kInf, kInf, kInf, 0), hi = F4::splat(-kInf);
  uint32_t count() const { return lo.lane3(); }
};

class BinnedStepper {
 public:
  BinnedStepper(Ref* refs, const BuildOptions& options, uint32_t bins)
      : refs_(refs), options_(options), bins_(bins), sides_(1) {
    for (auto& set : sets_) set.resize(3 * size_t(bins));
  }

  // Leaf, or a split of the task's range (partitioned in place) with the children's boxes.
  detail::NodeStep<Task> step(const Task& task, const Aabb& box);

 private:
  void reserveScratch(uint32_t n);
  // The split finder for the node's size (2, 3..kTinyMax, fewer references than bins, the rest).
  Split findSplit(const Task& task, const BinMapping& mapping);

  // ---- small nodes (sah_binned_small.cpp)
  // 3..kTinyMax references: per axis, the references ordered by (bin, position) and swept in that
  // order, a boundary wherever the bin changes: the same sets, counts and float half areas as a
  // sweep over the occupied bins, so the same costs and the same first minimum. Leaves the chosen
  // left side as bits in sides_[0] (for partitionBySides).
  Split tinySplit(const Task& task, const BinMapping& mapping);
  // 3 or 4 references: the box and float half area of every subset, once (each a union of its
  // references' boxes, so the same bits as the bins' unions), then per axis the references sorted by
  // (bin, position) with a sorting network and the boundaries where the bin changes looked up.
  template <uint32_t N>
  Split subsetSplit(const Task& task, const BinMapping& mapping);
  // 5..kTinyMax references (at most M): keys bin << 5 | position, padded to M with keys that sort
  // last, sorted per axis, the first n positions swept.
  template <uint32_t M>
  Split tinySplit(const Task& task, const BinMapping& mapping);
  // Two references: on every usable axis their centroids differ, the lower one lands in bin 0 and the
  // upper one in bin >= 1 ((c - lo) * (bins / (c - lo)) rounds to about bins), so every usable axis
  // offers the one split {lower} | {upper} at the same cost (the sum of two half areas, whatever the
  // order): the first usable axis is the binned builder's choice.
  Split splitPair(const Task& task, const BinMapping& mapping);
  uint32_t partitionPair(const Task& task, const Split& split);

  // ---- binning (sah_binned_bins.cpp)
  // Bins the node's references first, first + stride, ... into bin set `set`, stores their bins (a
  // byte per axis, by position in the node) and, if asked, marks the occupied bins. Written so that
  // nothing is re-read after a store (the box stores go through __m128, which may alias anything).
  template <bool kOccupancy>
  void binRefs(const Task& task, const BinMapping& mapping, uint32_t first, uint32_t stride, int set,
               uint64_t (*occupancy)[kMaxBins / 64]);
  // Nodes with at least as many references as bins: bins 0..last of every axis (last from the upper
  // corner of the centroid bounds), swept for all three axes at once. Large nodes bin into two sets
  // (even and odd references: consecutive references of a mesh often share a bin, and one set would
  // chain their updates through memory), merged on the way into the sweep.
  Split findSplitLarge(const Task& task, const BinMapping& mapping);
  // Nodes with fewer references than bins: one pass bins them (one bin set) and marks the occupied
  // bins; the sweep visits the occupied bins only, in order.
  Split findSplitSmall(const Task& task, const BinMapping& mapping);

  // ---- the sweeps: three axes in SIMD lanes (sah_binned_lanes.hpp), or one axis at a time (portable)
#if defined(BVHLAB_BINNED_SSE)
  // One position of the three axes' sweeps, axis a in lane a (lane 3 unused, zero): the bin (or
  // reference) there, transposed, its count, whether no boundary follows it, and the sweeps' results.
  struct Lanes {
    __m128 lx, ly, lz, hx, hy, hz;
    __m128i count, noCut;
    __m128 leftArea;
    __m128i leftCount;
  };

  // The SAH over boundaries after positions 0..m - 2 of the three axes at once, each position given
  // by gather(j, lanes) (position 0 holds references on every axis). A boundary is a candidate on an
  // axis when the right side holds references and gather did not set noCut there. Per axis the first
  // minimum, then the first axis with the lowest one, strictly below best.cost: what three scalar
  // sweeps over the occupied bins would find (a boundary after an empty bin costs what the one before
  // it costs). Float half areas of the unions, Ci * (A_L * N_L + A_R * N_R) in double. On success
  // sets best's axis, cost, left count and boxes, and `cut`: the last position on the left.
  template <class Gather>
  bool sweepLanes(uint32_t m, Gather gather, Split& best, uint32_t& cut);
  template <bool kUnitCi, bool kSmallCounts>
  void suffixSweep(uint32_t m, double ci, __m128d& best01, __m128d& best23, __m128i& at01, __m128i& at23);
  // The same sweep with the four lanes' double costs in one AVX register (the same operations per
  // lane, so the same bits); taken when the CPU has AVX2 (__builtin_cpu_supports).
  template <bool kUnitCi, bool kSmallCounts>
  __attribute__((target("avx2"))) void suffixSweepAvx2(uint32_t m, double ci, double* lowest, int64_t* at);
  // Half areas of the boxes in lanes (corners given per coordinate): (x y + y z) + z x, per lane.
  static __m128 halfAreas(__m128 lx, __m128 ly, __m128 lz, __m128 hx, __m128 hy, __m128 hz);
  std::array<Lanes, kMaxBins> lanes_;
#else
  // SAH over the boundaries between bins index(0), ..., index(m - 1) of `axis` (the first and the
  // last occupied, empty ones in between allowed). Replaces `best` when a boundary here costs strictly
  // less, so the first minimum over axes 0, 1, 2 and bins in order wins. Costs as the textbook sweep
  // computes them: float half areas of the unions, Ci * (A_L * N_L + A_R * N_R) in double.
  template <class Index>
  void sweep(const Bin* bins, uint32_t m, Index index, int axis, Split& best);
  std::array<Bin, kMaxBins> binsScratch_;
  std::array<float, kMaxBins> leftArea_, rightArea_;
  std::array<uint32_t, kMaxBins> leftN_, rightN_;
#endif

  // ---- partition (sah_binned_partition.cpp)
  // In-place partition by the stored bin on the split axis. The references in [begin, mid) that go
  // right are swapped with those in [mid, end) that go left, the first of the former (from the left)
  // with the last of the latter (from the right), as a two-sided scan pairs them; mid is known from
  // the sweep's count. Classification: one bit per reference, 16 per instruction.
  uint32_t partition(const Task& task, const Split& split);
  // The in-place partition proper, from the sides in sides_ (bit k: reference begin + k goes left;
  // nLeft of them).
  uint32_t partitionBySides(const Task& task, uint32_t nLeft);

  // ---- the rest of the node step (sah_binned.cpp)
  void centroidBounds(uint32_t begin, uint32_t end, Box4& centroids) const;
  // The n/2 smallest references by (centroid on `axis`, input index) first: a total order, so the
  // split does not depend on where equal centroids happen to sit.
  void medianSplit(const Task& task, int axis);
  void bounds(uint32_t begin, uint32_t end, Box4& box, Box4& centroids) const;

  static constexpr uint32_t kTinyMax = 32;
  static constexpr uint32_t kTwoSetsMin = 1024;  // nodes this large bin into two sets
  static constexpr uint32_t kScratchPad = 64;  // the classification reads whole 64-byte blocks
  Ref* refs_;
  const BuildOptions& options_;
  uint32_t bins_;
  std::array<std::vector<Bin>, 2> sets_;  // bin sets: 3 x bins each; all empty between nodes
  std::unique_ptr<detail::ScratchArray<uint32_t>> binOf_;  // the current node's references' bins, a byte per axis
  std::vector<uint64_t> sides_;            // partition: one bit per reference
  std::array<std::array<uint8_t, kMaxBins>, 3> occupied_;  // small nodes: each axis's occupied bins, in order
};

}  // namespace bvhlab::binned
