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
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

// BVHLAB_NO_SIMD forces the portable path (to check that it builds the same trees).
#if defined(__SSE2__) && !defined(BVHLAB_NO_SIMD)
#define BVHLAB_BINNED_SSE 1
#include <emmintrin.h>
#endif

#include "builders/build_util.hpp"
#include "builders/builder.hpp"

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
static_assert(kMaxBins == kMaxBuildBins, "reviewBuildOptions (builders/registry.cpp) validates --bins against kMaxBuildBins");  // bin indices are stored in one byte
constexpr float kInf = std::numeric_limits<float>::infinity();

// Four floats with the handful of operations binning needs: SSE where the target has it, a plain
// loop elsewhere. (GCC does not vectorise the loop form itself: std::min/max on floats are not
// min/max instructions to it without -ffinite-math-only.) Lanes 0..2 are x, y, z, validated finite;
// lane 3 is bookkeeping (an index or a count as an integer, or +-inf / 0 padding) that reaches no
// arithmetic whose result is read and decides nothing.
struct alignas(16) F4 {
#if defined(BVHLAB_BINNED_SSE)
  __m128 v;
  static F4 set(float x, float y, float z, float w) { return {_mm_setr_ps(x, y, z, w)}; }
  static F4 splat(float x) { return {_mm_set1_ps(x)}; }
  void store(float* p) const { _mm_store_ps(p, v); }
  friend F4 min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
  friend F4 max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
  friend F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
  friend F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
  friend F4 operator/(F4 a, F4 b) { return {_mm_div_ps(a.v, b.v)}; }
  // Truncation toward zero of values in [0, 2^31).
  void truncate(int32_t* out) const { _mm_store_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(v)); }
  // Lane 3 as an integer (a bin's count), and the same vector with it incremented or zeroed.
  uint32_t lane3() const { return uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(_mm_castps_si128(v), 0xff))); }
  F4 plusOneIn3() const { return {_mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(v), _mm_setr_epi32(0, 0, 0, 1)))}; }
  F4 xyz() const { return {_mm_and_ps(v, _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)))}; }
  static F4 withLane3(float x, float y, float z, uint32_t w) {
    return {_mm_castsi128_ps(_mm_setr_epi32(std::bit_cast<int32_t>(x), std::bit_cast<int32_t>(y), std::bit_cast<int32_t>(z), int32_t(w)))};
  }
#else
  float v[4];
  static F4 set(float x, float y, float z, float w) { return {{x, y, z, w}}; }
  static F4 splat(float x) { return {{x, x, x, x}}; }
  void store(float* p) const { std::memcpy(p, v, sizeof v); }
  template <class Op>
  static F4 map(F4 a, F4 b, Op op) { return {{op(a.v[0], b.v[0]), op(a.v[1], b.v[1]), op(a.v[2], b.v[2]), op(a.v[3], b.v[3])}}; }
  friend F4 min(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x < y ? x : y; }); }
  friend F4 max(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x > y ? x : y; }); }
  friend F4 operator-(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x - y; }); }
  friend F4 operator*(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x * y; }); }
  friend F4 operator/(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x / y; }); }
  void truncate(int32_t* out) const { for (int k = 0; k < 4; ++k) out[k] = int32_t(v[k]); }
  uint32_t lane3() const { return std::bit_cast<uint32_t>(v[3]); }
  F4 plusOneIn3() const { F4 r = *this; r.v[3] = std::bit_cast<float>(lane3() + 1); return r; }
  F4 xyz() const { return {{v[0], v[1], v[2], 0.0f}}; }
  static F4 withLane3(float x, float y, float z, uint32_t w) { return {{x, y, z, std::bit_cast<float>(w)}}; }
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

// Half the surface area of a non-empty box, e.x * e.y + e.y * e.z + e.z * e.x in float and in that
// order (the products are exact-order-independent; the two sums are done left to right): the same
// bits as Aabb::halfArea, whatever the path.
inline float halfArea(F4 lo, F4 hi) {
#if defined(BVHLAB_BINNED_SSE)
  const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));  // lane 3 may hold anything
  const __m128 e = _mm_sub_ps(_mm_and_ps(hi.v, xyz), _mm_and_ps(lo.v, xyz));
  const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // xy, yz, zx, ww
  const __m128 s = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(1, 1, 1, 1)));  // xy + yz
  return _mm_cvtss_f32(_mm_add_ss(s, _mm_movehl_ps(p, p)));                        // + zx
#else
  const glm::vec3 e = vec3(hi - lo);
  return e.x * e.y + e.y * e.z + e.z * e.x;
#endif
}

// Branch-free choices (the compiler keeps these as masks: the conditions are data, not control).
inline uint32_t select(bool c, uint32_t a, uint32_t b) {
  const uint32_t m = 0u - uint32_t(c);
  return (a & m) | (b & ~m);
}
inline double select(bool c, double a, double b) {
  const uint64_t m = 0 - uint64_t(c);
  return std::bit_cast<double>((std::bit_cast<uint64_t>(a) & m) | (std::bit_cast<uint64_t>(b) & ~m));
}

