// A builder's per-build memory. Every build takes fresh arrays (references, keys, the full tree,
// clusters), and fresh memory costs a page fault per 4 KiB on first touch: about 0.25 us on bare
// metal, 11 us in this project's VM (measured: 64 MiB touched in 182 ms at 4 KiB, in 3.8 ms as 2 MiB
// transparent huge pages; the run is in the git history of docs/builders.md). So arrays of 1 MiB and more are
// taken 2 MiB-aligned, rounded up to whole 2 MiB and advised as huge-page candidates (Linux), one
// fault per 2 MiB: at 1 MiB the zeroing of one huge page costs about what 256 small faults cost on
// bare metal, and far less here. Smaller arrays come from the usual allocator.
// Where the memory is reused (a heap that keeps what the previous build freed: bench_builders'
// warm policy, experiments/bench/heap_policy.hpp) none of this costs or saves anything.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace bvhlab::detail {

constexpr size_t kHugePage = size_t(2) << 20;
constexpr size_t kHugePageMinBytes = size_t(1) << 20;  // from here on, whole huge pages (see above)

// Advises the kernel (Linux) that the 2 MiB-aligned part of [data, data + bytes) may use
// transparent huge pages. Before the memory is touched, that turns a page fault per 4 KiB into one
// per 2 MiB. Harmless elsewhere or when refused. (For memory this header did not allocate, such as
// the vectors a Bvh returns in: their ends outside the aligned part stay small pages.)
inline void adviseHugePages(void* data, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

// `bytes` (> 0) aligned to `align` (a power of two, at most 2 MiB); from kHugePageMinBytes on, whole
// advised huge pages. Freed with freeScratch (std::free). Throws std::bad_alloc.
inline void* allocateScratch(size_t bytes, size_t align) {
  const bool huge = bytes >= kHugePageMinBytes;
  align = std::max({align, alignof(std::max_align_t), huge ? kHugePage : size_t(1)});
  const size_t rounded = (bytes + align - 1) / align * align;  // aligned_alloc wants a multiple
  if (rounded < bytes) throw std::bad_alloc();
  void* data = std::aligned_alloc(align, rounded);
  if (!data) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (huge) madvise(data, rounded, MADV_HUGEPAGE);  // a hint: failure is harmless
#endif
  return data;
}
inline void freeScratch(void* data) noexcept { std::free(data); }

// The allocator of a builder's scratch: behind ScratchArray, and behind std::vector as ScratchVector
// (a builder's scratch vectors: keys, clusters' partners, entries).
template <class T>
struct ScratchAllocator {
  using value_type = T;
  ScratchAllocator() = default;
  template <class U>
  ScratchAllocator(const ScratchAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(allocateScratch(std::max<size_t>(n, 1) * sizeof(T), alignof(T)));
  }
  void deallocate(T* p, size_t) noexcept { freeScratch(p); }
  friend bool operator==(const ScratchAllocator&, const ScratchAllocator&) { return true; }
};

// An uninitialised array for a builder's per-build working set (trivial types only).
template <class T>
class ScratchArray {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>);

 public:
  explicit ScratchArray(size_t n) : data_(ScratchAllocator<T>().allocate(n)), size_(n) {}
  ScratchArray(const ScratchArray&) = delete;
  ScratchArray& operator=(const ScratchArray&) = delete;
  ~ScratchArray() { freeScratch(data_); }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }
  size_t size() const { return size_; }

 private:
  T* data_ = nullptr;
  size_t size_ = 0;
};

template <class T>
using ScratchVector = std::vector<T, ScratchAllocator<T>>;

}  // namespace bvhlab::detail
