// sah-binned's tiny nodes (2 to 32 references): the pair, the subsets of 3 or 4, and the references
// sorted by (bin, position) with a sorting network for 5..32, each giving the split the binned sweep
// over the occupied bins would give (builders/sah_binned.hpp; the overview is in sah_binned.cpp).
#include <algorithm>
#include <array>
#include <bit>

#include "builders/sah_binned.hpp"
#include "builders/sah_binned_lanes.hpp"

namespace bvhlab::binned {

namespace {

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
#if defined(BVHLAB_BINNED_SSE)  // the portable path ranks by counting instead
template <uint32_t N>
constexpr auto kSortingNetwork = makeSortingNetwork<N>();
#endif

}  // namespace

Split BinnedStepper::tinySplit(const Task& task, const BinMapping& mapping) {
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
Split BinnedStepper::subsetSplit(const Task& task, const BinMapping& mapping) {
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
Split BinnedStepper::tinySplit(const Task& task, const BinMapping& mapping) {
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
Split BinnedStepper::splitPair(const Task& task, const BinMapping& mapping) {
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

uint32_t BinnedStepper::partitionPair(const Task& task, const Split& split) {
  if (split.bin) std::swap(refs_[task.begin], refs_[task.begin + 1]);
  return task.begin + 1;
}

}  // namespace bvhlab::binned