// Batcher's odd-even merge sort of N elements: the network for the next power of two, less the
// compare-exchanges that reach past N (padding that sorts last would not move).
template <uint32_t N, class F>
constexpr void forEachCompareExchange(F f) {
  constexpr uint32_t P = std::bit_ceil(N);
  for (uint32_t p = 1; p < P; p <<= 1)
    for (uint32_t k = p; k >= 1; k >>= 1)
      for (uint32_t j = k % p; j + k < P; j += 2 * k)
        for (uint32_t i = 0; i < std::min(k, P - j - k); ++i)
          if ((i + j) / (2 * p) == (i + j + k) / (2 * p) && i + j + k < N) f(i + j, i + j + k);
}
template <uint32_t N>
constexpr auto makeSortingNetwork() {
  constexpr uint32_t size = [] {
    uint32_t count = 0;
    forEachCompareExchange<N>([&](uint32_t, uint32_t) { ++count; });
    return count;
  }();
  std::array<std::array<uint8_t, 2>, size> network{};
  uint32_t next = 0;
  forEachCompareExchange<N>([&](uint32_t a, uint32_t b) { network[next++] = {uint8_t(a), uint8_t(b)}; });
  return network;
}
template <uint32_t N>
constexpr auto kSortingNetwork = makeSortingNetwork<N>();

// A box as two F4 corners; starts empty (+inf/-inf).
struct Box4 {
  F4 lo = F4::splat(kInf);
  F4 hi = F4::splat(-kInf);

