// sah-binned's in-place partition: the references a two-sided (Hoare) scan would swap, found from one
// bit per reference (builders/sah_binned.hpp; the overview is in sah_binned.cpp).
#include <bit>
#include <utility>

#include "builders/sah_binned.hpp"

namespace bvhlab::binned {

// In-place partition by the stored bin on the split axis. The references in [begin, mid) that go
// right are swapped with those in [mid, end) that go left, the first of the former (from the left)
// with the last of the latter (from the right), as a two-sided scan pairs them; mid is known from
// the sweep's count. Classification: one bit per reference, 16 per instruction.
uint32_t BinnedStepper::partition(const Task& task, const Split& split) {
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
uint32_t BinnedStepper::partitionBySides(const Task& task, uint32_t nLeft) {
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

}  // namespace bvhlab::binned
