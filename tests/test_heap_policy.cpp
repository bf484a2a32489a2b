// bench_builders' and ab_revisions' heap policies (experiments/bench/heap_policy.hpp): the names, and
// that warm and cold do what they say to a block freed and taken again, counted in page faults. Each
// policy is applied in a child process (EXPECT_EXIT): a policy is process-wide.
#include <cstdio>
#include <cstdlib>
#include <gtest/gtest.h>

#include "experiments/bench/heap_policy.hpp"

namespace {

using namespace bvhlab::bench;

TEST(HeapPolicy, NamesRoundTripAndOthersAreRefused) {
  for (HeapPolicy p : {HeapPolicy::Adaptive, HeapPolicy::Warm, HeapPolicy::Cold}) {
    const std::optional<HeapPolicy> parsed = parseHeapPolicy(heapPolicyName(p));
    ASSERT_TRUE(parsed.has_value()) << heapPolicyName(p);
    EXPECT_EQ(*parsed, p);
  }
  for (const char* bad : {"", "Warm", "hot", "warm ", "cold1"}) EXPECT_FALSE(parseHeapPolicy(bad).has_value()) << bad;
}

// The faults taken by touching every 4 KiB of an 8 MiB block taken right after one of the same size
// was freed (the third such round: the first rounds let glibc settle its thresholds).
long faultsOfAFreedAndRetakenBlock() {
  constexpr size_t kBytes = size_t(8) << 20, kPage = 4096;
  long faults = 0;
  for (int round = 0; round < 3; ++round) {
    auto* block = static_cast<volatile char*>(std::malloc(kBytes));
    if (!block) return -1;
    const long before = minorPageFaults();
    for (size_t i = 0; i < kBytes; i += kPage) block[i] = char(i);
    faults = minorPageFaults() - before;
    std::free(const_cast<char*>(block));
  }
  return faults;
}

#if defined(__SANITIZE_ADDRESS__)
#define BVHLAB_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BVHLAB_UNDER_ASAN 1
#endif
#endif

TEST(HeapPolicy, WarmReusesAFreedBlockAndColdFaultsItInAgain) {
#if defined(BVHLAB_UNDER_ASAN) || !defined(__GLIBC__)
  GTEST_SKIP() << "the policies set glibc's malloc; AddressSanitizer (or another C library) allocates by its own rules";
#else
  // Warm: the block comes back from the heap, already touched.
  EXPECT_EXIT(
      {
        if (!applyHeapPolicy(HeapPolicy::Warm)) std::exit(2);
        const long faults = faultsOfAFreedAndRetakenBlock();
        std::fprintf(stderr, "warm: %ld faults\n", faults);
        std::exit(faults >= 0 && faults < 16 ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "warm: [0-9]+ faults");
  // Cold: a fresh mapping every time, faulted in again (at least once per 2 MiB, even with huge pages).
  EXPECT_EXIT(
      {
        if (!applyHeapPolicy(HeapPolicy::Cold)) std::exit(2);
        const long faults = faultsOfAFreedAndRetakenBlock();
        std::fprintf(stderr, "cold: %ld faults\n", faults);
        std::exit(faults >= 4 ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "cold: [0-9]+ faults");
#endif
}

}  // namespace