  void grow(F4 l, F4 h) { lo = min(lo, l), hi = max(hi, h); }
  void grow(const Box4& b) { grow(b.lo, b.hi); }
  float halfArea() const { return bvhlab::halfArea(lo, hi); }  // only on non-empty boxes
  Aabb aabb() const { return {vec3(lo), vec3(hi)}; }
};

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
  detail::NodeStep<Task> step(const Task& task, const Aabb& box) {
    detail::NodeStep<Task> step;
    const uint32_t n = task.end - task.begin;
    if (n == 1) return step;

    const BinMapping mapping(task.centroids, bins_);
    Split split;
    if (mapping.anyUsable()) {
      if (n == 2) {
        split = splitPair(task, mapping);
      } else if (n <= kTinyMax) {
        split = tinySplit(task, mapping);
      } else {
        reserveScratch(n);
        split = n < bins_ ? findSplitSmall(task, mapping) : findSplitLarge(task, mapping);
      }
    }

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

 private:
  void reserveScratch(uint32_t n) {
    if (binOf_ && binOf_->size() >= n + kScratchPad) return;
    binOf_ = std::make_unique<detail::ScratchArray<uint32_t>>(n + kScratchPad);
    std::fill_n(binOf_->data() + n, kScratchPad, 0u);  // the classification reads past the references
    sides_.resize(n / 64 + 2);
  }

  // 3..kTinyMax references: per axis, the references ordered by (bin, position) and swept in that
  // order, a boundary wherever the bin changes: the same sets, counts and float half areas as a
  // sweep over the occupied bins, so the same costs and the same first minimum. Leaves the chosen
  // left side as bits in sides_[0] (for partitionBySides).
  Split tinySplit(const Task& task, const BinMapping& mapping) {
    const uint32_t n = task.end - task.begin;
    if (n == 3) return subsetSplit<3>(task, mapping);
    if (n == 4) return subsetSplit<4>(task, mapping);
    if (n == 5) return tinySplit<5>(task, mapping);
    if (n == 6) return tinySplit<6>(task, mapping);
    if (n == 7) return tinySplit<7>(task, mapping);
    if (n == 8) return tinySplit<8>(task, mapping);
    if (n <= 12) return tinySplit<12>(task, mapping);
    if (n <= 16) return tinySplit<16>(task, mapping);
    if (n <= 24) return tinySplit<24>(task, mapping);
    return tinySplit<32>(task, mapping);
  }
  // 3 or 4 references: the box and float half area of every subset, once (each a union of its
  // references' boxes, so the same bits as the bins' unions), then per axis the references sorted by
  // (bin, position) with a sorting network and the boundaries where the bin changes looked up.
  template <uint32_t N>
  Split subsetSplit(const Task& task, const BinMapping& mapping) {
    static_assert(N == 3 || N == 4);
    constexpr uint32_t kAll = (1u << N) - 1;
    const Ref* const refs = refs_ + task.begin;
    Box4 box[kAll];  // box[0] is empty
    float area[kAll];
#pragma GCC unroll 16
    for (uint32_t mask = 1; mask < kAll; ++mask) {
      const uint32_t i = uint32_t(std::countr_zero(mask));
      box[mask] = box[mask & (mask - 1)];
      box[mask].grow(refs[i].lo, refs[i].hi);
      area[mask] = box[mask].halfArea();
    }
    alignas(16) int32_t bin[N][4];
    for (uint32_t k = 0; k < N; ++k) mapping.binsOf(refs[k].centroid, bin[k]);
    const double ci = options_.cost.intersectionCost;
    Split best;
    uint32_t bestLeft = 0;
    for (int a = 0; a < 3; ++a) {
      if (!mapping.usable[a]) continue;
      uint32_t key[N];
      for (uint32_t k = 0; k < N; ++k) key[k] = uint32_t(bin[k][a]) << 4 | k;
      auto order = [&key](uint32_t i, uint32_t j) {  // compare-exchange without a branch
        const uint32_t swap = (key[i] ^ key[j]) & (0u - uint32_t(key[j] < key[i]));
        key[i] ^= swap, key[j] ^= swap;
      };
      if constexpr (N == 3) {
        order(0, 1), order(1, 2), order(0, 1);
      } else {
        order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
      }
      double lowest = best.cost;
      uint32_t left = 0, leftSide = 0, leftCount = 0;
      for (uint32_t t = 0; t + 1 < N; ++t) {
        left |= 1u << (key[t] & 15);
        const double cost = ci * (double(area[left]) * (t + 1) + double(area[kAll ^ left]) * (N - 1 - t));
        const bool better = ((key[t] >> 4) != (key[t + 1] >> 4)) & (cost < lowest);
        lowest = select(better, cost, lowest);
        leftSide = select(better, left, leftSide);
        leftCount = select(better, t + 1, leftCount);
      }
      if (leftSide) best.axis = a, best.cost = lowest, best.leftCount = leftCount, bestLeft = leftSide;
    }
    if (best.axis >= 0) best.left = box[bestLeft], best.right = box[kAll ^ bestLeft];
    sides_[0] = bestLeft;
    return best;
  }

  // 5..kTinyMax references (at most M): keys bin << 5 | position, padded to M with keys that sort
  // last, sorted per axis, the first n positions swept.
  template <uint32_t M>
  Split tinySplit(const Task& task, const BinMapping& mapping) {
    static_assert(M <= kTinyMax && kTinyMax <= 32);
    constexpr int kShift = 5;  // key = bin << kShift | position
    const uint32_t n = task.end - task.begin;
    const Ref* const refs = refs_ + task.begin;
    Split best;
#if defined(BVHLAB_BINNED_SSE)
    // 16-bit lanes (keys < 2^13), one per axis: the network sorts all axes at once.
    __m128i key[M];
    for (uint32_t k = 0; k < n; ++k) {
      const __m128i b = _mm_cvttps_epi32(_mm_min_ps(_mm_mul_ps(_mm_sub_ps(refs[k].centroid.v, mapping.origin.v), mapping.scale.v), mapping.last.v));
      const __m128i b16 = _mm_packs_epi32(b, b);  // bins < 256
      key[k] = _mm_or_si128(_mm_slli_epi16(b16, kShift), _mm_set1_epi16(int16_t(k)));
    }
    for (uint32_t k = n; k < M; ++k) key[k] = _mm_set1_epi16(0x7fff);
#pragma GCC unroll 256
    for (const auto& [i, j] : kSortingNetwork<M>) {
      const __m128i lo = _mm_min_epi16(key[i], key[j]);
      key[j] = _mm_max_epi16(key[i], key[j]);
      key[i] = lo;
    }
    const __m128i one = _mm_setr_epi32(1, 1, 1, 0);
    uint32_t cut;
    const bool found = sweepLanes(n, [&](uint32_t j, Lanes& l) {
      const __m128i k = key[j];
      const Ref& r0 = refs[_mm_extract_epi16(k, 0) & 31];
      const Ref& r1 = refs[_mm_extract_epi16(k, 1) & 31];
      const Ref& r2 = refs[_mm_extract_epi16(k, 2) & 31];
      __m128 lo0 = r0.lo.v, lo1 = r1.lo.v, lo2 = r2.lo.v, lw = _mm_setzero_ps();
      __m128 hi0 = r0.hi.v, hi1 = r1.hi.v, hi2 = r2.hi.v, hw = _mm_setzero_ps();
      _MM_TRANSPOSE4_PS(lo0, lo1, lo2, lw);
      _MM_TRANSPOSE4_PS(hi0, hi1, hi2, hw);
      l.lx = lo0, l.ly = lo1, l.lz = lo2, l.hx = hi0, l.hy = hi1, l.hz = hi2, l.count = one;
      if (j + 1 < n) {  // the same bin as the next: no boundary after j (lanes 3..7 never cut)
        const __m128i same = _mm_cmpeq_epi16(_mm_srai_epi16(k, kShift), _mm_srai_epi16(key[j + 1], kShift));
        l.noCut = _mm_unpacklo_epi16(same, same);
      }
    }, best, cut);
    uint64_t sides = 0;
    if (found) {
      alignas(16) int16_t lanes[8];
      for (uint32_t t = 0; t <= cut; ++t) {
        _mm_store_si128(reinterpret_cast<__m128i*>(lanes), key[t]);
        sides |= uint64_t(1) << (lanes[best.axis] & 31);
      }
    }
    sides_[0] = sides;
#else
    alignas(16) int32_t bin[M][4];
    for (uint32_t k = 0; k < n; ++k) mapping.binsOf(refs[k].centroid, bin[k]);
    const double ci = options_.cost.intersectionCost;
    uint64_t bestSides = 0;
    for (int a = 0; a < 3; ++a) {
      if (!mapping.usable[a]) continue;
      int32_t key[M];
      uint32_t order[M];
      for (uint32_t k = 0; k < n; ++k) key[k] = bin[k][a] << kShift | int32_t(k);
      for (uint32_t k = 0; k < n; ++k) {
        uint32_t rank = 0;
        for (uint32_t j = 0; j < n; ++j) rank += key[j] < key[k];
        order[rank] = k;
      }
      float leftArea[M], rightArea[M];
      Box4 left, right;
      for (uint32_t t = 0; t + 1 < n; ++t) {
        const Ref& l = refs[order[t]];
        const Ref& r = refs[order[n - 1 - t]];
        left.grow(l.lo, l.hi), right.grow(r.lo, r.hi);
        leftArea[t] = left.halfArea(), rightArea[n - 1 - t] = right.halfArea();
      }
      double lowest = kInf;
      uint32_t cut = n;
      for (uint32_t t = 0; t + 1 < n; ++t) {
        const double cost = ci * (double(leftArea[t]) * (t + 1) + double(rightArea[t + 1]) * (n - 1 - t));
        const bool better = (key[order[t]] >> kShift) != (key[order[t + 1]] >> kShift) && cost < lowest;
        lowest = better ? cost : lowest;
        cut = better ? t : cut;
      }
      if (cut < n && lowest < best.cost) {
        best.axis = a, best.cost = lowest, best.leftCount = cut + 1;
        bestSides = 0;
        for (uint32_t t = 0; t <= cut; ++t) bestSides |= uint64_t(1) << order[t];
      }
    }
    sides_[0] = bestSides;
    for (uint32_t k = 0; k < n; ++k) (bestSides >> k & 1 ? best.left : best.right).grow(refs[k].lo, refs[k].hi);
#endif
    return best;
  }

  // Two references: on every usable axis their centroids differ, the lower one lands in bin 0 and the
  // upper one in bin >= 1 ((c - lo) * (bins / (c - lo)) rounds to about bins), so every usable axis
  // offers the one split {lower} | {upper} at the same cost (the sum of two half areas, whatever the
  // order): the first usable axis is the binned builder's choice.
  Split splitPair(const Task& task, const BinMapping& mapping) {
    const Ref& r0 = refs_[task.begin];
    const Ref& r1 = refs_[task.begin + 1];
    Split split;
    split.axis = mapping.usable[0] ? 0 : mapping.usable[1] ? 1 : 2;
    const bool swap = r1.centroid[split.axis] < r0.centroid[split.axis];
    const Ref& lower = swap ? r1 : r0;
    const Ref& upper = swap ? r0 : r1;
    split.left = {lower.lo, lower.hi};
    split.right = {upper.lo, upper.hi};
    split.leftCount = 1;
    split.bin = swap;  // partitionPair's hint: the references are in the wrong order
    const double rightCost = double(split.right.halfArea()) * 1u;
    split.cost = double(options_.cost.intersectionCost) * (double(split.left.halfArea()) * 1u + rightCost);
    return split;
  }
  uint32_t partitionPair(const Task& task, const Split& split) {
    if (split.bin) std::swap(refs_[task.begin], refs_[task.begin + 1]);
    return task.begin + 1;
  }

  // Bins the node's references first, first + stride, ... into bin set `set`, stores their bins (a
  // byte per axis, by position in the node) and, if asked, marks the occupied bins. Written so that
  // nothing is re-read after a store (the box stores go through __m128, which may alias anything).
  template <bool kOccupancy>
  void binRefs(const Task& task, const BinMapping& mapping, uint32_t first, uint32_t stride, int set,
               uint64_t (*occupancy)[kMaxBins / 64]) {
    const uint32_t n = task.end - task.begin;
    const Ref* const refs = refs_ + task.begin;
    uint32_t* const binOf = binOf_->data();
    Bin* const base = sets_[set].data();
#if defined(BVHLAB_BINNED_SSE)
    const __m128i offsets = _mm_setr_epi32(0, int32_t(bins_ * sizeof(Bin)), int32_t(2 * bins_ * sizeof(Bin)), 0);
    for (uint32_t k = first; k < n; k += stride) {
      const Ref& r = refs[k];
      const __m128i b = _mm_cvttps_epi32(_mm_min_ps(_mm_mul_ps(_mm_sub_ps(r.centroid.v, mapping.origin.v), mapping.scale.v), mapping.last.v));
      const __m128i packed = _mm_packus_epi16(_mm_packs_epi32(b, b), b);
      binOf[k] = uint32_t(_mm_cvtsi128_si32(packed));
      const __m128i o = _mm_add_epi32(_mm_slli_epi32(b, 5), offsets);  // byte offsets: sizeof(Bin) == 32
      Bin& bx = *reinterpret_cast<Bin*>(reinterpret_cast<char*>(base) + _mm_cvtsi128_si32(o));
      Bin& by = *reinterpret_cast<Bin*>(reinterpret_cast<char*>(base) + _mm_cvtsi128_si32(_mm_shuffle_epi32(o, 1)));
      Bin& bz = *reinterpret_cast<Bin*>(reinterpret_cast<char*>(base) + _mm_cvtsi128_si32(_mm_shuffle_epi32(o, 2)));
#else
    for (uint32_t k = first; k < n; k += stride) {
      const Ref& r = refs[k];
      alignas(16) int32_t b[4];
      mapping.binsOf(r.centroid, b);
      binOf[k] = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16;
      Bin& bx = base[b[0]];
      Bin& by = base[bins_ + b[1]];
      Bin& bz = base[2 * bins_ + b[2]];
#endif
      const F4 lx = min(bx.lo, r.lo).plusOneIn3(), hx = max(bx.hi, r.hi);
      const F4 ly = min(by.lo, r.lo).plusOneIn3(), hy = max(by.hi, r.hi);
      const F4 lz = min(bz.lo, r.lo).plusOneIn3(), hz = max(bz.hi, r.hi);
      bx.lo = lx, bx.hi = hx, by.lo = ly, by.hi = hy, bz.lo = lz, bz.hi = hz;
      if constexpr (kOccupancy) {
        const uint32_t p = binOf[k], x = p & 255, y = (p >> 8) & 255, z = p >> 16;
        if (bins_ <= 64) {  // one word per axis (the default)
          occupancy[0][0] |= uint64_t(1) << x, occupancy[1][0] |= uint64_t(1) << y, occupancy[2][0] |= uint64_t(1) << z;
        } else {
          occupancy[0][x >> 6] |= uint64_t(1) << (x & 63);
          occupancy[1][y >> 6] |= uint64_t(1) << (y & 63);
          occupancy[2][z >> 6] |= uint64_t(1) << (z & 63);
        }
      }
    }
  }

  // Nodes with at least as many references as bins: bins 0..last of every axis (last from the upper
  // corner of the centroid bounds), swept for all three axes at once. Large nodes bin into two sets
  // (even and odd references: consecutive references of a mesh often share a bin, and one set would
  // chain their updates through memory), merged on the way into the sweep.
  Split findSplitLarge(const Task& task, const BinMapping& mapping) {
    const uint32_t n = task.end - task.begin;
    const uint32_t sets = n >= kTwoSetsMin ? 2 : 1;
    for (uint32_t set = 0; set < sets; ++set) binRefs<false>(task, mapping, set, sets, set, nullptr);
    alignas(16) int32_t lastBin[4];
    mapping.binsOf(task.centroids.hi, lastBin);
    const uint32_t m = 1 + uint32_t(std::max({lastBin[0], lastBin[1], lastBin[2]}));
    Split best;
    const Bin* const s0 = sets_[0].data();
#if defined(BVHLAB_BINNED_SSE)
    const uint32_t y = bins_, z = 2 * bins_;
    uint32_t cut;
    if (m >= 2 && sweepLanes(m, [&](uint32_t b, Lanes& l) {
          __m128 lo0 = s0[b].lo.v, lo1 = s0[y + b].lo.v, lo2 = s0[z + b].lo.v, count = _mm_setzero_ps();
          __m128 hi0 = s0[b].hi.v, hi1 = s0[y + b].hi.v, hi2 = s0[z + b].hi.v, hw = _mm_setzero_ps();
          for (uint32_t set = 1; set < sets; ++set) {
            const Bin* const s1 = sets_[set].data();
            const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
            auto merge = [&](__m128 a, __m128 c) {  // min of the corners, sum of the counts
              const __m128i sum = _mm_add_epi32(_mm_castps_si128(a), _mm_castps_si128(c));
              return _mm_or_ps(_mm_and_ps(xyz, _mm_min_ps(a, c)), _mm_andnot_ps(xyz, _mm_castsi128_ps(sum)));
            };
            lo0 = merge(lo0, s1[b].lo.v), lo1 = merge(lo1, s1[y + b].lo.v), lo2 = merge(lo2, s1[z + b].lo.v);
            hi0 = _mm_max_ps(hi0, s1[b].hi.v), hi1 = _mm_max_ps(hi1, s1[y + b].hi.v), hi2 = _mm_max_ps(hi2, s1[z + b].hi.v);
          }
          _MM_TRANSPOSE4_PS(lo0, lo1, lo2, count);  // lo0: the axes' boxes' lower x; count: their counts
          _MM_TRANSPOSE4_PS(hi0, hi1, hi2, hw);
          l.lx = lo0, l.ly = lo1, l.lz = lo2, l.hx = hi0, l.hy = hi1, l.hz = hi2;
          l.count = _mm_castps_si128(count), l.noCut = _mm_setzero_si128();
        }, best, cut))
      best.bin = cut;
#else
    for (int a = 0; a < 3; ++a) {
      Bin* const bins = binsScratch_.data();
      for (uint32_t b = 0; b < m; ++b) {
        bins[b] = s0[a * bins_ + b];
        for (uint32_t set = 1; set < sets; ++set) {
          const Bin& o = sets_[set][a * bins_ + b];
          bins[b].lo = F4::withLane3(std::min(bins[b].lo[0], o.lo[0]), std::min(bins[b].lo[1], o.lo[1]),
                                     std::min(bins[b].lo[2], o.lo[2]), bins[b].count() + o.count());
          bins[b].hi = max(bins[b].hi, o.hi);
        }
      }
      uint32_t last = m - 1;
      while (last > 0 && bins[last].count() == 0) --last;
      if (last > 0) sweep(bins, last + 1, [](uint32_t k) { return k; }, a, best);
    }
#endif
    // Back to empty.
    for (uint32_t set = 0; set < sets; ++set)
      for (int a = 0; a < 3; ++a) std::fill_n(sets_[set].data() + size_t(a) * bins_, lastBin[a] + 1, Bin{});
    return best;
  }

  // Nodes with fewer references than bins: one pass bins them (one bin set) and marks the occupied
  // bins; the sweep visits the occupied bins only, in order.
  Split findSplitSmall(const Task& task, const BinMapping& mapping) {
    uint64_t occupancy[3][kMaxBins / 64] = {};
    binRefs<true>(task, mapping, 0, 1, 0, occupancy);
    Split best;
    Bin* const box = sets_[0].data();
    uint32_t m[3];
    for (int a = 0; a < 3; ++a) {
      uint32_t k = 0;
      for (uint32_t w = 0; w < (bins_ + 63) / 64; ++w)
        for (uint64_t bits = occupancy[a][w]; bits; bits &= bits - 1)
          occupied_[a][k++] = uint8_t(64 * w + uint32_t(std::countr_zero(bits)));
      m[a] = k;
    }
#if defined(BVHLAB_BINNED_SSE)
    // All three axes at once, axis a's j-th occupied bin in lane a (an empty bin past its last).
    const uint32_t most = std::max({m[0], m[1], m[2]});
    const Bin empty;
    const Bin* const bx = box;
    const Bin* const by = box + bins_;
    const Bin* const bz = box + 2 * size_t(bins_);
    uint32_t cut;
    if (most >= 2 && sweepLanes(most, [&](uint32_t j, Lanes& l) {
          const Bin& b0 = j < m[0] ? bx[occupied_[0][j]] : empty;
          const Bin& b1 = j < m[1] ? by[occupied_[1][j]] : empty;
          const Bin& b2 = j < m[2] ? bz[occupied_[2][j]] : empty;
          __m128 lo0 = b0.lo.v, lo1 = b1.lo.v, lo2 = b2.lo.v, count = _mm_setzero_ps();
          __m128 hi0 = b0.hi.v, hi1 = b1.hi.v, hi2 = b2.hi.v, hw = _mm_setzero_ps();
          _MM_TRANSPOSE4_PS(lo0, lo1, lo2, count);
          _MM_TRANSPOSE4_PS(hi0, hi1, hi2, hw);
          l.lx = lo0, l.ly = lo1, l.lz = lo2, l.hx = hi0, l.hy = hi1, l.hz = hi2;
          l.count = _mm_castps_si128(count), l.noCut = _mm_setzero_si128();
        }, best, cut))
      best.bin = occupied_[best.axis][cut];
#else
    for (int a = 0; a < 3; ++a)
      if (m[a] >= 2 && mapping.usable[a])
        sweep(box + size_t(a) * bins_, m[a], [this, a](uint32_t k) { return occupied_[a][k]; }, a, best);
#endif
    for (int a = 0; a < 3; ++a)
      for (uint32_t k = 0; k < m[a]; ++k) box[size_t(a) * bins_ + occupied_[a][k]] = Bin{};
    return best;
  }

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
  bool sweepLanes(uint32_t m, Gather gather, Split& best, uint32_t& cut) {
    __m128 lx = _mm_set1_ps(kInf), ly = lx, lz = lx, hx = _mm_set1_ps(-kInf), hy = hx, hz = hx;
    __m128i count = _mm_setzero_si128();
    for (uint32_t j = 0; j < m; ++j) {  // left to right: prefix unions
      Lanes& l = lanes_[j];
      gather(j, l);
      lx = _mm_min_ps(lx, l.lx), ly = _mm_min_ps(ly, l.ly), lz = _mm_min_ps(lz, l.lz);
      hx = _mm_max_ps(hx, l.hx), hy = _mm_max_ps(hy, l.hy), hz = _mm_max_ps(hz, l.hz);
      count = _mm_add_epi32(count, l.count);
      l.leftArea = halfAreas(lx, ly, lz, hx, hy, hz);
      l.leftCount = count;
    }
    // Right to left: suffix unions, and the boundary before each position. Scanning down, `<=` keeps
    // the lowest position among equal costs: the first minimum.
    const double ci = options_.cost.intersectionCost;
    const bool unitCi = ci == 1.0, smallCounts = uint32_t(_mm_cvtsi128_si32(lanes_[m - 1].leftCount)) < 0x80000000u;  // the node's count
    __m128d best01 = _mm_set1_pd(kInf), best23 = best01;
    __m128i at01 = _mm_setzero_si128(), at23 = _mm_setzero_si128();
    if (unitCi && smallCounts)
      suffixSweep<true, true>(m, ci, best01, best23, at01, at23);
    else
      suffixSweep<false, false>(m, ci, best01, best23, at01, at23);
    alignas(16) double lowest[4];
    alignas(16) int64_t at[4];
    _mm_store_pd(lowest, best01), _mm_store_pd(lowest + 2, best23);
    _mm_store_si128(reinterpret_cast<__m128i*>(at), at01), _mm_store_si128(reinterpret_cast<__m128i*>(at + 2), at23);
    int axis = -1;
    for (int a = 0; a < 3; ++a)
      if (lowest[a] < best.cost) best.cost = lowest[a], axis = a;
    if (axis < 0) return false;
    cut = uint32_t(at[axis]);
    alignas(16) int32_t counts[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(counts), lanes_[cut].leftCount);
    best.axis = axis, best.leftCount = uint32_t(counts[axis]);
    // The children's boxes: unions of the axis's positions on either side.
    auto lane = [axis](__m128 v) {
      alignas(16) float f[4];
      _mm_store_ps(f, v);
      return f[axis];
    };
    for (int side = 0; side < 2; ++side) {
      lx = _mm_set1_ps(kInf), ly = lx, lz = lx, hx = _mm_set1_ps(-kInf), hy = hx, hz = hx;
      for (uint32_t j = side ? cut + 1 : 0; j < (side ? m : cut + 1); ++j) {
        const Lanes& l = lanes_[j];
        lx = _mm_min_ps(lx, l.lx), ly = _mm_min_ps(ly, l.ly), lz = _mm_min_ps(lz, l.lz);
        hx = _mm_max_ps(hx, l.hx), hy = _mm_max_ps(hy, l.hy), hz = _mm_max_ps(hz, l.hz);
      }
      const Box4 box{F4::set(lane(lx), lane(ly), lane(lz), 0.0f), F4::set(lane(hx), lane(hy), lane(hz), 0.0f)};
      if (side)
        best.right = box;
      else
        best.left = box;
    }
    return true;
  }

  template <bool kUnitCi, bool kSmallCounts>
  void suffixSweep(uint32_t m, double ci, __m128d& best01, __m128d& best23, __m128i& at01, __m128i& at23) {
    __m128 lx = _mm_set1_ps(kInf), ly = lx, lz = lx, hx = _mm_set1_ps(-kInf), hy = hx, hz = hx;
    __m128i count = _mm_setzero_si128();
    const __m128d ci2 = _mm_set1_pd(ci);
    auto toDouble = [](__m128i u) {  // the low two lanes, unsigned, as doubles (exactly)
      if constexpr (kSmallCounts) return _mm_cvtepi32_pd(u);
      const __m128i flipped = _mm_xor_si128(u, _mm_set1_epi32(int32_t(0x80000000u)));
      return _mm_add_pd(_mm_cvtepi32_pd(flipped), _mm_set1_pd(2147483648.0));
    };
    for (uint32_t j = m - 1; j > 0; --j) {
      const Lanes& r = lanes_[j];
      lx = _mm_min_ps(lx, r.lx), ly = _mm_min_ps(ly, r.ly), lz = _mm_min_ps(lz, r.lz);
      hx = _mm_max_ps(hx, r.hx), hy = _mm_max_ps(hy, r.hy), hz = _mm_max_ps(hz, r.hz);
      count = _mm_add_epi32(count, r.count);
      const __m128i none = _mm_or_si128(_mm_cmpeq_epi32(count, _mm_setzero_si128()), lanes_[j - 1].noCut);
      // Area 0 where the suffix is empty (no inf * 0; those lanes are no candidates anyway).
      const __m128 rightArea = _mm_andnot_ps(_mm_castsi128_ps(none), halfAreas(lx, ly, lz, hx, hy, hz));
      const Lanes& l = lanes_[j - 1];
      __m128d c01 = _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(l.leftArea), toDouble(l.leftCount)),
                               _mm_mul_pd(_mm_cvtps_pd(rightArea), toDouble(count)));
      __m128d c23 = _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(_mm_movehl_ps(l.leftArea, l.leftArea)), toDouble(_mm_unpackhi_epi64(l.leftCount, l.leftCount))),
                               _mm_mul_pd(_mm_cvtps_pd(_mm_movehl_ps(rightArea, rightArea)), toDouble(_mm_unpackhi_epi64(count, count))));
      if constexpr (!kUnitCi) c01 = _mm_mul_pd(ci2, c01), c23 = _mm_mul_pd(ci2, c23);  // 1 * c == c exactly
      const __m128d none01 = _mm_castsi128_pd(_mm_unpacklo_epi32(none, none)), none23 = _mm_castsi128_pd(_mm_unpackhi_epi32(none, none));
      const __m128d better01 = _mm_andnot_pd(none01, _mm_cmple_pd(c01, best01));
      const __m128d better23 = _mm_andnot_pd(none23, _mm_cmple_pd(c23, best23));
      const __m128i at = _mm_set1_epi64x(j - 1);
      best01 = _mm_or_pd(_mm_and_pd(better01, c01), _mm_andnot_pd(better01, best01));
      best23 = _mm_or_pd(_mm_and_pd(better23, c23), _mm_andnot_pd(better23, best23));
      at01 = _mm_or_si128(_mm_and_si128(_mm_castpd_si128(better01), at), _mm_andnot_si128(_mm_castpd_si128(better01), at01));
      at23 = _mm_or_si128(_mm_and_si128(_mm_castpd_si128(better23), at), _mm_andnot_si128(_mm_castpd_si128(better23), at23));
    }
  }

  // Half areas of the boxes in lanes (corners given per coordinate): (x y + y z) + z x, per lane.
  static __m128 halfAreas(__m128 lx, __m128 ly, __m128 lz, __m128 hx, __m128 hy, __m128 hz) {
    const __m128 ex = _mm_sub_ps(hx, lx), ey = _mm_sub_ps(hy, ly), ez = _mm_sub_ps(hz, lz);
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)), _mm_mul_ps(ez, ex));
  }
  std::array<Lanes, kMaxBins> lanes_;
