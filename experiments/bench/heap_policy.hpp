// The heap policy a build-time benchmark runs under: --heap=adaptive|warm|cold.
//
// Why: a builder takes fresh arrays on every build (the node array it returns, its scratch), and on
// this machine (a VM) a 4 KiB page fault costs about 11 us, so whether those arrays arrive as fresh pages
// or as pages the heap already holds moves a build's time by far more than the differences between
// builders: the armadillo's ploc build (2 threads) took 22 ms in one process and 6 ms in another,
// same binary, same tree (the runs are in the git history of docs/builders.md). With glibc's default policy
// (adaptive) which one a build gets depends on the process's history: a freed block larger than
// the current mmap threshold raises that threshold (up to 32 MiB) and the trim threshold with it,
// so after some frees big blocks come from the heap and stay touched, and after others they are
// mmapped afresh. Two processes that run the same benchmarks in different orders end up with
// different policies. The two fixed policies take that history out:
//  - warm: no mmap for allocations and no trimming: memory a build frees stays in the heap, and the
//    next build reuses it without faults. What an application that rebuilds every frame sees;
//    measures the builder's own work.
//  - cold: the mmap threshold fixed at glibc's initial 128 KiB (no raising), the trim threshold
//    too: every block of 128 KiB or more is fresh memory, faulted in page by page (or 2 MiB at a
//    time where a builder advises huge pages). What a one-off build in a fresh process sees.
// Embree's nodes come from its own allocator, whose blocks an RTCBVH keeps from build to build, so
// the policy reaches only Embree's smaller allocations: embree-raw's faults per build on the bunny
// were 0 warm, 46 adaptive and 189 cold, against thousands for our builders cold.
#pragma once
#include <climits>
#include <optional>
#include <string_view>

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <sys/resource.h>

namespace bvhlab::bench {

enum class HeapPolicy { Adaptive, Warm, Cold };

inline std::optional<HeapPolicy> parseHeapPolicy(std::string_view name) {
  if (name == "adaptive") return HeapPolicy::Adaptive;
  if (name == "warm") return HeapPolicy::Warm;
  if (name == "cold") return HeapPolicy::Cold;
  return std::nullopt;
}

inline const char* heapPolicyName(HeapPolicy policy) {
  switch (policy) {
    case HeapPolicy::Warm: return "warm";
    case HeapPolicy::Cold: return "cold";
    default: return "adaptive";
  }
}

// Applies the policy to this process (call it before anything is timed). False when the C library
// refused it (or is not glibc, for warm and cold): the caller reports that and stops.
inline bool applyHeapPolicy(HeapPolicy policy) {
  if (policy == HeapPolicy::Adaptive) return true;
#if defined(__GLIBC__)
  constexpr int kInitialMmapThreshold = 128 * 1024;  // glibc's DEFAULT_MMAP_THRESHOLD_MIN, its start value
  if (policy == HeapPolicy::Warm)  // mallopt returns 1 on success
    return mallopt(M_MMAP_MAX, 0) == 1 && mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1;
  return mallopt(M_MMAP_THRESHOLD, kInitialMmapThreshold) == 1 && mallopt(M_TRIM_THRESHOLD, kInitialMmapThreshold) == 1;
#else
  return false;
#endif
}

// Minor page faults of this process so far, all threads (getrusage; 0 where it fails): a benchmark
// takes the difference over its timed loop and divides by the iterations, the faults per build, the
// count that explains most of a build's time moving with the heap.
inline long minorPageFaults() {
  rusage usage{};
  return getrusage(RUSAGE_SELF, &usage) == 0 ? usage.ru_minflt : 0;
}

}  // namespace bvhlab::bench
