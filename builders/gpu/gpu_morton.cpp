// The GPU builders' Morton phase (builders/gpu/gpu_morton.hpp).
#include "builders/gpu/gpu_morton.hpp"

#include "builders/gpu/gpu_build_steps.hpp"  // groupsFor

namespace bvhlab::gpubuild {

void MortonPasses::run(const std::string& builder, uint32_t n, MortonGrid grid, GLuint centroids, GLuint boundKeys,
                       GLuint gridBuffer, GLuint keys) const {
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, centroids);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, boundKeys);
  bounds_.set("u_count", n);
  bounds_.dispatch(groupsFor(n), (builder + " morton: centroid bounds (gpubuild_bounds.glsl)").c_str());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, boundKeys);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gridBuffer);
  grid_.set("u_cube", int32_t(grid == MortonGrid::Cube));
  grid_.dispatch(1, (builder + " morton: grid (gpubuild_grid.glsl)").c_str());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, centroids);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gridBuffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, keys);
  morton_.set("u_count", n);
  morton_.dispatch(groupsFor(n), (builder + " morton: codes (gpubuild_morton.glsl)").c_str());
}

}  // namespace bvhlab::gpubuild