#else
  // SAH over the boundaries between bins index(0), ..., index(m - 1) of `axis` (the first and the
  // last occupied, empty ones in between allowed). Replaces `best` when a boundary here costs strictly
  // less, so the first minimum over axes 0, 1, 2 and bins in order wins. Costs as the textbook sweep
  // computes them: float half areas of the unions, Ci * (A_L * N_L + A_R * N_R) in double.
  template <class Index>
  void sweep(const Bin* bins, uint32_t m, Index index, int axis, Split& best) {
    Box4 left, right;
    uint32_t leftCount = 0, rightCount = 0;
    for (uint32_t j = 0; j + 1 < m; ++j) {  // prefixes from the left, suffixes from the right
      const Bin& l = bins[index(j)];
      const Bin& r = bins[index(m - 1 - j)];
      left.grow(l.lo.xyz(), l.hi);
      right.grow(r.lo.xyz(), r.hi);
      leftCount += l.count(), rightCount += r.count();
      leftArea_[j] = left.halfArea(), rightArea_[m - 1 - j] = right.halfArea();
      leftN_[j] = leftCount, rightN_[m - 1 - j] = rightCount;
    }
    const double ci = options_.cost.intersectionCost;
    double lowest = kInf;
    uint32_t k = m;
    for (uint32_t j = 0; j + 1 < m; ++j) {
      const double cost = ci * (double(leftArea_[j]) * leftN_[j] + double(rightArea_[j + 1]) * rightN_[j + 1]);
      const bool better = cost < lowest;
      lowest = better ? cost : lowest;
      k = better ? j : k;
    }
    if (!(lowest < best.cost)) return;
    best.axis = axis, best.cost = lowest, best.bin = index(k), best.leftCount = leftN_[k];
    best.left = best.right = Box4{};
    for (uint32_t j = 0; j <= k; ++j) best.left.grow(bins[index(j)].lo.xyz(), bins[index(j)].hi);
    for (uint32_t j = k + 1; j < m; ++j) best.right.grow(bins[index(j)].lo.xyz(), bins[index(j)].hi);
  }
  std::array<Bin, kMaxBins> binsScratch_;
  std::array<float, kMaxBins> leftArea_, rightArea_;
  std::array<uint32_t, kMaxBins> leftN_, rightN_;
