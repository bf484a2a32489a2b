// sah-binned's binning: one pass drops a node's references into the bins of all three axes (and
// keeps each reference's bins for the partition); large nodes sweep every bin, smaller ones only the
// occupied bins (builders/sah_binned.hpp; the overview is in sah_binned.cpp).
#include <algorithm>
#include <bit>

#include "builders/sah_binned.hpp"
#include "builders/sah_binned_lanes.hpp"

namespace bvhlab::binned {

  // Bins the node's references first, first + stride, ... into bin set `set`, stores their bins (a
  // byte per axis, by position in the node) and, if asked, marks the occupied bins. Written so that
  // nothing is re-read after a store (the box stores go through __m128, which may alias anything).
template <bool kOccupancy>
void BinnedStepper::binRefs(const Task& task, const BinMapping& mapping, uint32_t first, uint32_t stride, int set,
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
Split BinnedStepper::findSplitLarge(const Task& task, const BinMapping& mapping) {
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
Split BinnedStepper::findSplitSmall(const Task& task, const BinMapping& mapping) {
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

#if !defined(BVHLAB_BINNED_SSE)
  // SAH over the boundaries between bins index(0), ..., index(m - 1) of `axis` (the first and the
  // last occupied, empty ones in between allowed). Replaces `best` when a boundary here costs strictly
  // less, so the first minimum over axes 0, 1, 2 and bins in order wins. Costs as the textbook sweep
  // computes them: float half areas of the unions, Ci * (A_L * N_L + A_R * N_R) in double.
template <class Index>
void BinnedStepper::sweep(const Bin* bins, uint32_t m, Index index, int axis, Split& best) {
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
#endif

}  // namespace bvhlab::binned
