// The GPU radix sort (builders/gpu/gpu_radix_sort.hpp).
#include "builders/gpu/gpu_radix_sort.hpp"

#include <utility>

namespace bvhlab::gpubuild {

GpuRadixSort::GpuRadixSort()
    : hist_("gpubuild_radix_hist.glsl"), scan_("gpubuild_radix_scan.glsl", "", {"gpubuild_workgroup_scan.glsl"}),
      scatter_("gpubuild_radix_scatter.glsl", "", {"gpubuild_workgroup_scan.glsl"}) {}

void GpuRadixSort::sort(GLuint keys, GLuint scratch, GLuint counts, uint32_t n) const {
  const uint32_t groups = blocks(n);
  GLuint from = keys, to = scratch;
  hist_.set("u_count", n);
  scatter_.set("u_count", n);
  scan_.set("u_blocks", groups);
  for (uint32_t shift = 0; shift < 64; shift += 8) {  // every pass, so the result is always in `keys`
    hist_.set("u_shift", shift);
    scatter_.set("u_shift", shift);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, from);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, counts);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, to);
    hist_.dispatch(groups, "lbvh-gpu sort: digit counts (gpubuild_radix_hist.glsl)");
    scan_.dispatch(256, "lbvh-gpu sort: scan per digit (gpubuild_radix_scan.glsl)");
    scatter_.dispatch(groups, "lbvh-gpu sort: scatter (gpubuild_radix_scatter.glsl)");
    std::swap(from, to);
  }
}

}  // namespace bvhlab::gpubuild