#endif

  // In-place partition by the stored bin on the split axis. The references in [begin, mid) that go
  // right are swapped with those in [mid, end) that go left, the first of the former (from the left)
  // with the last of the latter (from the right), as a two-sided scan pairs them; mid is known from
  // the sweep's count. Classification: one bit per reference, 16 per instruction.
  uint32_t partition(const Task& task, const Split& split) {
    const uint32_t n = task.end - task.begin, nLeft = split.leftCount;
    const uint32_t* bin = binOf_->data();
    uint64_t* left = sides_.data();  // bit k: reference begin + k goes left
    const uint32_t words = (n + 63) / 64, shift = 8 * uint32_t(split.axis);
#if defined(BVHLAB_BINNED_SSE)
    const __m128i limit = _mm_set1_epi32(int32_t(split.bin) + 1), byte = _mm_set1_epi32(255);
    const __m128i count = _mm_cvtsi32_si128(int32_t(shift));
    for (uint32_t w = 0; w < words; ++w) {
      uint64_t bits = 0;
      const uint32_t groups = std::min(16u, (n - 64 * w + 3) / 4);
      for (uint32_t j = 0; j < groups; ++j) {
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bin + 64 * w + 4 * j));
        const __m128i isLeft = _mm_cmplt_epi32(_mm_and_si128(_mm_srl_epi32(b, count), byte), limit);
        bits |= uint64_t(uint32_t(_mm_movemask_ps(_mm_castsi128_ps(isLeft)))) << (4 * j);
      }
      left[w] = bits;
    }
