// The GL glue of the GPU builders: a compute program made from an embedded .glsl module (builders/gpu/),
// its dispatch with an error that names the pass, and the implementation limits a build must fit in.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <glad/gl.h>

namespace bvhlab::gpubuild {

// Compiles and links "#version 450" + `defines` + the embedded module `module` in the current context.
// Throws std::runtime_error naming the module and quoting the driver's log when it does not compile or
// link.
class ComputeProgram {
 public:
  // `prelude`: modules compiled ahead of `module` (functions and types it shares with other passes).
  // Each is GLSL source string 1, 2, ... in a driver's messages (`#line 1 k`), `module` string 0.
  explicit ComputeProgram(const std::string& module, const std::string& defines = "",
                          const std::vector<std::string>& prelude = {});
  ~ComputeProgram();
  ComputeProgram(const ComputeProgram&) = delete;
  ComputeProgram& operator=(const ComputeProgram&) = delete;

  GLuint id() const { return program_; }
  void use() const { glUseProgram(program_); }
  void set(const char* name, uint32_t v) const;
  void set(const char* name, int32_t v) const;
  void set(const char* name, float v) const;
  // glDispatchCompute(groups, 1, 1), then a shader-storage barrier; checkGl names `pass`.
  void dispatch(uint32_t groups, const char* pass) const;
  // glDispatchComputeIndirect(offset) from the bound GL_DISPATCH_INDIRECT_BUFFER, then the same barrier.
  void dispatchIndirect(GLintptr offset, const char* pass) const;

 private:
  GLuint program_ = 0;
  std::string module_;
};

// Every source text a ComputeProgram was made from in this process, by its label (the module, its
// defines and preludes), as the driver received it: for offline checks (tests/test_gpu_glslang.cpp runs
// glslang, the reference GLSL front end, over them).
std::map<std::string, std::string> computeSourcesMade();

// What the GL implementation allows (queried in the current context), or smaller values a test sets.
struct GpuLimits {
  uint64_t maxStorageBlockBytes = 0;  // GL_MAX_SHADER_STORAGE_BLOCK_SIZE
  uint32_t maxWorkGroupsX = 0;        // GL_MAX_COMPUTE_WORK_GROUP_COUNT, x
};
GpuLimits queryGpuLimits();

// A shader storage buffer of `bytes` (at least 4) with undefined contents, or `data` when given.
GLuint makeStorageBuffer(uint64_t bytes, const void* data = nullptr);

}  // namespace bvhlab::gpubuild
