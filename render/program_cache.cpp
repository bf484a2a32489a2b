#include "render/program_cache.hpp"

#include <glad/gl.h>

#include "render/gpu_renderer.hpp"

namespace bvhlab {

ProgramCache::~ProgramCache() {
  for (const auto& [source, program] : programs_) glDeleteProgram(program.id);
}

ProgramCache::Program ProgramCache::get(const AssembledShader& shader) {
  auto it = programs_.find(shader.source);
  if (it != programs_.end()) return it->second;
  const Program program{compileFullscreenProgram(shader), int(programs_.size())};
  programs_.emplace(shader.source, program);
  return program;
}

}  // namespace bvhlab