#else
    for (uint32_t w = 0; w < words; ++w) {
      uint64_t bits = 0;
      for (uint32_t j = 0; j < 64; ++j) bits |= uint64_t(((bin[64 * w + j] >> shift) & 255) <= split.bin) << j;
      left[w] = bits;
    }
#endif
    if (n % 64) left[words - 1] &= (uint64_t(1) << (n % 64)) - 1;  // the scratch's padding is not a reference
    return partitionBySides(task, nLeft);
  }

  // The in-place partition proper, from the sides in sides_ (bit k: reference begin + k goes left;
  // nLeft of them).
  uint32_t partitionBySides(const Task& task, uint32_t nLeft) {
    const uint32_t n = task.end - task.begin, words = (n + 63) / 64;
    const uint64_t* left = sides_.data();
    Ref* refs = refs_ + task.begin;
    if (n <= 64) {  // one word (0 < nLeft < n)
      const uint64_t low = (uint64_t(1) << nLeft) - 1;
      for (uint64_t p = ~left[0] & low, q = left[0] & ~low; p; p &= p - 1) {
        const uint32_t top = 63 - uint32_t(std::countl_zero(q));
        std::swap(refs[std::countr_zero(p)], refs[top]);
        q ^= uint64_t(1) << top;
      }
      return task.begin + nLeft;
    }
    // Misplaced: right-goers below nLeft (ascending), left-goers at or above it (descending).
    auto below = [&](uint32_t w) -> uint64_t {  // w < lowWords
      uint64_t bits = ~left[w];
      if (64 * w + 64 > nLeft) bits &= (uint64_t(1) << (nLeft - 64 * w)) - 1;
      return bits;
    };
    auto above = [&](uint32_t w) -> uint64_t {
      if (64 * w + 64 <= nLeft) return 0;
      uint64_t bits = left[w];
      if (64 * w < nLeft) bits &= ~((uint64_t(1) << (nLeft - 64 * w)) - 1);
      return bits;
    };
    const uint32_t lowWords = (nLeft + 63) / 64;
    uint32_t pw = 0, qw = words - 1;
    uint64_t p = lowWords ? below(0) : 0, q = above(qw);
    while (true) {
      while (!p && ++pw < lowWords) p = below(pw);
      if (!p) break;
      while (!q) q = above(--qw);  // as many left-goers above nLeft as right-goers below it
      const uint32_t i = 64 * pw + uint32_t(std::countr_zero(p));
      const uint32_t top = 63 - uint32_t(std::countl_zero(q));
      std::swap(refs[i], refs[64 * qw + top]);
      p &= p - 1;
      q &= ~(uint64_t(1) << top);
    }
    return task.begin + nLeft;
  }

  void centroidBounds(uint32_t begin, uint32_t end, Box4& centroids) const {
    for (uint32_t i = begin; i < end; ++i) centroids.grow(refs_[i].centroid, refs_[i].centroid);
  }

  // The n/2 smallest references by (centroid on `axis`, input index) first: a total order, so the
  // split does not depend on where equal centroids happen to sit.
  void medianSplit(const Task& task, int axis) {
    const uint32_t n = task.end - task.begin;
    Ref* const first = refs_ + task.begin;
    std::nth_element(first, first + n / 2, first + n, [axis](const Ref& a, const Ref& b) {
      const float ca = a.centroid[axis], cb = b.centroid[axis];
      return ca < cb || (ca == cb && a.id() < b.id());
    });
  }

  void bounds(uint32_t begin, uint32_t end, Box4& box, Box4& centroids) const {
    for (uint32_t i = begin; i < end; ++i) {
      box.grow(refs_[i].lo, refs_[i].hi);
      centroids.grow(refs_[i].centroid, refs_[i].centroid);
    }
  }

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

}  // namespace

Bvh buildSahBinnedBvh(const BuildInput& input, const BuildOptions& options) {
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
