// sah-binned's three-axis sweep: the SAH at every boundary of the three axes at once, one axis per
// SSE2 lane (the double costs of the suffix sweep in one AVX register where the CPU has AVX2, chosen
// at run time; the same operations per lane, so the same tree). Included by the files whose split
// finders use it (sah_binned_small.cpp, sah_binned_bins.cpp); nothing here on the portable path.
#pragma once
#include "builders/sah_binned.hpp"

#if defined(BVHLAB_BINNED_SSE)
#include <cstdlib>

#include <immintrin.h>
#endif

#if defined(BVHLAB_BINNED_SSE)
namespace bvhlab::binned {

template <class Gather>
bool BinnedStepper::sweepLanes(uint32_t m, Gather gather, Split& best, uint32_t& cut) {
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
  alignas(32) double lowest[4];
  alignas(32) int64_t at[4];
  // AVX2 when the CPU has it, unless BVHLAB_NO_AVX2 is set (any value): the tests run the SSE2 sweep
  // that way too (tests/CMakeLists.txt, sah_binned_sse2).
  static const bool avx2 = __builtin_cpu_supports("avx2") && !std::getenv("BVHLAB_NO_AVX2");
  if (avx2) {
    if (unitCi && smallCounts)
      suffixSweepAvx2<true, true>(m, ci, lowest, at);
    else
      suffixSweepAvx2<false, false>(m, ci, lowest, at);
  } else {
    if (unitCi && smallCounts)
      suffixSweep<true, true>(m, ci, best01, best23, at01, at23);
    else
      suffixSweep<false, false>(m, ci, best01, best23, at01, at23);
    _mm_store_pd(lowest, best01), _mm_store_pd(lowest + 2, best23);
    _mm_store_si128(reinterpret_cast<__m128i*>(at), at01), _mm_store_si128(reinterpret_cast<__m128i*>(at + 2), at23);
  }
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
void BinnedStepper::suffixSweep(uint32_t m, double ci, __m128d& best01, __m128d& best23, __m128i& at01, __m128i& at23) {
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

template <bool kUnitCi, bool kSmallCounts>
__attribute__((target("avx2"))) void BinnedStepper::suffixSweepAvx2(uint32_t m, double ci, double* lowest, int64_t* atOut) {
  __m128 lx = _mm_set1_ps(kInf), ly = lx, lz = lx, hx = _mm_set1_ps(-kInf), hy = hx, hz = hx;
  __m128i count = _mm_setzero_si128();
  const __m256d ci4 = _mm256_set1_pd(ci);
  __m256d best = _mm256_set1_pd(kInf);
  __m256i at = _mm256_setzero_si256();
  for (uint32_t j = m - 1; j > 0; --j) {
    const Lanes& r = lanes_[j];
    lx = _mm_min_ps(lx, r.lx), ly = _mm_min_ps(ly, r.ly), lz = _mm_min_ps(lz, r.lz);
    hx = _mm_max_ps(hx, r.hx), hy = _mm_max_ps(hy, r.hy), hz = _mm_max_ps(hz, r.hz);
    count = _mm_add_epi32(count, r.count);
    const __m128i none = _mm_or_si128(_mm_cmpeq_epi32(count, _mm_setzero_si128()), lanes_[j - 1].noCut);
    const __m128 rightArea = _mm_andnot_ps(_mm_castsi128_ps(none), halfAreas(lx, ly, lz, hx, hy, hz));
    const Lanes& l = lanes_[j - 1];
    __m256d leftN, rightN;  // the counts, unsigned, as doubles (exactly)
    if constexpr (kSmallCounts) {
      leftN = _mm256_cvtepi32_pd(l.leftCount), rightN = _mm256_cvtepi32_pd(count);
    } else {
      const __m128i flip = _mm_set1_epi32(int32_t(0x80000000u));
      const __m256d offset = _mm256_set1_pd(2147483648.0);
      leftN = _mm256_add_pd(_mm256_cvtepi32_pd(_mm_xor_si128(l.leftCount, flip)), offset);
      rightN = _mm256_add_pd(_mm256_cvtepi32_pd(_mm_xor_si128(count, flip)), offset);
    }
    __m256d c = _mm256_add_pd(_mm256_mul_pd(_mm256_cvtps_pd(l.leftArea), leftN), _mm256_mul_pd(_mm256_cvtps_pd(rightArea), rightN));
    if constexpr (!kUnitCi) c = _mm256_mul_pd(ci4, c);
    const __m256d none4 = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(none));  // -1 -> all ones
    const __m256d better = _mm256_andnot_pd(none4, _mm256_cmp_pd(c, best, _CMP_LE_OQ));
    best = _mm256_blendv_pd(best, c, better);
    at = _mm256_castpd_si256(_mm256_blendv_pd(_mm256_castsi256_pd(at), _mm256_castsi256_pd(_mm256_set1_epi64x(j - 1)), better));
  }
  _mm256_store_pd(lowest, best);
  _mm256_store_si256(reinterpret_cast<__m256i*>(atOut), at);
}

// Half areas of the boxes in lanes (corners given per coordinate): (x y + y z) + z x, per lane.
inline __m128 BinnedStepper::halfAreas(__m128 lx, __m128 ly, __m128 lz, __m128 hx, __m128 hy, __m128 hz) {
  const __m128 ex = _mm_sub_ps(hx, lx), ey = _mm_sub_ps(hy, ly), ez = _mm_sub_ps(hz, lz);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)), _mm_mul_ps(ez, ex));
}

}  // namespace bvhlab::binned
#endif
