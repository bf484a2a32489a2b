// The phase `morton` the GPU builders share (lbvh-gpu, ploc-gpu, plocpp-gpu, hploc-gpu): the codes of
// builders/morton.hpp without size bits, unsorted.
#pragma once
#include <cstdint>
#include <string>

#include <glad/gl.h>

#include "builders/bvh.hpp"  // MortonGrid
#include "builders/gpu/gpu_compute.hpp"

namespace bvhlab::gpubuild {

// The phase `morton` of every GPU builder: the centroids' bounds (atomics), the grid (one invocation,
// the CPU's float rounding) and the codes (gpubuild_bounds/grid/morton.glsl), from `centroids` into
// `keys` (GpuKey, unsorted); `boundKeys` starts as {~0u, ~0u, ~0u, 0, 0, 0}, `grid` holds 6 words.
// Every pass's label starts with `builder`.
class MortonPasses {
 public:
  MortonPasses() : bounds_("gpubuild_bounds.glsl"), grid_("gpubuild_grid.glsl"), morton_("gpubuild_morton.glsl") {}
  void run(const std::string& builder, uint32_t n, MortonGrid grid, GLuint centroids, GLuint boundKeys, GLuint gridBuffer,
           GLuint keys) const;

 private:
  ComputeProgram bounds_, grid_, morton_;
};

}  // namespace bvhlab::gpubuild
