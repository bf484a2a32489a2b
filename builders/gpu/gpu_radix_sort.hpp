// A stable LSD radix sort of Morton keys in GL buffers (gpubuild_radix_{hist,scan,scatter}.glsl, with
// gpubuild_workgroup_scan.glsl):
// 8 passes of 8-bit digits over the 64-bit code, each a per-block digit count, a scan of each digit's
// counts over the blocks (one workgroup per digit) and a stable scatter that starts each digit after
// the lower digits' totals. Equal codes keep their input order, so
// keys made in index order come out sorted by (code, index), as builders/morton_sort.hpp sorts them.
#pragma once
#include <cstdint>

#include <glad/gl.h>

#include "builders/gpu/gpu_compute.hpp"

namespace bvhlab::gpubuild {

// A key as the shaders store it (std430: 12 bytes).
struct GpuKey {
  uint32_t hi, lo, id;  // code = hi << 32 | lo
};
static_assert(sizeof(GpuKey) == 12);

class GpuRadixSort {
 public:
  static constexpr uint32_t kBlock = 4096;  // keys per workgroup (the shaders' kBlock)
  GpuRadixSort();                           // compiles its programs in the current context

  static uint32_t blocks(uint32_t n) { return (n + kBlock - 1) / kBlock; }
  // 256 counts per block, then the 256 digits' totals.
  static uint64_t countBytes(uint32_t n) { return uint64_t(256) * (blocks(n) + 1) * 4; }
  // Sorts the n keys in `keys`; `scratch` holds n keys, `counts` countBytes(n). The result is in `keys`
  // (an even number of passes). Leaves storage-buffer slots 0..2 bound to the three buffers.
  void sort(GLuint keys, GLuint scratch, GLuint counts, uint32_t n) const;

 private:
  ComputeProgram hist_, scan_, scatter_;  // gpubuild_radix_{hist,scan,scatter}.glsl
};

}  // namespace bvhlab::gpubuild
